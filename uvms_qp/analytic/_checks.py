"""Input checks shared by the closed-form schemes (internal).

Every public function of :mod:`uvms_qp.analytic` converts its inputs here, so a wrong shape or a
NaN is reported with the argument's name and the library's own error types.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validation import as_matrix, as_scalar, as_vector
from ..errors import InputError, ShapeError

FloatArray = NDArray[np.float64]


def items(value: Any, name: str) -> list[Any]:
    """Return the elements of a list/tuple/array argument as a list.

    Raises:
        InputError: ``value`` is not a sequence (e.g. None, a number or a string).
    """
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray):
        raise InputError(f"{name}: expected a list, got {type(value).__name__}")
    return list(value)


def indices(value: Any, name: str) -> list[int]:
    """Return a list of integer indices.

    Raises:
        InputError: not a sequence, or an element that is not an integer.
    """
    out = []
    for k, item in enumerate(items(value, name)):
        if isinstance(item, bool) or not isinstance(item, int | np.integer):
            raise InputError(f"{name}[{k}]: expected an integer index, got {item!r}")
        out.append(int(item))
    return out


def jacobian(value: Any, name: str, cols: int | None = None) -> FloatArray:
    """Return a finite 2-D Jacobian with at least one row and one column."""
    J = as_matrix(value, name, cols=cols)
    if J.shape[0] == 0 or J.shape[1] == 0:
        raise ShapeError(f"{name}: expected a non-empty matrix, got shape {J.shape}")
    return J


def rate(value: Any, name: str, size: int) -> FloatArray:
    """Return a finite task-rate vector of length ``size``."""
    return as_vector(value, name, size)


def metric_root(n: int, weights: Any = None, inverse_weights: Any = None) -> FloatArray | None:
    """Return ``D`` with ``D D^T = W^{-1}`` for the metric ``x^T W x``, or None for W = I.

    Args:
        n: Number of variables.
        weights: ``W`` as a positive (n,) diagonal or an (n, n) symmetric positive-definite matrix.
        inverse_weights: ``W^{-1}`` as a non-negative (n,) diagonal; a zero entry locks that
            variable (the motion distribution of Wang et al. (2017) with beta = 1). Exclusive
            with ``weights``.

    Raises:
        InputError: both given, non-positive weights, or a non-symmetric/indefinite matrix.
    """
    if weights is not None and inverse_weights is not None:
        raise InputError("give either weights or inverse_weights, not both")
    if inverse_weights is not None:
        w_inv = as_vector(inverse_weights, "inverse_weights", n)
        if (w_inv < 0.0).any():
            i = int(np.flatnonzero(w_inv < 0.0)[0])
            raise InputError(f"inverse_weights: expected non-negative entries (index {i})")
        return np.diag(np.sqrt(w_inv))
    if weights is None:
        return None
    array = np.asarray(weights, dtype=np.float64)
    if array.ndim == 2:
        W = as_matrix(array, "weights", n, n)
        if not np.allclose(W, W.T, rtol=1e-10, atol=1e-12):
            raise InputError("weights: expected a symmetric matrix")
        try:
            L = np.linalg.cholesky(W)
        except np.linalg.LinAlgError as exc:
            raise InputError("weights: expected a positive-definite matrix") from exc
        # W = L L^T  =>  W^{-1} = L^{-T} L^{-1}, so D = L^{-T}.
        return np.linalg.inv(L).T
    w = as_vector(array, "weights", n)
    if not (w > 0.0).all():
        i = int(np.flatnonzero(~(w > 0.0))[0])
        raise InputError(f"weights: expected positive entries (index {i} is {w[i]:.6g})")
    return np.diag(1.0 / np.sqrt(w))


def nonneg(value: Any, name: str) -> float:
    """Return a finite non-negative scalar."""
    return as_scalar(value, name, nonnegative=True)


def gain_matrix(value: Any, name: str, size: int) -> FloatArray:
    """Return a gain as a (size, size) matrix from a scalar, a diagonal vector or a matrix."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected numbers, got {type(value).__name__}") from exc
    if array.ndim == 0:
        return as_scalar(float(array), name) * np.eye(size)
    if array.ndim == 1:
        return np.diag(as_vector(array, name, size))
    return as_matrix(array, name, size, size)
