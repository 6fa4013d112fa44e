"""Gradient projection: a primary task plus the gradient of objectives projected onto its kernel."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import InputError, ShapeError
from ._checks import FloatArray, items, jacobian, metric_root, rate
from .inverses import _pinv

#: Null-space projectors of the gradient term (see :func:`multi_objective_gradient_projection`).
PROJECTORS = ("weighted", "euclidean")


def normalized_gradient(gradient: Any, tol: float = 1e-12) -> FloatArray:
    """Unit gradient ``grad h = grad H / ||grad H||_2``.

    Wang et al. (2017), Eq. (11): keeps one objective from dominating the sum in
    Eq. (10). A gradient of norm below ``tol`` (a stationary point) returns zeros.

    Args:
        gradient: (n,) gradient of a scalar objective.
        tol: Norm below which the gradient is treated as zero.

    Returns:
        (n,) unit vector, or zeros.
    """
    g = as_vector(gradient, "gradient")
    norm = float(np.linalg.norm(g))
    if norm <= tol:
        return np.zeros_like(g)
    return g / norm


def gradient_projection(
    J: Any,
    xdot: Any,
    gradient: Any,
    gain: float,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    rcond: float = 1e-10,
) -> FloatArray:
    """Projected gradient ``qdot = J_W^+ xdot + (I - J_W^+ J) (gain * grad h)``.

    Soylu et al. (2007), Eq. (4) (Liegeois): a positive ``gain`` ascends ``h``, a
    negative one descends it. Wang et al. (2017), Eq. (9) writes ``-lambda grad H``:
    pass ``gain = -lambda``. The projection never changes the task rate ``J qdot``.

    Args:
        J: (m, n) task Jacobian.
        xdot: (m,) task rate reference (e.g. ``xdot_d + K e``).
        gradient: (n,) gradient of the objective with respect to the n variables.
        gain: Scalar step on the gradient.
        weights: Optional metric W (see :func:`weighted_pinv`); W = I gives Eq. (4) exactly.
        inverse_weights: Optional (n,) diagonal of ``W^{-1}``.
        rcond: Relative singular-value cut-off.

    Returns:
        (n,) rates.
    """
    J = jacobian(J, "J")
    n = J.shape[1]
    g = as_vector(gradient, "gradient", n)
    gain = as_scalar(gain, "gain")
    return _project(J, rate(xdot, "xdot", J.shape[0]), gain * g, n, weights, inverse_weights, rcond)


def _project(
    J: FloatArray,
    xdot: FloatArray,
    secondary: FloatArray,
    n: int,
    weights: Any,
    inverse_weights: Any,
    rcond: float,
    projector: str = "weighted",
) -> FloatArray:
    D = metric_root(n, weights, inverse_weights)
    Jp = _pinv(J, rcond) if D is None else D @ _pinv(J @ D, rcond)
    particular = Jp @ xdot
    Jn = Jp if projector == "weighted" or D is None else _pinv(J, rcond)
    return particular + secondary - Jn @ (J @ secondary)


def check_projector(projector: Any) -> str:
    """Return ``projector`` if it names one of :data:`PROJECTORS`.

    Raises:
        InputError: anything else (the known projectors are listed).
    """
    if not isinstance(projector, str) or projector not in PROJECTORS:
        raise InputError(
            f"projector: expected one of {', '.join(repr(p) for p in PROJECTORS)}, "
            f"got {projector!r}"
        )
    return projector


def multi_objective_gradient_projection(
    J: Any,
    xdot: Any,
    gradients: Sequence[Any],
    alphas: Sequence[float],
    gain: float,
    weights: Any = None,
    *,
    inverse_weights: Any = None,
    normalize: bool = True,
    rcond: float = 1e-10,
    projector: str = "weighted",
) -> FloatArray:
    """Multi-objective weighted gradient projection.

    ``qdot = J_W^+ xdot + gain P sum_i alpha_i grad H_i / ||grad H_i||``:
    Wang et al. (2017), Eq. (10)-(11) (W = I) and the multitask weighted form of Eq. (22)-(23),
    where ``gain`` is k_H, ``xdot = zeta_dot_de + K_e e`` and W^{-1} is the motion distribution
    matrix of Eq. (14). Eq. (23) subtracts the payload term: pass a negative alpha
    (``alphas = [alpha_1, -alpha_2]``).

    Eq. (22)-(23) print the null-space projector as ``I - J_w^+ J_w``, a symbol defined nowhere
    else in the paper; two readings leave the task rate ``J qdot`` unchanged:

    * ``projector="weighted"``: ``P = I - J_W^+ J``, the W-oblique projector of the weighted
      inverse of Eq. (12). It moves the gradient step back into the task's kernel along
      ``W^{-1} J^T``, so the variables W makes expensive (the vehicle in Eq. 14) barely take
      part: a joint-space gradient then cannot move the vehicle.
    * ``projector="euclidean"``: ``P = I - J^+ J``, the orthogonal projector of Eq. (7)-(10),
      which Eq. (22) says it combines. A joint-space gradient then moves the vehicle as much as
      the kernel of the task requires.

    With ``weights`` and ``inverse_weights`` both None the two are the same matrix.

    Args:
        J: (m, n) task Jacobian.
        xdot: (m,) task rate reference.
        gradients: k gradients, each (n,) (pad arm-only gradients with zeros for vehicle DOFs).
        alphas: k signed weights alpha_i.
        gain: Scalar k_H (or lambda).
        weights: Optional metric W.
        inverse_weights: Optional (n,) diagonal of ``W^{-1}``.
        normalize: Normalise each gradient (Eq. 11); False sums raw gradients.
        rcond: Relative singular-value cut-off.
        projector: ``"weighted"`` or ``"euclidean"`` (above).

    Returns:
        (n,) rates.

    Raises:
        InputError: different numbers of gradients and alphas, or an unknown projector.
    """
    projector = check_projector(projector)
    J = jacobian(J, "J")
    n = J.shape[1]
    gradients = items(gradients, "gradients")
    alphas = items(alphas, "alphas")
    if len(gradients) != len(alphas):
        raise InputError(
            f"gradients and alphas: expected the same count, got {len(gradients)} and {len(alphas)}"
        )
    combined = np.zeros(n)
    for i, (g, a) in enumerate(zip(gradients, alphas, strict=True)):
        gi = as_vector(g, f"gradients[{i}]")
        if gi.shape[0] != n:
            raise ShapeError(f"gradients[{i}]: expected length {n}, got {gi.shape[0]}")
        ai = as_scalar(a, f"alphas[{i}]")
        combined += ai * (normalized_gradient(gi) if normalize else gi)
    gain = as_scalar(gain, "gain")
    return _project(
        J, rate(xdot, "xdot", J.shape[0]), gain * combined, n, weights, inverse_weights, rcond,
        projector,
    )
