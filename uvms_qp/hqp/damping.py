r"""Singular-value damping of a lexicographic problem that keeps the hierarchy exact elsewhere.

A level whose rows are nearly singular in the freedom the higher levels leave (a stretched arm, a
station-keeping level that conflicts with the tool task) has an undamped least-squares optimum
that asks ``b_i / sigma_i`` along the weak direction: rates far beyond any bound for a tiny gain
in the level's residual. The box clips it to a vertex, one period of motion crosses the
singularity, and the optimum jumps to the opposite vertex: the command bangs between its bounds.

The damping here is the variable, per-direction damping of Nakamura and Hanafusa (1986) and
Maciejewski and Klein (1988), applied per level inside the hierarchy as in the damped HQP of
Escande, Mansard and Wieber (2014). For level ``k``, with ``Z`` an orthonormal basis of the
freedom left by the higher levels' active rows (in the metric ``W`` of the final regularisation,
``y = W^(1/2) x``), the level's weighted rows are scaled to unit norm (``D``, so that units and
scale drop out: a singular value is then a pure measure of how nearly the rows depend on each
other and on the higher levels) and ``D A_k W^(-1/2) Z = U S V'``. Every direction with
``sigma_i < epsilon_i`` gets one damping row appended to the level,

    lambda_i (Z v_i)' W^(1/2) x = 0,   lambda_i = c_i sqrt(epsilon_i^2 - sigma_i^2),

with ``c_i = |D^(-1) u_i|`` the rows' own scale along that direction. In the normalised units
the level then answers ``sigma_i b_i / epsilon_i^2`` along ``v_i`` instead of
``b_i / sigma_i``: bounded by ``|b_i| / epsilon_i``, continuous through the singularity, equal to
the undamped value at ``sigma_i = epsilon_i``; every other direction is untouched. Directions with
``sigma_i >= epsilon_i`` get no row: away from singularities no row is added at all and the
answer is the undamped lexicographic optimum, bit for bit.

The threshold is ``epsilon_i = max(epsilon, sqrt(dt |b_i|))``, ``b_i`` the level's demand along
the direction (normalised units, from the undamped answer). In closed loop the damped answer
moves the singular value by ``dt g sigma_i b_i / epsilon_i^2`` per period (``g``, the change of
``sigma`` per unit of motion, is of order 1 per radian in normalised units), so
``sigma_(k+1) = (1 - dt g |b_i| / epsilon_i^2) sigma_k`` near the singularity: monotone, without
the overshoot that is the chatter, when ``epsilon_i^2 >= dt g |b_i|``. The demand term keeps that
condition at large demands and long periods; ``epsilon`` is the floor.

Damping does not consume the null space: ``v_i`` lies in the row space of the level's rows in
``Z`` (``sigma_i > 0``), so any direction the level's own rows leave free to the lower levels is
orthogonal to ``v_i`` and satisfies the damping rows whatever it is. The lower levels keep
exactly the freedom ``null(A_k)`` they have without damping. Directions with ``sigma_i = 0`` (to
round-off) are not damped: the level's rows do not see them.

The active rows come from an undamped answer ``x``: every equality row, and the inequality rows
at or beyond a side (a row the level cannot satisfy counts as active). They restrict ``Z`` for
the levels below. The rows a level damps are its equality rows and the active inequality rows
that demand motion (a side that excludes zero, ``lo > 0`` or ``hi < 0``: a floor already
crossed): an inequality row that zero motion satisfies asks for no rate, and a damping row on it
would pin a direction the row leaves free once it is no longer active. Hard rows active at ``x``
restrict ``Z`` from the start; the box does not (it is what the damping keeps the rates away
from, not a kinematic constraint of the level). The active set is the undamped answer's, so an
inequality row of a higher level that a lower level pushes onto its side enters that level's
freedom: near a singularity, such a lower level can change how a higher one is damped.

A damped level's answer is the lexicographic optimum of the problem with the damping rows, not
of the user's problem: a certificate of the user's problem does not apply to it (see
:class:`Damping`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack

from .._validation import FloatArray

#: The library's damping threshold ``epsilon`` of every level (``Controller(damping=...)``): the
#: singular value of a level's unit-norm rows, in the freedom the levels above leave, below which
#: its directions are damped (dimensionless; a row at about 3 degrees from the span of the others).
DEFAULT_THRESHOLD = 0.05
#: Singular values at or below ``RANK_RTOL * sigma_max`` (and ``RANK_ATOL``) count as zero.
RANK_RTOL = 1e-12
RANK_ATOL = 1e-15
#: A row counts as active when it is within ``ACTIVE_RTOL * max(1, |side|)`` of a side.
ACTIVE_RTOL = 1e-7


@dataclass(frozen=True)
class Damping:
    """The damping rows of each level of a problem, and what they are for.

    Attributes:
        rows: Per level, the damping rows ``D_k`` (r_k, n) (targets 0, weight 1), or None for a
            level without damping (threshold 0 or no singular value below it).
        sigma_min: Per level, the smallest nonzero singular value of its weighted active rows in
            the freedom the higher levels leave (``inf`` for a level without active rows or
            freedom, NaN for a level whose threshold is 0 and whose singular values were not
            computed).
    """

    rows: tuple[FloatArray | None, ...]
    sigma_min: tuple[float, ...]

    @property
    def acted(self) -> bool:
        """True when at least one level got damping rows."""
        return any(r is not None for r in self.rows)

    @property
    def damped_levels(self) -> tuple[int, ...]:
        """Indices of the levels that got damping rows."""
        return tuple(k for k, r in enumerate(self.rows) if r is not None)


def _active(A: FloatArray, lo: FloatArray, hi: FloatArray, x: FloatArray) -> np.ndarray:
    """Rows of ``lo <= A x <= hi`` that are equalities or at (or beyond) a side at ``x``."""
    y = A @ x
    with np.errstate(invalid="ignore"):
        near_lo = y <= lo + ACTIVE_RTOL * np.maximum(1.0, np.abs(lo))
        near_hi = y >= hi - ACTIVE_RTOL * np.maximum(1.0, np.abs(hi))
    return np.asarray((lo == hi) | near_lo | near_hi)


def _svd(M: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``U`` (m, m), singular values (descending) and ``V'`` (c, c) of ``M`` (m, c)."""
    u, s, vt, info = lapack.dgesdd(M, compute_uv=1, full_matrices=1)
    if info != 0:  # pragma: no cover - LAPACK's divide and conquer failed; the slow, sure path
        u, s, vt = np.linalg.svd(M, full_matrices=True)
    return u, s, vt


def level_damping(
    levels: Sequence[tuple[FloatArray, FloatArray, FloatArray, FloatArray]],
    x: FloatArray,
    metric: FloatArray,
    thresholds: Sequence[float],
    hard: tuple[FloatArray, FloatArray, FloatArray] | None = None,
    dt: float = 0.0,
) -> Damping:
    """The damping rows of every level at the undamped answer ``x`` (see the module docstring).

    Args:
        levels: Per level ``(A, lo, hi, w)``: rows (m_k, n), sides (m_k,), weights (m_k,).
        x: The undamped answer (n,), which fixes the active inequality rows and the demands.
        metric: Diagonal ``W`` (n,) of the final regularisation (positive).
        thresholds: Per level ``epsilon`` (>= 0; 0: no damping), dimensionless.
        hard: Hard rows ``(A, lo, hi)`` (their active rows restrict the freedom), or None.
        dt: Control period [s] of the closed loop (0: no demand term in the threshold).

    Returns:
        The damping rows and the smallest singular value of each level.
    """
    inv_root = 1.0 / np.sqrt(metric)
    root = np.sqrt(metric)
    y = x * root
    Z: FloatArray | None = None  # basis of the remaining freedom in y = W^(1/2) x; None: all
    if hard is not None and hard[0].shape[0]:
        H = hard[0][_active(*hard, x)] * inv_root
        if H.shape[0]:
            _, s, vt = _svd(H)
            Z = vt[_rank(s):].T
    last = max((k for k, e in enumerate(thresholds) if e > 0.0), default=-1)
    rows: list[FloatArray | None] = []
    sigmas: list[float] = []
    for k, (A, lo, hi, w) in enumerate(levels):
        if k > last:  # no damped level below: nothing more to compute
            rows.append(None)
            sigmas.append(float("nan"))
            continue
        active = _active(A, lo, hi, x)
        scaled = A * np.sqrt(w)[:, None] * inv_root  # weighted rows over y
        c = scaled.shape[1] if Z is None else Z.shape[1]
        demanding = active & ((lo == hi) | (lo > 0.0) | (hi < 0.0))
        vt = None
        if not demanding.any() or c == 0:
            rows.append(None)
            sigmas.append(float("inf"))
        else:
            Ad = scaled[demanding]
            norms = np.sqrt((Ad * Ad).sum(axis=1))
            norms[norms == 0.0] = 1.0
            M = Ad if Z is None else Ad @ Z
            u, s, vt = _svd(M / norms[:, None])
            r = _rank(s)
            sigmas.append(float(s[r - 1]) if r else float("inf"))
            rows.append(_damping_rows(float(thresholds[k]), dt, u, s, vt, r, norms, Z, root,
                                      A[demanding] @ x, lo[demanding], hi[demanding],
                                      np.sqrt(w[demanding]), y))
        if k < last and c and active.any():
            if vt is None or not np.array_equal(active, demanding):
                M = scaled[active] if Z is None else scaled[active] @ Z
                _, s, vt = _svd(M)
            null = vt[_rank(s):].T
            Z = null if Z is None else Z @ null
    return Damping(tuple(rows), tuple(sigmas))


def _damping_rows(eps: float, dt: float, u: FloatArray, s: FloatArray, vt: FloatArray, r: int,
                  norms: FloatArray, Z: FloatArray | None, root: FloatArray, z: FloatArray,
                  lo: FloatArray, hi: FloatArray, root_w: FloatArray, y: FloatArray
                  ) -> FloatArray | None:
    """The damping rows of one level (None when no direction is below its threshold).

    ``u, s, vt``: SVD of the level's normalised rows in the freedom ``Z`` (rank ``r``);
    ``z = A x`` and the sides of those rows, their weights' roots, and ``y = W^(1/2) x``.
    """
    if eps <= 0.0 or r == 0:
        return None
    limit = np.full(r, eps)
    if dt > 0.0:  # the demand along each direction, from the undamped answer (normalised units)
        slack = z - np.minimum(np.maximum(z, lo), hi)
        yz = y if Z is None else Z.T @ y
        demand = s[:r] * (vt[:r] @ yz) - u[:, :r].T @ (root_w * slack / norms)
        limit = np.sqrt(np.maximum(eps * eps, dt * np.abs(demand)))
    weak = np.flatnonzero(s[:r] < limit)
    if weak.size == 0:
        return None
    scale = np.linalg.norm(u[:, weak] * norms[:, None], axis=0)  # the rows' own units
    lam = scale * np.sqrt(limit[weak] ** 2 - s[weak] ** 2)
    directions = vt[weak] if Z is None else vt[weak] @ Z.T  # (r_w, n) in y
    return np.asarray(lam[:, None] * directions * root, dtype=np.float64)


def _rank(s: FloatArray) -> int:
    """Number of singular values above the rank tolerance."""
    if s.size == 0:
        return 0
    tol = max(RANK_ATOL, RANK_RTOL * float(s[0]))
    return int(np.count_nonzero(s > tol))
