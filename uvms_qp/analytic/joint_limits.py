"""Joint-limit index of Wang et al. (2017), Eq. (15)-(17) (Chan and Dubey).

``H(q) = sum_i (q_max,i - q_min,i)^2 / (C_i (q_max,i - q_i) (q_i - q_min,i))`` (dimensionless,
smallest ``4 / C_i`` per joint at mid-range, infinite at a limit) and its gradient

    dH/dq_i = (q_max - q_min)^2 (2 q_i - q_max - q_min) / (C_i (q_max - q_i)^2 (q_i - q_min)^2)

[1/rad]. With ``clearance = 0`` (the default) the formulas are exact and a joint on or outside
its limits is an error. A controller needs finite, bounded numbers everywhere, so with
``clearance > 0`` both distances ``q_max - q_i`` and ``q_i - q_min`` are clipped from below at
``eps_i = clearance (q_max,i - q_min,i)`` in both formulas: the values are exact for every joint
farther than ``eps_i`` from its limits; closer, at or beyond a limit, the distance to that limit
counts as ``eps_i`` (the gradient is then Eq. (16) with clipped distances, a saturation, not the
derivative of the clipped ``H``). It keeps the sign of ``2 q_i - q_max - q_min`` (pointing away
from the middle of the range, also outside the limits) and is bounded by
:func:`joint_limit_gradient_bound`.

One routine computes both numbers (:func:`index_and_gradient` on the per-joint constants of
:func:`limit_table`); the functions below validate their inputs and call it, and the
joint-limit task calls it every tick with constants prepared once.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import as_scalar, as_vector, check_bounds_order
from ..errors import BoundsError, InputError
from ._checks import FloatArray

#: Distance to a limit, as a fraction of the joint's range, below which the joint-limit task
#: counts the distance as exactly that much (see the module docstring).
LIMIT_CLEARANCE = 1e-2

#: Per joint ``(q_min, q_max, C, span, eps)`` as plain floats.
LimitTable = list[tuple[float, float, float, float, float]]


def limit_table(lower: FloatArray, upper: FloatArray, C: FloatArray,
                clearance: float) -> LimitTable:
    """Per-joint constants of :func:`index_and_gradient` (inputs already validated)."""
    span = upper - lower
    return list(zip(lower.tolist(), upper.tolist(), C.tolist(), span.tolist(),
                    (clearance * span).tolist(), strict=True))


def index_and_gradient(q: list[float], table: LimitTable) -> tuple[float, list[float]]:
    """``H`` and ``dH/dq`` of joint angles ``q`` [rad] (plain floats, one pass per joint).

    ``table`` comes from :func:`limit_table`; distances are clipped at its ``eps``.
    """
    H = 0.0
    grad = []
    for x, (lo, hi, c, span, eps) in zip(q, table, strict=True):
        a = max(hi - x, eps)
        b = max(x - lo, eps)
        H += span * span / (c * a * b)
        grad.append(span * span * (2.0 * x - hi - lo) / (c * a * a * b * b))
    return H, grad


def _inputs(q: Any, lower: Any, upper: Any, C: Any, clearance: Any
            ) -> tuple[list[float], LimitTable]:
    q = as_vector(q, "q")
    n = q.shape[0]
    lo = as_vector(lower, "lower", n)
    hi = as_vector(upper, "upper", n)
    check_bounds_order(lo, hi, "joint limits")
    if (hi - lo <= 0.0).any():
        raise BoundsError("joint limits: expected lower < upper for every joint")
    c = as_vector(C, "C", n) if np.ndim(C) else np.full(n, as_scalar(C, "C"))
    if not (c > 0.0).all():
        raise InputError("C: expected positive constants")
    clearance = as_scalar(clearance, "clearance", nonnegative=True)
    if clearance >= 0.5:
        raise InputError(f"clearance: expected a fraction of the range below 0.5, got {clearance}")
    if clearance == 0.0:
        inside = (q > lo) & (q < hi)
        if not inside.all():
            i = int(np.flatnonzero(~inside)[0])
            raise BoundsError(
                f"q: joint {i} at {q[i]:.6g} is not strictly inside ({lo[i]:.6g}, {hi[i]:.6g}); "
                "the joint-limit index is infinite there (give clearance > 0 to saturate it)"
            )
    return q.tolist(), limit_table(lo, hi, c, clearance)


def joint_limit_index(q: Any, lower: Any, upper: Any, C: Any = 1.0, *,
                      clearance: float = 0.0) -> float:
    """``H(q)``, Eq. (15) (see the module docstring).

    Args:
        q: (n,) joint angles [rad], strictly inside the limits when ``clearance`` is 0.
        lower: (n,) lower limits [rad].
        upper: (n,) upper limits [rad].
        C: Positive constant(s) C_i, scalar or (n,) (Wang et al., 2017: [10, 6, 10, 10, 10]).
        clearance: Fraction of each joint's range at which distances to a limit are clipped,
            in ``[0, 0.5)`` (0: exact).

    Returns:
        H (dimensionless).

    Raises:
        BoundsError: lower >= upper, or (``clearance`` 0) a joint on or outside its limits.
    """
    return index_and_gradient(*_inputs(q, lower, upper, C, clearance))[0]


def joint_limit_gradient(q: Any, lower: Any, upper: Any, C: Any = 1.0, *,
                         clearance: float = 0.0) -> FloatArray:
    """Gradient of the joint-limit index, Eq. (16) [1/rad] (arguments of :func:`joint_limit_index`).

    Returns:
        (n,) gradient; zero at mid-range, positive toward the upper limit.
    """
    return np.array(index_and_gradient(*_inputs(q, lower, upper, C, clearance))[1])


def joint_limit_weights(q: Any, lower: Any, upper: Any, C: Any = 1.0, *,
                        clearance: float = 0.0) -> FloatArray:
    """Arm inverse weights ``w_i = 1 / (1 + |dH/dq_i|)`` of Eq. (17), in (0, 1].

    One at mid-range, tending to zero at a limit (the joint is frozen by the weighted inverse).
    """
    return 1.0 / (1.0 + np.abs(joint_limit_gradient(q, lower, upper, C, clearance=clearance)))


def joint_limit_gradient_bound(lower: Any, upper: Any, C: Any = 1.0,
                               clearance: float = LIMIT_CLEARANCE) -> FloatArray:
    """Upper bound of ``|dH/dq_i|`` [1/rad] at any ``q`` with distances clipped at ``clearance``.

    ``1 / (C_i clearance^2 (q_max,i - q_min,i))``; ``H`` itself stays below
    ``1 / (C_i clearance (1 - clearance))`` per joint.
    """
    lo = as_vector(lower, "lower")
    hi = as_vector(upper, "upper", lo.shape[0])
    c = as_vector(C, "C", lo.shape[0]) if np.ndim(C) else as_scalar(C, "C", positive=True)
    clearance = as_scalar(clearance, "clearance", positive=True)
    return np.asarray(1.0 / (c * clearance * clearance * (hi - lo)), dtype=np.float64)
