"""Manipulability, its gradient, and Soylu et al.'s (2007) dexterous task priority."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .._validation import as_array, as_scalar, as_vector
from ..errors import NonFiniteError, ShapeError
from ._checks import FloatArray, jacobian, metric_root, nonneg, rate
from .inverses import _pinv


def manipulability(J: Any) -> float:
    """Yoshikawa's measure ``rho = sqrt(det(J J^T)) = prod_i sigma_i``.

    Soylu et al. (2007), Eq. (18); Wang et al. (2017), Eq. (18). Zero when ``J``
    has fewer columns than rows or loses row rank. For Soylu et al.'s (2007) collective Jacobian
    ``J_a = [J_p; J_s]`` with ``J_s = [I 0]`` (vehicle pose), ``rho(J_a)`` equals the
    manipulability of the arm columns of ``J_p`` alone (Schur complement).

    Args:
        J: (m, n) Jacobian.

    Returns:
        rho >= 0, in the product of ``J``'s units.
    """
    J = jacobian(J, "J")
    if J.shape[0] > J.shape[1]:
        return 0.0
    return float(np.prod(np.linalg.svd(J, compute_uv=False)))


def manipulability_gradient(J: Any, dJ: Any) -> FloatArray:
    """Gradient ``d rho / d q_i = rho * trace(dJ/dq_i J^+)``.

    Soylu et al. (2007), Eq. (19); Wang et al. (2017), Eq. (19). Valid where
    ``J`` has full row rank (rho > 0); returns zeros where rho = 0.

    Args:
        J: (m, n) Jacobian at q.
        dJ: (k, m, n) stack of partial derivatives ``dJ/dq_i`` for the k variables q_i
            (see :func:`jacobian_derivatives` for finite differences).

    Returns:
        (k,) gradient.
    """
    J = jacobian(J, "J")
    D = np.asarray(dJ, dtype=np.float64)
    if D.ndim != 3 or D.shape[1:] != J.shape:
        raise ShapeError(f"dJ: expected shape (k, {J.shape[0]}, {J.shape[1]}), got {D.shape}")
    if not np.isfinite(D).all():
        raise NonFiniteError("dJ contains NaN or inf")
    rho = manipulability(J)
    if rho == 0.0:
        return np.zeros(D.shape[0])
    Jp = _pinv(J)
    return rho * np.einsum("kij,ji->k", D, Jp)


def jacobian_derivatives(
    jacobian_fn: Callable[[FloatArray], Any], q: Any, step: float = 1e-6
) -> FloatArray:
    """Central finite differences ``dJ/dq_i`` of a Jacobian function, shape (k, m, n).

    Args:
        jacobian_fn: Maps a (k,) configuration to an (m, n) Jacobian.
        q: (k,) configuration at which to differentiate.
        step: Difference step [rad or m].

    Returns:
        (k, m, n) derivatives, accurate to O(step^2).
    """
    q = as_vector(q, "q")
    step = as_scalar(step, "step", positive=True)
    out = []
    for i in range(q.shape[0]):
        dq = np.zeros_like(q)
        dq[i] = step
        Jp = np.asarray(jacobian_fn(q + dq), dtype=np.float64)
        Jm = np.asarray(jacobian_fn(q - dq), dtype=np.float64)
        out.append((Jp - Jm) / (2.0 * step))
    return np.stack(out)


def shaping_function(rho: Any, rho_bar: float) -> Any:
    """Shaping function k(rho) of Soylu et al. (2007), Eq. (21) (Fig. 4).

    The text fixes k = 0 for ``rho >= rho_bar``, k = 1 for ``rho < rho_bar / 2`` and a blend in
    between; the figure with the exact curve is not in the text. This reconstruction uses the
    C1-smooth cosine blend::

        k = (1 + cos(pi * (rho - rho_bar/2) / (rho_bar/2))) / 2   for rho_bar/2 <= rho < rho_bar

    Args:
        rho: Manipulability value(s) >= 0 (a number or an array).
        rho_bar: Threshold > 0 (Soylu et al., 2007: 1.3).

    Returns:
        k in [0, 1], a float for a number, else an array of rho's shape.

    Raises:
        InputError: ``rho_bar`` not positive, or ``rho`` not real numbers.
        NonFiniteError: ``rho`` holds NaN or inf.
    """
    rho_bar = as_scalar(rho_bar, "rho_bar", positive=True)
    if isinstance(rho, float | int) and not isinstance(rho, bool):
        if not math.isfinite(rho):
            raise NonFiniteError(f"rho: expected a finite number, got {rho}")
        return _shaping(float(rho), rho_bar)
    r = as_array(rho, "rho")
    if not np.isfinite(r).all():
        raise NonFiniteError("rho contains NaN or inf")
    k = np.array([_shaping(x, rho_bar) for x in r.reshape(-1).tolist()]).reshape(r.shape)
    return float(k) if k.ndim == 0 else k


def _shaping(rho: float, rho_bar: float) -> float:
    half = 0.5 * rho_bar
    if rho >= rho_bar:
        return 0.0
    if rho < half:
        return 1.0
    return 0.5 * (1.0 + math.cos(math.pi * (rho - half) / half))


def sign_switch(rho_rate: float) -> float:
    """Switch ``(1 - sign(rho_dot)) / 2`` of Soylu et al. (2007), Eq. (21).

    With the paper's convention ``sign(rho_dot) = -1`` for ``rho_dot <= 0``: returns 1 while
    manipulability is not increasing (the gradient term acts) and 0 while it increases.
    """
    value = as_scalar(rho_rate, "rho_rate")
    return 1.0 if value <= 0.0 else 0.0


def dexterous_task_priority(
    Jp: Any,
    xp: Any,
    Js: Any,
    xs: Any,
    rho: float,
    rho_gradient: Any,
    rho_bar: float,
    gain: float,
    weights: Any = None,
    *,
    rho_rate: float | None = None,
    rcond: float = 1e-10,
) -> FloatArray:
    """Dexterous task priority of Soylu et al. (2007), Eq. (21).

    ``qdot = J_wp^+ xp + (I - J_wp^+ Jp) ((1 - k) Js^+ xs + k s lambda grad rho)``,
    ``s = (1 - sign(rho_dot)) / 2``

    with ``J_wp^+`` the weighted pseudoinverse (Eq. 17), ``k = shaping_function(rho, rho_bar)``,
    ``xp = xdot_p + K_p e_p`` and ``xs = xdot_s + K_s e_s``. When ``rho_rate`` is None it is
    predicted by Eq. (20), ``rho_dot = grad rho . qdot_SR`` with ``qdot_SR`` the weighted
    singularity-robust solution (Eq. 15/16) of the same tasks; pass a measured value (e.g. the
    backward difference of rho) to use that instead.

    Args:
        Jp: (m1, n) primary (end-effector) Jacobian.
        xp: (m1,) primary rate reference.
        Js: (m2, n) secondary (vehicle station-keeping) Jacobian.
        xs: (m2,) secondary rate reference.
        rho: Current manipulability of ``J_a = [Jp; Js]`` (Eq. 18).
        rho_gradient: (n,) ``d rho / d q`` (Eq. 19), zeros on the vehicle DOFs.
        rho_bar: Threshold (Soylu et al., 2007: 1.3).
        gain: lambda > 0 (Soylu et al., 2007: 10).
        weights: Optional metric W (Soylu et al., 2007: ``diag(10, 10, 10, 1, 1, 1)``).
        rho_rate: Optional rho_dot; None predicts it with Eq. (20).
        rcond: Relative singular-value cut-off.

    Returns:
        (n,) rates.
    """
    A1 = jacobian(Jp, "Jp")
    n = A1.shape[1]
    A2 = jacobian(Js, "Js", cols=n)
    b1 = rate(xp, "xp", A1.shape[0])
    b2 = rate(xs, "xs", A2.shape[0])
    rho = nonneg(rho, "rho")
    g = as_vector(rho_gradient, "rho_gradient", n)
    gain = as_scalar(gain, "gain")
    D = metric_root(n, weights, None)
    D = np.eye(n) if D is None else D
    P1 = D @ _pinv(A1 @ D, rcond)
    N1 = np.eye(n) - P1 @ A1
    secondary = D @ _pinv(A2 @ D, rcond) @ b2
    primary = P1 @ b1
    if rho_rate is None:
        rho_rate = float(g @ (primary + N1 @ secondary))
    k = shaping_function(rho, rho_bar)
    blend = (1.0 - k) * secondary + k * sign_switch(rho_rate) * gain * g
    return primary + N1 @ blend
