"""Generalised inverses of a Jacobian: plain, weighted and damped least squares.

All three are computed from a singular value decomposition, so they stay defined (and finite) when
the Jacobian loses rank; the closed formulas quoted in the papers hold when ``J`` has full row rank.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ._checks import FloatArray, jacobian, metric_root, nonneg


def pinv(J: Any, rcond: float = 1e-10) -> FloatArray:
    """Moore-Penrose pseudoinverse ``J^+ = sum_i v_i u_i^T / sigma_i``.

    Soylu et al. (2007), Eq. (11); equals ``J^T (J J^T)^{-1}`` of
    Wang et al. (2017), Eq. (6) when ``J`` has full row rank.

    Args:
        J: (m, n) Jacobian (any units; the inverse has the reciprocal units).
        rcond: Singular values below ``rcond * sigma_max`` are treated as zero.

    Returns:
        (n, m) pseudoinverse.

    Raises:
        ShapeError: ``J`` is not a non-empty 2-D array.
        NonFiniteError: ``J`` holds NaN or inf.
    """
    J = jacobian(J, "J")
    rcond = nonneg(rcond, "rcond")
    return _pinv(J, rcond)


def _pinv(J: FloatArray, rcond: float = 1e-10) -> FloatArray:
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    if s.size == 0 or s[0] == 0.0:
        return np.zeros((J.shape[1], J.shape[0]))
    keep = s > rcond * s[0]
    inv = np.zeros_like(s)
    inv[keep] = 1.0 / s[keep]
    return (Vt.T * inv) @ U.T


def _damped(J: FloatArray, damping: float) -> FloatArray:
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    denom = s**2 + damping**2
    factor = np.divide(s, denom, out=np.zeros_like(s), where=denom > 0.0)
    return (Vt.T * factor) @ U.T


def damped_pinv(
    J: Any,
    damping: float,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
) -> FloatArray:
    """Damped least-squares inverse ``J^* = sum_i sigma_i / (sigma_i^2 + eta^2) v_i u_i^T``.

    Soylu et al. (2007), Section 2.5 (Nakamura and Hanafusa). It minimises
    ``||J x - b||^2 + eta^2 ||x||_W^2``; with a metric W it is applied to ``J W^{-1/2}``.
    ``damping = 0`` gives the (weighted) pseudoinverse without truncation of small singular values.

    Args:
        J: (m, n) Jacobian.
        damping: eta >= 0, in the units of ``J``'s singular values.
        weights: Optional metric W, (n,) positive diagonal or (n, n) SPD.
        inverse_weights: Optional (n,) non-negative diagonal of ``W^{-1}`` instead of ``weights``.

    Returns:
        (n, m) damped inverse.
    """
    J = jacobian(J, "J")
    damping = nonneg(damping, "damping")
    D = metric_root(J.shape[1], weights, inverse_weights)
    if D is None:
        return _damped(J, damping)
    return D @ _damped(J @ D, damping)


def weighted_pinv(
    J: Any,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    rcond: float = 1e-10,
) -> FloatArray:
    """Weighted pseudoinverse ``J_W^+ = W^{-1} J^T (J W^{-1} J^T)^{-1}``.

    Soylu et al. (2007), Eq. (17) and Wang et al. (2017), Eq. (12)-(13). It gives
    the solution of ``J x = b`` of least ``x^T W x`` (bigger weight, smaller motion). Computed
    as ``W^{-1/2} (J W^{-1/2})^+``: Eq. (17) for full row rank, and still defined otherwise.
    Wang et al. (2017) specify ``W^{-1}`` directly (Eq. 14, zeros allowed): pass
    ``inverse_weights``.

    Args:
        J: (m, n) Jacobian.
        weights: W as a positive (n,) diagonal or an (n, n) SPD matrix; None means W = I.
        inverse_weights: (n,) non-negative diagonal of ``W^{-1}`` (exclusive with ``weights``).
        rcond: Relative singular-value cut-off of the inner pseudoinverse.

    Returns:
        (n, m) weighted pseudoinverse.

    Raises:
        InputError: bad weights (non-positive, indefinite, both forms given).
    """
    J = jacobian(J, "J")
    rcond = nonneg(rcond, "rcond")
    D = metric_root(J.shape[1], weights, inverse_weights)
    if D is None:
        return _pinv(J, rcond)
    return D @ _pinv(J @ D, rcond)


def null_space_projector(
    J: Any,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    rcond: float = 1e-10,
) -> FloatArray:
    """Projector ``N = I - J_W^+ J`` onto the kernel of ``J`` (W-orthogonal in a metric W).

    Soylu et al. (2007), Eq. (4) and (7); Wang et al. (2017), Eq. (7).

    Returns:
        (n, n) projector with ``J N = 0`` and ``N N = N``.
    """
    J = jacobian(J, "J")
    Jw = weighted_pinv(J, weights, inverse_weights=inverse_weights, rcond=rcond)
    return np.eye(J.shape[1]) - Jw @ J
