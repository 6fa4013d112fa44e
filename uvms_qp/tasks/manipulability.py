"""Manipulability of the arm (Yoshikawa's measure) as an objective, a floor or a shaped task."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_scalar
from ..analytic.manipulability import shaping_function
from ..errors import InputError
from ._common import TWIST_AXES, check_choice, check_frame, parse_axes
from .task import Task, check_barrier_gain

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


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
    w, grad = _measure(J6, rows)
    return w, np.array(grad)


def _measure(J6: FloatArray, rows: Any) -> tuple[float, list[float]]:
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


class ManipulabilityTask(Task):
    r"""Keep the arm dexterous using Yoshikawa's manipulability ``w`` of the arm Jacobian.

    ``w = sqrt(det(J_S J_S^T))`` of the selected rows ``S`` of the arm's Jacobian of ``frame`` in
    the arm-base axes (joint columns only; Soylu et al. (2007), Eq. (18); in that paper
    the measure of the collective Jacobian ``[J_p; J_s]`` reduces to this one since ``J_s``
    selects the vehicle coordinates). ``grad w`` (Eq. (19)) is exact (see
    :func:`manipulability_and_gradient`). Modes:

    * ``"ascend"``: rows ``qdot = lambda grad w`` over the arm joint rates (n_joints rows,
      [rad/s]): the gradient-projection objective of Eq. (4) with ``h = w`` (in a hierarchy the
      level below the tracking task reproduces Eq. (4)).
    * ``"floor"``: one inequality row ``grad w . qdot >= gain (minimum - w)`` ([w]/s), the
      first-order barrier that keeps ``w >= minimum``: with ``gain = 1/dt`` it is exactly
      ``w + dt grad w . qdot >= minimum``; a smaller gain approaches the floor gradually.
      Below the floor, the demand is capped at ``gain |grad w|^2 / w``: near a maximum of
      ``w`` (a floor the arm cannot reach) the gradient vanishes and the uncapped row would
      ask for ``gain (minimum - w) / |grad w|`` rad/s, which the box clips and which crosses
      the maximum in one period, so that the command would bang between its bounds. With the
      cap the joints move at most ``gain dt |grad w| / w <= |grad w| / w`` rad per period
      along the gradient, about the distance to the maximum (where ``w`` has a curvature of
      about ``w`` per rad^2, exactly so for a product of sines such as a planar 2R arm's
      ``l1 l2 |sin q2|``): ``w`` rises to its maximum without crossing it (the damping
      criterion of :mod:`uvms_qp.hqp.damping` for a single row, in relative units of ``w``).
    * ``"shaping"``: rows ``qdot = k(w) (1 - sign(w_dot)) / 2 lambda grad w`` (Eq. (21)):
      :func:`~uvms_qp.analytic.shaping_function` ``k`` with the threshold ``rho_bar``, and the
      sign switch that only intervenes while ``w`` is not increasing (``sign(w_dot) = -1`` for
      ``w_dot <= 0``); ``w_dot`` is the finite difference of ``w`` between evaluations (0 at
      the first one). Place it in the same level as a
      ``StationKeepingTask(blend=<this task's name>)``, whose demand is then scaled by
      ``1 - k``: the level asks
      ``[vehicle: (1 - k) K_s e_s; arm: k s lambda grad w]``, the secondary term of Eq. (21).

    Args:
        mode: ``"ascend"``, ``"floor"`` or ``"shaping"``.
        frame: Frame whose arm Jacobian is measured (default ``"tool"``).
        axes: Rows of the twist used, from ``x, y, z, rx, ry, rz`` (default ``x, y, z``; planar
            models ``x, y``).
        gain: ``lambda`` [rad/s per unit of w] for ascend/shaping; the barrier gain [1/s] for floor.
        minimum: Floor value of ``w`` (mode ``"floor"``).
        threshold: ``rho_bar`` of the shaping function (mode ``"shaping"``).
        weight: Weight within the level.
        name: Task name (default ``"manipulability"``).
        activation: Initial activation in [0, 1] (1: in the stack; see
            :class:`~uvms_qp.tasks.Task`).
    """

    type_name = "manipulability"
    error_unit = "m^k"
    rate_unit = "rad/s | m^k/s"

    def __init__(
        self,
        *,
        mode: Literal["ascend", "floor", "shaping"] = "floor",
        frame: str = "tool",
        axes: list[str] | None = None,
        gain: float = 1.0,
        minimum: float | None = None,
        threshold: float | None = None,
        weight: float = 1.0,
        name: str | None = None,
        activation: float = 1.0,
    ) -> None:
        super().__init__(name=name, weight=weight, activation=activation)
        check_choice(mode, ("ascend", "floor", "shaping"), f"{self.name}.mode")
        if not isinstance(frame, str) or not frame:
            raise InputError(f"{self.name}.frame: expected a frame name, got {frame!r}")
        self.mode = mode
        self.frame = frame
        self._axes_arg = None if axes is None else parse_axes(axes, TWIST_AXES,
                                                              f"{self.name}.axes")
        self.gain = as_scalar(gain, f"{self.name}.gain", positive=True)
        self.minimum = None if minimum is None else as_scalar(minimum, f"{self.name}.minimum",
                                                              nonnegative=True)
        self.threshold = None if threshold is None else as_scalar(
            threshold, f"{self.name}.threshold", positive=True)
        if mode == "floor" and self.minimum is None:
            raise InputError(f"{self.name}.minimum: required in mode 'floor'")
        if mode == "shaping" and self.threshold is None:
            raise InputError(f"{self.name}.threshold: required in mode 'shaping'")
        self.axes: list[str] = []
        self._rows: list[int] | None = None
        self._select = np.zeros((0, 0))
        self._zeros: list[float] = []  # vehicle columns of the floor row
        self._nvh = 0
        self._prev: tuple[float, float] | None = None
        self._w_dot = 0.0
        self.value = float("nan")
        self.shaping = 0.0
        self._memo_serial = -1  # the state whose (w, grad w) is in _memo
        self._memo: tuple[float, list[float]] = (float("nan"), [])

    @property
    def equality_rows(self) -> bool:
        """False in mode ``'floor'`` (an inequality), True otherwise."""
        return self.mode != "floor"

    def check_period(self, dt: float) -> None:
        """In mode ``"floor"``, refuse ``gain * dt > 1`` (see :func:`.check_barrier_gain`)."""
        if self.mode == "floor":
            check_barrier_gain(self.gain, dt, f"{self.name}.gain", "floor row")

    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        if model.n_joints == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        axes = self._axes_arg if self._axes_arg is not None else default_axes(model)
        self.axes = list(axes)
        rows = [TWIST_AXES.index(a) for a in axes]
        self._rows = None if rows == [0, 1, 2] else rows
        self._nvh = model.n_vehicle
        k = sum(a in ("x", "y", "z") for a in axes)  # linear rows: [m] each, angular: [1]
        self.error_unit = "1" if k == 0 else "m" if k == 1 else f"m^{k}"
        self.rate_unit = f"{self.error_unit}/s" if self.mode == "floor" else "rad/s"
        n = model.n_joints
        self._select = np.zeros((n, model.nv))  # rows of ascend/shaping: qdot = ...
        self._select[np.arange(n), model.n_vehicle + np.arange(n)] = 1.0
        self._select.setflags(write=False)
        self._zeros = [0.0] * model.n_vehicle
        self._memo_serial = -1
        return 1 if self.mode == "floor" else n

    def _reset(self) -> None:
        """Forget the previous value used for ``w_dot``."""
        self._prev = None
        self._w_dot = 0.0

    def compute_value(self, state: State) -> tuple[float, FloatArray]:
        """``(w, grad w)`` at ``state`` (gradient over the arm joints, (n_joints,))."""
        w, grad = self._value(state)
        return w, np.array(grad)

    def _value(self, state: State) -> tuple[float, list[float]]:
        """``(w, grad w)`` in plain floats, computed once per state.

        A task linked to this one (a blended :class:`StationKeepingTask`) reads the same
        numbers in the same tick.
        """
        if self._memo_serial != state.serial:
            self._memo = _measure(state.arm_jacobian(self.frame), self._rows)
            self._memo_serial = state.serial
        return self._memo

    def shaping_factor(self, state: State) -> float:
        """``k(w)`` of :func:`~uvms_qp.analytic.shaping_function` at ``state``."""
        k: float = shaping_function(self._value(state)[0], self.threshold)  # type: ignore[arg-type]
        return k

    def evaluate(self, state: State, t: float) -> tuple[FloatArray, Any, Any]:
        """The rows of the selected mode (see the class docstring)."""
        w, g = self._value(state)
        self.value = w
        self._error = (w,)
        if self.mode == "floor":
            short = self.minimum - w  # type: ignore[operator]
            if short > 0.0 and w > 0.0:
                # near a maximum of w (an unreachable floor) the gradient vanishes: ask at most
                # what a step of |grad w| / w [rad] along it gives (class docstring)
                reach = math.fsum(v * v for v in g) / w
                if reach < short:
                    short = reach
            return np.array([self._zeros + g]), self.gain * short, np.inf
        scale = self.gain
        if self.mode == "shaping":
            if self._prev is not None and t > self._prev[0]:
                self._w_dot = (w - self._prev[1]) / (t - self._prev[0])
            self._prev = (t, w)
            switch = 0.0 if self._w_dot > 0.0 else 1.0
            self.shaping = shaping_function(w, self.threshold)  # type: ignore[arg-type]
            scale *= self.shaping * switch
        sides = [scale * x for x in g]
        return self._select, sides, sides

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain", "minimum", "threshold")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "gain":
            self.gain = as_scalar(value, f"{self.name}.gain", positive=True)
        elif key == "minimum":
            self.minimum = as_scalar(value, f"{self.name}.minimum", nonnegative=True)
        elif key == "threshold":
            self.threshold = as_scalar(value, f"{self.name}.threshold", positive=True)
        else:
            super()._apply_update(key, value)
