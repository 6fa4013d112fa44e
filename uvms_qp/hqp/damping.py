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
``y = W^(1/2) x``) and ``M = A_k W^(-1/2) Z = U S V'`` (weighted active rows of the level), every
singular direction with ``sigma_i < epsilon`` gets one damping row

    lambda_i (Z v_i)' W^(1/2) x = 0,   lambda_i = sqrt(epsilon^2 - sigma_i^2),

appended to the level. The level then solves ``min |A_k x - b_k|^2 + sum_i lambda_i^2 (v_i' y)^2``:
along ``v_i`` the answer is ``sigma_i b_i / epsilon^2`` instead of ``b_i / sigma_i`` (bounded by
``|b_i| / epsilon``, continuous through the singularity, equal to the undamped ``b_i / sigma_i`` at
``sigma_i = epsilon``), and every other direction is untouched. Directions with
``sigma_i >= epsilon`` get no row: away from singularities no row is added at all and the answer
is the undamped lexicographic optimum, bit for bit.

Damping does not consume the null space: ``v_i`` lies in the row space of ``M``
(``sigma_i > 0``), so any direction the level's own rows leave free to the lower levels
(``M v = 0``) is orthogonal to ``v_i`` and satisfies the damping rows whatever it is. The lower
levels keep exactly the freedom ``null(A_k)`` they have without damping. Directions with
``sigma_i = 0`` (to round-off) are not damped: the level's rows do not see them.

The active rows come from an undamped answer ``x``: every equality row, and the inequality rows
at or beyond a side (a row the level cannot satisfy counts as active). Hard rows active at ``x``
restrict ``Z`` from the start; the box does not (it is what the damping keeps the rates away
from, not a kinematic constraint of the level).

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

#: Singular values at or below ``RANK_RTOL * sigma_max`` (and ``RANK_ATOL``) count as zero.
RANK_RTOL = 1e-10
RANK_ATOL = 1e-12
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


def _svd(M: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Singular values (descending) and the full right factor ``V'`` (c, c) of ``M`` (m, c)."""
    _, s, vt, info = lapack.dgesdd(M, compute_uv=1, full_matrices=1)
    if info != 0:  # pragma: no cover - LAPACK's divide and conquer failed; the slow, sure path
        _, s, vt = np.linalg.svd(M, full_matrices=True)
    return s, vt


def level_damping(
    levels: Sequence[tuple[FloatArray, FloatArray, FloatArray, FloatArray]],
    x: FloatArray,
    metric: FloatArray,
    thresholds: Sequence[float],
    hard: tuple[FloatArray, FloatArray, FloatArray] | None = None,
) -> Damping:
    """The damping rows of every level at the undamped answer ``x`` (see the module docstring).

    Args:
        levels: Per level ``(A, lo, hi, w)``: rows (m_k, n), sides (m_k,), weights (m_k,).
        x: The undamped answer (n,), which fixes the active inequality rows.
        metric: Diagonal ``W`` (n,) of the final regularisation (positive).
        thresholds: Per level ``epsilon`` (>= 0; 0: no damping) in the units of the level's
            weighted rows per unit of ``W^(1/2) x``.
        hard: Hard rows ``(A, lo, hi)`` (their active rows restrict the freedom), or None.

    Returns:
        The damping rows and the smallest singular value of each level.
    """
    inv_root = 1.0 / np.sqrt(metric)
    root = np.sqrt(metric)
    Z: FloatArray | None = None  # basis of the remaining freedom in y = W^(1/2) x; None: all
    if hard is not None and hard[0].shape[0]:
        H = hard[0][_active(*hard, x)] * inv_root
        if H.shape[0]:
            s, vt = _svd(H)
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
        M = A[active] * np.sqrt(w[active])[:, None] * inv_root
        if Z is not None:
            M = M @ Z
        c = M.shape[1]
        if M.shape[0] == 0 or c == 0:
            rows.append(None)
            sigmas.append(float("inf"))
            continue
        s, vt = _svd(M)
        r = _rank(s)
        sigmas.append(float(s[r - 1]) if r else float("inf"))
        eps = float(thresholds[k])
        weak = np.flatnonzero(s[:r] < eps) if eps > 0.0 else np.zeros(0, dtype=np.intp)
        if weak.size:
            lam = np.sqrt(eps * eps - s[weak] * s[weak])
            directions = vt[weak]  # (r_w, c) in the coordinates of Z
            if Z is not None:
                directions = directions @ Z.T  # (r_w, n) in y
            rows.append(lam[:, None] * directions * root)
        else:
            rows.append(None)
        if k < last:
            null = vt[r:].T
            Z = null if Z is None else Z @ null
    return Damping(tuple(rows), tuple(sigmas))


def _rank(s: FloatArray) -> int:
    """Number of singular values above the rank tolerance."""
    if s.size == 0:
        return 0
    tol = max(RANK_ATOL, RANK_RTOL * float(s[0]))
    return int(np.count_nonzero(s > tol))
