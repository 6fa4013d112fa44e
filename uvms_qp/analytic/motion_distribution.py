"""Motion distribution between vehicle and arm (Wang et al. (2017), Eq. (14))."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import InputError
from ._checks import FloatArray


def motion_distribution(
    beta: float,
    n_vehicle: int,
    n_joints: int,
    w_max: float = 0.02,
    joint_weights: Any = None,
) -> FloatArray:
    """Diagonal of the inverse weight matrix ``w^{-1}`` of Eq. (14).

    ``w^{-1} = diag((1 - beta) w_max I_vehicle, beta I_arm)``: beta = 1 uses the arm only,
    beta = 0 the vehicle only. Pass the result as ``inverse_weights`` to the weighted schemes.
    Wang et al. (2017) write ``I_{6x6}``; their vehicle actuates 4 DOFs, so the block has
    ``n_vehicle`` entries. The optional ``joint_weights`` (Eq. 17, :func:`joint_limit_weights`)
    multiply the arm block: the paper defines both as ``w^{-1}`` without saying how they combine;
    the product is this library's reading.

    Args:
        beta: Distribution factor in [0, 1].
        n_vehicle: Number of vehicle rates.
        n_joints: Number of arm joint rates.
        w_max: Largest vehicle inverse weight, 0 < w_max <= 1 (paper: 0.02).
        joint_weights: Optional (n_joints,) factors in (0, 1].

    Returns:
        (n_vehicle + n_joints,) non-negative diagonal of ``w^{-1}``.
    """
    beta = as_scalar(beta, "beta")
    if not 0.0 <= beta <= 1.0:
        raise InputError(f"beta: expected a value in [0, 1], got {beta}")
    w_max = as_scalar(w_max, "w_max", positive=True)
    if w_max > 1.0:
        raise InputError(f"w_max: expected 0 < w_max <= 1, got {w_max}")
    for name, count in (("n_vehicle", n_vehicle), ("n_joints", n_joints)):
        if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 0:
            raise InputError(f"{name}: expected a non-negative integer, got {count!r}")
    arm = np.full(int(n_joints), beta)
    if joint_weights is not None:
        w = as_vector(joint_weights, "joint_weights", int(n_joints))
        if (w < 0.0).any():
            raise InputError("joint_weights: expected non-negative entries")
        arm = arm * w
    return np.concatenate([np.full(int(n_vehicle), (1.0 - beta) * w_max), arm])
