"""Yoshikawa's manipulability of an arm Jacobian and its exact gradient (plain floats).

The kinematics shared by the manipulability tasks (:mod:`uvms_qp.tasks.manipulability`) and
the run probes: the measure of selected rows of the arm's twist Jacobian, its gradient over the
joints in O(n), and the rows measured by default.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from ._common import TWIST_AXES

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model

#: ``G = J_S J_S'`` counts as singular when ``sqrt(det G) < _SINGULAR max(1, max |G|)^(k / 2)``
#: (k rows): the same test for the closed forms and LAPACK.
_SINGULAR = 1e-12


def _scaled_pinv_columns(J6: FloatArray, cols: list[list[float]], sel: list[int]
                         ) -> tuple[float, list[list[float]]]:
    """``(w, columns of P6)`` with ``P6`` the rows ``sel`` of ``w (J_S^+)^T``, zero elsewhere.

    ``w = sqrt(det(J_S J_S^T))`` (or of ``J_S^T J_S``), ``J_S`` the rows ``sel`` of ``J6``
    (``cols`` are its columns as plain floats). Two or three rows of full rank (the default
    selections) take the adjugate in plain floats, ``w G^{-1} = adj(G) / w`` with
    ``G = J_S J_S^T``: LAPACK's per-call overhead exceeds the work on such tiny matrices. A
    (nearly) singular ``G`` (:data:`_SINGULAR`) and any other number of rows go through LAPACK
    (a pseudoinverse when singular).
    """
    n, k = len(cols), len(sel)
    if k == 3 and n >= 3:
        i, j, l = sel
        a = b = c = d = e = f = 0.0
        for col in cols:
            x, y, z = col[i], col[j], col[l]
            a += x * x
            b += x * y
            c += x * z
            d += y * y
            e += y * z
            f += z * z
        A0, A1, A2 = d * f - e * e, c * e - b * f, b * e - c * d
        A4, A5, A8 = a * f - c * c, b * c - a * e, a * d - b * b
        det = a * A0 + b * A1 + c * A2
        big = max(1.0, a, d, f)  # the largest entry of G (a Gram matrix: on its diagonal)
        if det > _SINGULAR * _SINGULAR * big * big * big:
            w = math.sqrt(det)
            s = 1.0 / w
            out = []
            for col in cols:
                x, y, z = col[i], col[j], col[l]
                p = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
                p[i] = (A0 * x + A1 * y + A2 * z) * s
                p[j] = (A1 * x + A4 * y + A5 * z) * s
                p[l] = (A2 * x + A5 * y + A8 * z) * s
                out.append(p)
            return w, out
    elif k == 2 and n >= 2:
        i, j = sel
        a = b = d = 0.0
        for col in cols:
            x, y = col[i], col[j]
            a += x * x
            b += x * y
            d += y * y
        det = a * d - b * b
        big = max(1.0, a, d)
        if det > _SINGULAR * _SINGULAR * big * big:
            w = math.sqrt(det)
            s = 1.0 / w
            out = []
            for col in cols:
                x, y = col[i], col[j]
                p = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
                p[i] = (d * x - b * y) * s
                p[j] = (a * y - b * x) * s
                out.append(p)
            return w, out
    Js = J6[sel]
    G = Js @ Js.T if k <= n else Js.T @ Js
    det = float(np.linalg.det(G)) if G.shape[0] > 0 else 1.0
    w = math.sqrt(det) if det > 0.0 else 0.0
    if w < _SINGULAR * max(1.0, float(np.abs(G).max(initial=0.0))) ** (0.5 * G.shape[0]):
        wP = w * np.linalg.pinv(Js).T
    elif k <= n:
        wP = w * np.linalg.solve(G, Js)
    else:
        wP = w * (Js @ np.linalg.inv(G))
    P6 = np.zeros((6, n))
    P6[sel] = wP
    return w, P6.T.tolist()


def _gradient(cols: list[list[float]], pcols: list[list[float]]) -> list[float]:
    """``grad w`` from the columns of ``J6 = [V; W]`` and of ``P6 = w (J_S^+)^T`` (plain floats).

    One forward pass builds ``c_j = v_j x P_v,j + w_j x P_w,j`` and the prefix term
    ``v_j . sum_{i<j} d_i`` (``d_i = P_v,i x w_i``), one backward pass adds the suffix term
    ``w_j . sum_{i>=j} c_i`` (:func:`manipulability_and_gradient`).
    """
    n = len(cols)
    cs: list[tuple[float, float, float]] = []
    prefix: list[float] = []
    t0 = t1 = t2 = 0.0
    for (v0, v1, v2, w0, w1, w2), (p0, p1, p2, r0, r1, r2) in zip(cols, pcols, strict=True):
        cs.append((v1 * p2 - v2 * p1 + w1 * r2 - w2 * r1,
                   v2 * p0 - v0 * p2 + w2 * r0 - w0 * r2,
                   v0 * p1 - v1 * p0 + w0 * r1 - w1 * r0))
        prefix.append(v0 * t0 + v1 * t1 + v2 * t2)
        t0 += p1 * w2 - p2 * w1
        t1 += p2 * w0 - p0 * w2
        t2 += p0 * w1 - p1 * w0
    grad = [0.0] * n
    s0 = s1 = s2 = 0.0
    for i in range(n - 1, -1, -1):
        c0, c1, c2 = cs[i]
        s0 += c0
        s1 += c1
        s2 += c2
        col = cols[i]
        grad[i] = (col[3] * s0 + col[4] * s1 + col[5] * s2) + prefix[i]
    return grad


def manipulability_and_gradient(J6: FloatArray, rows: Any = None) -> tuple[float, FloatArray]:
    r"""Yoshikawa's measure of a serial arm Jacobian and its exact gradient over the joints.

    ``w = sqrt(det(J_S J_S^T))`` (``sqrt(det(J_S^T J_S))`` when ``J_S`` has more rows than columns),
    Soylu et al. (2007), Eq. (18), with ``J_S`` the selected rows of the twist Jacobian
    ``J6 = [V; W]`` (6, n) of the arm (columns in chain order, revolute or prismatic joints, any
    fixed reference frame). Its gradient (Eq. (19)) is
    ``dw/dq_i = w trace(dJ_S/dq_i J_S^+)``, evaluated with the exact column derivatives of a
    serial-chain geometric Jacobian:

        dJ_j/dq_i = [w_i x v_j; w_i x w_j]  (i <= j),     [w_j x v_i; 0]  (i > j),

    which turn the trace into ``dw/dq_i = w (w_i . sum_{j>=i} c_j + v_i . sum_{j<i} d_j)`` with
    ``c_j = v_j x P_v,j + w_j x P_w,j``, ``d_j = P_v,j x w_j`` and ``P = (J_S^+)^T`` padded to six
    rows: O(n) work, no Hessian tensor. Units: ``w`` in the product of the row units (e.g. m^3
    for 3 position rows); gradient in those units per rad.

    The sums run in plain floats: for the handful of joints of an arm this is cheaper than
    array operations (a vectorised form with an outer product and triangular sums was measured
    at about twice the time for 4 joints).

    Args:
        J6: Twist Jacobian (6, n) of the frame, linear rows first.
        rows: Indices of the rows of ``J6`` to use (any sequence of ints or an index array;
            default: the 3 linear rows).

    Returns:
        ``(w, grad)`` with ``grad`` a new array of shape (n,).
    """
    w, grad = measure(J6, rows)
    return w, np.array(grad)


def measure(J6: FloatArray, rows: Any) -> tuple[float, list[float]]:
    """:func:`manipulability_and_gradient` with the gradient as plain floats."""
    cols = J6.T.tolist()
    if rows is None:
        sel = [0, 1, 2]
    elif isinstance(rows, np.ndarray):
        sel = [int(r) for r in rows.reshape(-1).tolist()]
    else:  # any sequence of ints (a tuple would index J6 as (row, column))
        sel = [int(r) for r in rows]
    w, pcols = _scaled_pinv_columns(J6, cols, sel)
    return w, _gradient(cols, pcols)


def default_axes(model: Model) -> list[str]:
    """Twist rows measured by default: ``x, y`` for planar vehicles, else ``x, y, z``.

    A planar model's arm moves in the horizontal plane, so its ``z`` row is zero and the measure
    of the three position rows would always be 0.
    """
    return ["x", "y"] if model.vehicle_kind == "planar" else ["x", "y", "z"]


def default_rows(model: Model) -> list[int]:
    """Indices into the twist ``[v; w]`` of :func:`default_axes`."""
    return [TWIST_AXES.index(a) for a in default_axes(model)]
