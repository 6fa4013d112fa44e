"""Task-priority redundancy resolution in a weighted metric W.

Nakamura's two-task form, its recursive p-task extension (Siciliano-Slotine) and the
singularity-robust variant (Chiaverini).

With a metric W every formula is evaluated on ``J W^{-1/2}`` and mapped back by ``W^{-1/2}``, so
each pseudoinverse is the weighted one of Soylu et al. (2007), Eq. (17) and each
projector ``I - J_W^+ J`` is W-orthogonal.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from ._checks import FloatArray, gain_matrix, items, jacobian, metric_root, nonneg, rate
from .inverses import _damped, _pinv


def _inverse(J: FloatArray, damping: float, rcond: float) -> FloatArray:
    return _damped(J, damping) if damping > 0.0 else _pinv(J, rcond)


def _pair(
    J1: Any, x1: Any, J2: Any, x2: Any
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    A1 = jacobian(J1, "J1")
    A2 = jacobian(J2, "J2", cols=A1.shape[1])
    return A1, rate(x1, "x1", A1.shape[0]), A2, rate(x2, "x2", A2.shape[0])


def _root(n: int, weights: Any, inverse_weights: Any) -> FloatArray:
    D = metric_root(n, weights, inverse_weights)
    return np.eye(n) if D is None else D


def task_priority(
    J1: Any,
    x1: Any,
    J2: Any,
    x2: Any,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    rcond: float = 1e-10,
) -> FloatArray:
    """Two-task priority ``qdot = J1^+ x1 + N1 (J2 N1)^+ (x2 - J2 J1^+ x1)``, ``N1 = I - J1^+ J1``.

    Soylu et al. (2007), Eq. (10) (Nakamura et al.); also dos Santos et al. (2006),
    Eq. (27). The secondary task is met as well as possible (least squares) without disturbing
    the primary one. Near an algorithmic singularity (``J2 N1`` losing rank) the rates grow
    without bound; the pseudoinverse truncates singular values below ``rcond * sigma_max``.

    Args:
        J1: (m1, n) primary Jacobian.
        x1: (m1,) primary rate reference.
        J2: (m2, n) secondary Jacobian.
        x2: (m2,) secondary rate reference.
        weights: Optional metric W ((n,) positive or (n, n) SPD).
        inverse_weights: Optional (n,) non-negative diagonal of ``W^{-1}``.
        rcond: Relative singular-value cut-off.

    Returns:
        (n,) rates.
    """
    A1, b1, A2, b2 = _pair(J1, x1, J2, x2)
    return recursive_task_priority(
        [(A1, b1), (A2, b2)], weights, inverse_weights=inverse_weights, rcond=rcond
    )


def recursive_task_priority(
    tasks: Sequence[tuple[Any, Any]],
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    damping: float = 0.0,
    rcond: float = 1e-10,
) -> FloatArray:
    """Recursive p-task priority (Siciliano-Slotine extension of Soylu et al. (2007), Eq. (10)).

    With ``qdot_0 = 0``, ``N_0 = I``::

        qdot_k = qdot_{k-1} + (J_k N_{k-1})^+ (x_k - J_k qdot_{k-1})
        N_k    = N_{k-1} - (J_k N_{k-1})^+ (J_k N_{k-1})

    ``N_k`` is the projector onto the kernel of the stacked ``[J_1; ...; J_k]``. For two tasks this
    is exactly Eq. (10). With ``damping > 0`` every ``(J_k N_{k-1})^+`` is replaced by the damped
    least-squares inverse (Soylu et al. (2007), Section 2.5). It is the closed-form reference of the
    lexicographic solver for equality levels with no active bound.

    Args:
        tasks: Sequence of ``(J_k, x_k)`` pairs, highest priority first; ``J_k`` is (m_k, n).
        weights: Optional metric W ((n,) positive or (n, n) SPD) for the minimum-norm choice.
        inverse_weights: Optional (n,) non-negative diagonal of ``W^{-1}``.
        damping: Damping eta >= 0 of every inverse (0: pseudoinverse).
        rcond: Relative singular-value cut-off when ``damping == 0``.

    Returns:
        (n,) rates.

    Raises:
        InputError: no task given.
        ShapeError: Jacobians with different column counts or wrong rate lengths.
    """
    tasks = items(tasks, "tasks")
    if len(tasks) == 0:
        raise InputError("tasks: expected at least one (J, x) pair")
    damping = nonneg(damping, "damping")
    rcond = nonneg(rcond, "rcond")
    checked: list[tuple[FloatArray, FloatArray]] = []
    n = -1
    for k, task in enumerate(tasks):
        if isinstance(task, str | bytes) or not isinstance(task, Sequence) or len(task) != 2:
            raise InputError(f"tasks[{k}]: expected a (J, x) pair")
        J = jacobian(task[0], f"tasks[{k}].J")
        if n < 0:
            n = J.shape[1]
        elif J.shape[1] != n:
            raise ShapeError(f"tasks[{k}].J: expected {n} columns, got {J.shape[1]}")
        checked.append((J, rate(task[1], f"tasks[{k}].x", J.shape[0])))
    D = _root(n, weights, inverse_weights)
    y = np.zeros(n)
    N = np.eye(n)
    for J, x in checked:
        Jt = J @ D
        JN = Jt @ N
        P = _inverse(JN, damping, rcond)
        y = y + P @ (x - Jt @ y)
        N = N - P @ JN
    return D @ y


def singularity_robust_task_priority(
    J1: Any,
    x1: Any,
    J2: Any,
    x2: Any,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    damping: float = 0.0,
    rcond: float = 1e-10,
) -> FloatArray:
    """Singularity-robust task priority ``qdot = J1^+ x1 + (I - J1^+ J1) J2^+ x2``.

    Soylu et al. (2007), Eq. (15) and dos Santos et al. (2006), Eq. (28)
    (Chiaverini). Each task is inverted on its own and the secondary rates are projected onto the
    kernel of the primary task: no algorithmic singularity, at the price of the secondary task not
    being met even when it could be. When the tasks do not conflict it equals Eq. (10).
    ``damping > 0`` uses the damped inverse ``J^*`` for both tasks (Section 2.5). With a metric W
    both inverses are weighted (for Soylu et al.'s (2007) vehicle-pose secondary task
    ``J2 = [I 0]``, the weighted and plain ``J2^+`` coincide for any diagonal W).

    Args:
        J1: (m1, n) primary Jacobian.
        x1: (m1,) primary rate reference.
        J2: (m2, n) secondary Jacobian.
        x2: (m2,) secondary rate reference.
        weights: Optional metric W.
        inverse_weights: Optional (n,) diagonal of ``W^{-1}``.
        damping: Damping eta >= 0 (0: pseudoinverse).
        rcond: Relative singular-value cut-off when ``damping == 0``.

    Returns:
        (n,) rates.
    """
    A1, b1, A2, b2 = _pair(J1, x1, J2, x2)
    damping = nonneg(damping, "damping")
    rcond = nonneg(rcond, "rcond")
    n = A1.shape[1]
    D = _root(n, weights, inverse_weights)
    T1 = A1 @ D
    P1 = _inverse(T1, damping, rcond)
    y2 = _inverse(A2 @ D, damping, rcond) @ b2
    y = P1 @ b1 + y2 - P1 @ (T1 @ y2)
    return D @ y


def closed_loop_reference(xdot_d: Any, error: Any, gain: Any) -> FloatArray:
    """Closed-loop task rate ``xdot_d + K e`` (Soylu et al. (2007), Eq. (16)).

    Args:
        xdot_d: (m,) desired task rate.
        error: (m,) task error ``x_d - x``.
        gain: K as a scalar, an (m,) diagonal (Soylu et al., 2007: ``K_p = [10, 10]``,
            ``K_s = [10, 10, 100]``) or an (m, m) matrix [1/s].

    Returns:
        (m,) reference rate.
    """
    xd = rate(xdot_d, "xdot_d", np.asarray(xdot_d).size)
    e = rate(error, "error", xd.shape[0])
    return xd + gain_matrix(gain, "gain", xd.shape[0]) @ e


def sr_task_priority_closed_loop(
    J1: Any,
    xdot1_d: Any,
    e1: Any,
    K1: Any,
    J2: Any,
    xdot2_d: Any,
    e2: Any,
    K2: Any,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    damping: float = 0.0,
) -> FloatArray:
    """Closed-loop singularity-robust task priority (Soylu et al. (2007), Eq. (16)).

    ``qdot = J1^+ (xdot1_d + K1 e1) + (I - J1^+ J1) J2^+ (xdot2_d + K2 e2)``; Soylu et al. (2007)
    use the weighted inverse with ``W = diag(10, 10, 10, 1, 1, 1)``, ``K1 = [10, 10]``,
    ``K2 = [10, 10, 100]``.

    Returns:
        (n,) rates.
    """
    return singularity_robust_task_priority(
        J1,
        closed_loop_reference(xdot1_d, e1, K1),
        J2,
        closed_loop_reference(xdot2_d, e2, K2),
        weights,
        inverse_weights=inverse_weights,
        damping=damping,
    )
