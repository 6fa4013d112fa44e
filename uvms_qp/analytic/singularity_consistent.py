"""Singularity-consistent (SC) method of Nenchev and Tsumaki.

The end-effector path ``x(p)`` with unit tangent ``S`` closes the arm into one loop,
``H dq_bar = 0`` with the column-augmented Jacobian ``H = [J, -S]`` and ``q_bar = (q, p)``
(Section 2.1, Eq. 1). A kernel vector is built from signed minors, not from a pseudoinverse, so it
stays smooth through kinematic singularities (where the path rate ``dp`` simply goes to zero).

For the 4-DOF positioning arm of Section 3 (PA-10-like, zero offsets, links d3 and d5) the kernel
of the 3 x 5 matrix H is two-dimensional and is spanned by the self-motion field ``f_sm``
(``f_sm4 = f_sm5 = 0``) and the end-point field ``f_ep`` (``f_ep3 = 0``, ``f_ep5 = sin q4``),
blended by Eq. (3): ``dq_bar = b_sm f_sm + b_ep f_ep``.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import InputError, ShapeError
from ._checks import FloatArray, jacobian

Scale = Literal["paper", "minors"]


def column_augmented_jacobian(J: Any, direction: Any) -> FloatArray:
    """Column-augmented Jacobian ``H = [J, -S]`` with ``S = direction / ||direction||``.

    Nenchev and Tsumaki, Section 2.1, step 2 (and Section 3 with ``S = v_hat``).

    Args:
        J: (m, n) Jacobian.
        direction: (m,) non-zero path tangent (normalised here).

    Returns:
        (m, n + 1) matrix.
    """
    J = jacobian(J, "J")
    d = as_vector(direction, "direction", J.shape[0])
    norm = float(np.linalg.norm(d))
    if norm == 0.0:
        raise InputError("direction: expected a non-zero vector")
    return np.hstack([J, -(d / norm)[:, None]])


def signed_minor_null_vector(H: Any) -> FloatArray:
    """Kernel vector ``f_i = (-1)^(i+1) det H_i`` of an (m, m + 1) matrix.

    Nenchev and Tsumaki, Section 2.1, step 3: ``H_i`` is H without its i-th column
    (1-based). ``H f = 0`` holds identically (each row of ``H f`` is a determinant with a repeated
    row); f vanishes only where H loses rank, and it is a polynomial in H's entries, so it varies
    smoothly through singularities. Its norm is the product of H's singular values.

    Args:
        H: (m, m + 1) matrix.

    Returns:
        (m + 1,) kernel vector.
    """
    H = jacobian(H, "H")
    m, cols = H.shape
    if cols != m + 1:
        raise ShapeError(f"H: expected shape (m, m + 1), got {H.shape}")
    return _signed_minors(H)


def _signed_minors(H: FloatArray) -> FloatArray:
    f = np.empty(H.shape[1])
    with np.errstate(divide="ignore", invalid="ignore"):  # LU of an exactly singular minor
        for i in range(H.shape[1]):
            f[i] = (-1.0) ** i * np.linalg.det(np.delete(H, i, axis=1))
    return f


def sc_vector_field(J: Any, direction: Any) -> FloatArray:
    """SC vector field of a non-redundant arm: signed minors of ``[J, -S]``.

    Nenchev and Tsumaki, Section 2.1. The first n entries are joint rates per unit
    parameter, the last is the path rate ``dp``; its last entry is ``(-1)^n det J``, so at a
    kinematic singularity the end point stops while the joints keep moving.

    Args:
        J: (n, n) Jacobian.
        direction: (n,) path tangent.

    Returns:
        (n + 1,) field ``f_bar``.
    """
    J = jacobian(J, "J")
    if J.shape[0] != J.shape[1]:
        raise ShapeError(f"J: expected a square Jacobian, got shape {J.shape}")
    return signed_minor_null_vector(column_augmented_jacobian(J, direction))


def _q4(q: Any) -> FloatArray:
    return as_vector(q, "q", 4)


def _links(d3: float, d5: float) -> tuple[float, float]:
    return as_scalar(d3, "d3", positive=True), as_scalar(d5, "d5", positive=True)


def sc_arm_position(q: Any, d3: float = 1.0, d5: float = 1.0) -> FloatArray:
    """Wrist-centre position of the 4-DOF positioning arm [m].

    Nenchev and Tsumaki, Section 3, Fig. 1: shoulder at the origin, joint 1 about +Z,
    links d3 (upper arm) and d5 (forearm). Reconstructed by integrating the printed Jacobian;
    ``q = 0`` points the arm up (0, 0, d3 + d5), ``q = (0, 0, 0, -90 deg)`` gives (d5, 0, d3), the
    paper's initial point (1, 0, 1) m.

    Args:
        q: (4,) joint angles [rad].
        d3: Upper-arm length [m] (paper: 1).
        d5: Forearm length [m] (paper: 1).

    Returns:
        (3,) position [m].
    """
    c1, c2, c3, c4 = np.cos(_q4(q))
    s1, s2, s3, s4 = np.sin(_q4(q))
    d3, d5 = _links(d3, d5)
    return np.array(
        [
            -d3 * c1 * s2 + d5 * (-c1 * s2 * c4 + (s1 * s3 - c1 * c2 * c3) * s4),
            -d3 * s1 * s2 - d5 * (s1 * s2 * c4 + (c1 * s3 + s1 * c2 * c3) * s4),
            d3 * c2 + d5 * (c2 * c4 - c3 * s2 * s4),
        ]
    )


def sc_arm_jacobian(q: Any, d3: float = 1.0, d5: float = 1.0) -> FloatArray:
    """Position Jacobian ``j_ij`` of the 4-DOF positioning arm (Nenchev and Tsumaki, Section 3).

    The printed ``j11`` lacks a factor ``S1`` in its first d5 term (``C4 S2`` should read
    ``C4 S1 S2``: at ``q1 = 0``, ``dx/dq1 = -y = d5 S3 S4``); this is the corrected entry. All other
    entries are as printed and equal the derivative of :func:`sc_arm_position`.

    Returns:
        (3, 4) Jacobian [m/rad].
    """
    c1, c2, c3, c4 = np.cos(_q4(q))
    s1, s2, s3, s4 = np.sin(_q4(q))
    d3, d5 = _links(d3, d5)
    return np.array(
        [
            [
                d3 * s1 * s2 + d5 * (c4 * s1 * s2 + (c2 * c3 * s1 + c1 * s3) * s4),
                -d3 * c1 * c2 + d5 * (c1 * c3 * s2 * s4 - c1 * c2 * c4),
                d5 * (c3 * s1 + c1 * c2 * s3) * s4,
                d5 * (c4 * (s1 * s3 - c1 * c2 * c3) + c1 * s2 * s4),
            ],
            [
                -d3 * c1 * s2 + d5 * ((s1 * s3 - c1 * c2 * c3) * s4 - c1 * c4 * s2),
                -d3 * c2 * s1 - d5 * (c2 * c4 * s1 - c3 * s1 * s2 * s4),
                -d5 * (c1 * c3 - c2 * s1 * s3) * s4,
                -d5 * (c4 * (c2 * c3 * s1 + c1 * s3) - s1 * s2 * s4),
            ],
            [
                0.0,
                -d3 * s2 - d5 * (c4 * s2 + c2 * c3 * s4),
                d5 * s2 * s3 * s4,
                -d5 * (c3 * c4 * s2 + c2 * s4),
            ],
        ]
    )


def shoulder_term(q: Any, d3: float = 1.0, d5: float = 1.0) -> float:
    """The term ``c = (d3 + d5 C4) S2 + d5 C2 C3 S4`` of Nenchev and Tsumaki, Section 3 [m].

    It vanishes at the shoulder singularity (wrist centre on the Z axis) and divides the first two
    components of the paper-scaled fields.
    """
    _, c2, c3, c4 = np.cos(_q4(q))
    _, s2, _, s4 = np.sin(_q4(q))
    d3, d5 = _links(d3, d5)
    return float((d3 + d5 * c4) * s2 + d5 * c2 * c3 * s4)


def _scale_factor(q: Any, d3: float, d5: float, scale: Scale) -> float:
    if scale == "minors":
        return 1.0
    if scale != "paper":
        raise InputError(f"scale: expected 'paper' or 'minors', got {scale!r}")
    c = shoulder_term(q, d3, d5)
    if abs(c) < 1e-12:
        raise InputError(
            "the paper-scaled SC fields are undefined at the shoulder singularity (c = 0); "
            "use scale='minors' (b proportional to c, footnote 2)"
        )
    return 1.0 / (d3 * d5 * c)


def self_motion_field(
    q: Any, d3: float = 1.0, d5: float = 1.0, scale: Scale = "paper"
) -> FloatArray:
    """Self-motion field ``f_sm`` of the 4-DOF arm (Nenchev and Tsumaki, Section 3).

    Computed as the signed minors of the 3 x 4 Jacobian (the last minor, ``det J[:, :3]``, is
    identically zero because joints 1-3 meet at the shoulder), padded with ``dp = 0``. With
    ``scale="paper"`` it is divided by ``d3 d5 c`` to give the printed closed form
    ``(-d5 C3 S4^2 / c, d5 S2 S3 S4^2 / c, S4, 0, 0)``; ``scale="minors"`` keeps the polynomial
    form (``d3 d5 c`` times the paper's), finite at the shoulder singularity.

    Args:
        q: (4,) joint angles [rad].
        d3: Upper-arm length [m].
        d5: Forearm length [m].
        scale: ``"paper"`` or ``"minors"``.

    Returns:
        (5,) field over ``(q1, q2, q3, q4, p)``; ``J f[:4] = 0``.
    """
    d3, d5 = _links(d3, d5)
    factor = _scale_factor(q, d3, d5, scale)
    return factor * _self_motion(sc_arm_jacobian(q, d3, d5))


def _self_motion(J: FloatArray) -> FloatArray:
    f = np.zeros(5)
    f[:4] = _signed_minors(J)
    f[3] = 0.0  # det J[:, :3] == 0 identically; drop round-off
    return f


def _end_point(J: FloatArray, direction: Any) -> FloatArray:
    H = column_augmented_jacobian(J, direction)
    return np.insert(-_signed_minors(np.delete(H, 2, axis=1)), 2, 0.0)


def end_point_field(
    q: Any,
    direction: Any,
    d3: float = 1.0,
    d5: float = 1.0,
    scale: Scale = "paper",
) -> FloatArray:
    """End-point field ``f_ep`` of the 4-DOF arm (Nenchev and Tsumaki, Section 3).

    The kernel vector of ``H = [J, -v_hat]`` with no joint-3 rate: the signed minors of H without
    its third column, with a zero inserted at position 3. With ``scale="paper"`` it is divided by
    ``-d3 d5 c`` so that ``f_ep5 = S4`` as printed; ``scale="minors"`` multiplies that by
    ``d3 d5 c`` (finite at the shoulder singularity; footnote 2's ``b_ep`` proportional to c).

    Args:
        q: (4,) joint angles [rad].
        direction: (3,) desired wrist-centre direction ``v_hat`` (normalised here).
        d3: Upper-arm length [m].
        d5: Forearm length [m].
        scale: ``"paper"`` or ``"minors"``.

    Returns:
        (5,) field over ``(q1, q2, q3, q4, p)``; ``J f[:4] = v_hat f[4]``.
    """
    d3, d5 = _links(d3, d5)
    factor = _scale_factor(q, d3, d5, scale)
    return factor * _end_point(sc_arm_jacobian(q, d3, d5), direction)


def sc_blend(
    q: Any,
    direction: Any,
    b_sm: float,
    b_ep: float,
    d3: float = 1.0,
    d5: float = 1.0,
    scale: Scale = "paper",
) -> FloatArray:
    """Blended SC motion ``dq_bar = b_sm f_sm + b_ep f_ep`` (Nenchev and Tsumaki, Eq. (3)).

    Args:
        q: (4,) joint angles [rad].
        direction: (3,) path direction ``v_hat``.
        b_sm: Self-motion speed (paper: 0 in run 1, 1 in run 2).
        b_ep: End-point speed (paper: 1).
        d3: Upper-arm length [m].
        d5: Forearm length [m].
        scale: ``"paper"`` or ``"minors"``.

    Returns:
        (5,) ``(dq1, dq2, dq3, dq4, dp)`` per unit time when the b's are rates.
    """
    b_sm = as_scalar(b_sm, "b_sm")
    b_ep = as_scalar(b_ep, "b_ep")
    d3, d5 = _links(d3, d5)
    factor = _scale_factor(q, d3, d5, scale)
    J = sc_arm_jacobian(q, d3, d5)
    out = b_ep * _end_point(J, direction)
    if b_sm != 0.0:
        out = out + b_sm * _self_motion(J)
    return factor * out


def singularity_crossings(
    joints: Any,
    times: Any,
    d3: float = 1.0,
    d5: float = 1.0,
    shoulder_tolerance: float = 0.01,
) -> list[tuple[float, str]]:
    """Times at which a joint history of the 4-DOF arm passes through its singularities.

    Nenchev and Tsumaki, Section 3, name two kinds: the extended/folded arm (``q4 = 0`` or
    ``+/-pi``: ``sin q4`` changes sign; ``"extended"`` when ``cos q4 > 0``, else ``"folded"``) and
    the shoulder singularity (the wrist centre on the Z axis: the term ``c`` of
    :func:`shoulder_term` changes sign there, and the crossing counts when the wrist passes within
    ``shoulder_tolerance`` of the axis, so a sign change of ``c`` away from the axis is not
    reported). Crossing times are interpolated linearly between samples.

    Args:
        joints: (N, 4) joint angles [rad], one row per sample.
        times: (N,) sample times [s], increasing.
        d3: Upper-arm length [m].
        d5: Forearm length [m].
        shoulder_tolerance: Largest wrist distance from the Z axis at a shoulder crossing [m].

    Returns:
        ``[(t, kind), ...]`` in time order, kind ``"extended"``, ``"folded"`` or ``"shoulder"``.

    Raises:
        ShapeError: ``joints`` is not (N, 4) or ``times`` is not (N,).
    """
    q = np.asarray(joints, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != 4 or t.shape != (q.shape[0],):
        raise ShapeError(
            f"joints, times: expected shapes (N, 4) and (N,), got {q.shape} and {t.shape}"
        )
    d3, d5 = _links(d3, d5)
    tol = as_scalar(shoulder_tolerance, "shoulder_tolerance", positive=True)
    s4 = np.sin(q[:, 3])
    c = np.array([shoulder_term(row, d3, d5) for row in q])
    events: list[tuple[float, str]] = []
    for i, j in _sign_changes(s4):
        kind = "extended" if np.cos(q[i, 3]) > 0.0 else "folded"
        events.append((_zero_time(t, s4, i, j), kind))
    for i, j in _sign_changes(c):
        radius = min(float(np.hypot(*sc_arm_position(q[k], d3, d5)[:2])) for k in range(i, j + 1))
        if radius <= tol:
            events.append((_zero_time(t, c, i, j), "shoulder"))
    return sorted(events)


def _sign_changes(values: FloatArray) -> list[tuple[int, int]]:
    """Pairs ``(i, j)`` of consecutive non-zero samples of opposite sign (zeros in between)."""
    nonzero = np.flatnonzero(values != 0.0)
    signs = np.sign(values[nonzero])
    flips = np.flatnonzero(signs[:-1] != signs[1:])
    return [(int(nonzero[f]), int(nonzero[f + 1])) for f in flips]


def _zero_time(t: FloatArray, values: FloatArray, i: int, j: int) -> float:
    """Time of the zero of ``values`` between samples ``i < j``.

    The first exact zero sample between them, else linear interpolation between the two.
    """
    if j > i + 1:
        return float(t[i + 1])
    a, b = float(values[i]), float(values[j])
    return float(t[i] + (t[j] - t[i]) * a / (a - b))
