"""Joint-limit index of ``003_229789978cc4b235.txt, Eq. (15)-(17)`` (Chan and Dubey)."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import as_vector, check_bounds_order
from ..errors import BoundsError, InputError
from ._checks import FloatArray


def _inputs(
    q: Any, lower: Any, upper: Any, C: Any
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    q = as_vector(q, "q")
    n = q.shape[0]
    lo = as_vector(lower, "lower", n)
    hi = as_vector(upper, "upper", n)
    check_bounds_order(lo, hi, "joint limits")
    if (hi - lo <= 0.0).any():
        raise BoundsError("joint limits: expected lower < upper for every joint")
    c = as_vector(
        np.broadcast_to(np.asarray(C, dtype=np.float64), (n,)) if np.ndim(C) == 0 else C, "C", n
    )
    if not (c > 0.0).all():
        raise InputError("C: expected positive constants")
    inside = (q > lo) & (q < hi)
    if not inside.all():
        i = int(np.flatnonzero(~inside)[0])
        raise BoundsError(
            f"q: joint {i} at {q[i]:.6g} is not strictly inside ({lo[i]:.6g}, {hi[i]:.6g}); "
            "the joint-limit index is infinite there"
        )
    return q, lo, hi, c


def joint_limit_index(q: Any, lower: Any, upper: Any, C: Any = 1.0) -> float:
    """``H(q) = sum_i (q_max - q_min)^2 / (C_i (q_max - q_i)(q_i - q_min))``, Eq. (15).

    Smallest (``4 / C_i`` per joint) at mid-range, infinite at a limit.

    Args:
        q: (n,) joint angles [rad], strictly inside the limits.
        lower: (n,) lower limits [rad].
        upper: (n,) upper limits [rad].
        C: Positive constant(s) C_i, scalar or (n,) (paper 003: [10, 6, 10, 10, 10]).

    Returns:
        H (dimensionless).

    Raises:
        BoundsError: a joint on or outside its limits, or lower >= upper.
    """
    q, lo, hi, c = _inputs(q, lower, upper, C)
    return float(np.sum((hi - lo) ** 2 / (c * (hi - q) * (q - lo))))


def joint_limit_gradient(q: Any, lower: Any, upper: Any, C: Any = 1.0) -> FloatArray:
    """Gradient of the joint-limit index, Eq. (16) [1/rad].

    ``dH/dq_i = (q_max - q_min)^2 (2 q_i - q_max - q_min) / (C_i (q_max - q_i)^2 (q_i - q_min)^2)``.

    Returns:
        (n,) gradient; zero at mid-range, positive toward the upper limit.
    """
    q, lo, hi, c = _inputs(q, lower, upper, C)
    return (hi - lo) ** 2 * (2.0 * q - hi - lo) / (c * (hi - q) ** 2 * (q - lo) ** 2)


def joint_limit_weights(q: Any, lower: Any, upper: Any, C: Any = 1.0) -> FloatArray:
    """Arm inverse weights ``w_i = 1 / (1 + |dH/dq_i|)`` of Eq. (17), in (0, 1].

    One at mid-range, tending to zero at a limit (the joint is frozen by the weighted inverse).
    """
    return 1.0 / (1.0 + np.abs(joint_limit_gradient(q, lower, upper, C)))
