"""Optimality certificate of each level of a lexicographic answer, and its repair.

The problem is the stacked layout shared by every solver (:class:`~uvms_qp.hqp.problem.Problem`):
``n`` variables, rows ``A = [I_n; A_H; A_0; ...; A_{p-1}]`` of shape (M, n), sides ``lo``, ``hi``
(``-inf`` / ``+inf`` allowed, equality where ``lo == hi``), ``mh`` hard rows, level sizes and
level row weights ``w``. Level k's weighted violation is ``f_k(x) = 1/2 sum_i w_i s_i^2`` with
``s = A_k x - clip(A_k x, lo_k, hi_k)``; its residual is ``rho_k = sqrt(2 f_k)``.

**What a certificate proves.** Given an answer ``x`` inside the hard set, level k is optimal when
no point ``x'`` of its *frozen set* has a smaller ``f_k``: the box and the hard rows hold and
every row ``i`` of every higher level keeps at most the violation it has at ``x``,
``lo_i - |s_i| <= a_i x' <= hi_i + |s_i|`` (the lexicographic definition row by row). When a
higher level is optimal this is exactly the set of points that keep its optimum (its violations
are unique), so level-by-level certificates prove the lexicographic optimum. ``f_k`` is convex
with gradient ``g = A_k^T (w_k s_k)`` and the frozen set is a polyhedron, so ``x`` is optimal iff
``-g`` lies in the cone of the outward normals of the constraints active at ``x`` (``+a`` at a
frozen upper side, ``-a`` at a frozen lower side, either sign for a row at both, e.g. an
equality row met exactly).

For any multipliers ``lambda`` (signed: ``lambda_i > 0`` on the upper side of row ``i``, ``< 0``
on its lower side; the box rows included) and any feasible ``x*``, convexity gives

    f_k(x) - f_k(x*) <= sum_j |r_j| (width_j + |s_j|) + sum_i |lambda_i| (delta_i + eps_i) =: df,

with ``r = g + A_act' lambda``, ``width_j`` the box width of variable ``j``, ``delta_i`` the
distance of row ``i`` to the side its multiplier points to and ``eps_i`` the *freeze allowance*
``freeze_tol * max(1, |a_i x|)`` of a higher level row (0 for the box and hard rows). A variable
without a box has no width: its part of ``r`` is moved onto the level's own rows instead, with
multipliers ``w_i s_i + delta_i`` in the dual of the level's least-squares problem (equality rows
and violated inequality rows, signs kept), which adds ``1/2 sum delta_i^2 / w_i`` to ``df``
(weak duality; ``delta`` the least-norm change that cancels it, and what is left of ``r`` there
must be round-off, ``stat_tol`` of the gradient). So
``rho_k(x) - rho_k* <= rho_k - sqrt(rho_k^2 - 2 df)``. The bound holds for *any* multipliers
of the right signs: the certificate's soundness does not depend on how they were found. Level
k is

* ``met``: ``rho_k <= level_tol * scale_k`` (``scale_k = max(1, max |finite side of level k|)``);
* ``certified``: the bound with the allowance is at most ``opt_tol * scale_k``: no point that
  keeps every higher row within its violation at ``x`` plus ``eps_i`` improves the level by more
  than ``opt_tol * scale_k``;
* ``ill_posed``: certified without the allowance but not with it: ``x`` is the optimum of the
  frozen set, but moving the higher rows by 1e-9 relative could change this level by more than
  ``opt_tol * scale_k`` (nearly dependent rows across levels, a singular arm): the priorities do
  not determine the level to the tolerance, and the answer is not called optimal;
* ``improvable`` (an exact solve found a better point of the frozen set, kept as the witness) or
  ``unproven`` (neither shown).

**How the multipliers are found.** The best multipliers make ``r`` the projection of ``-g`` on
the polar of the cone of active normals, i.e. ``-r`` is the steepest feasible descent direction
``d* = argmin 1/2 |d|^2 + g'd`` subject to ``a_i' d <= 0`` (upper side active), ``>= 0`` (lower
side active), the box rows as simple bounds (Moreau's decomposition; ``d* = 0`` exactly when
``x`` is stationary): a least-distance problem (``H = I``), DAQP's own problem class, whose
multipliers are the ``lambda`` above. One DAQP workspace per problem holds every row above the
lowest level in place (the rows a controller writes every tick); per answer, one product
``A x`` gives every distance to a frozen side and one product every unmet level's gradient;
the levels are then solved from the lowest unmet one up, each switching off the rows of the
level below it (infinite sides) and handing DAQP its unit gradient (two C calls from an empty
working set); the bounds of all levels come from a few matrix products. A level these
multipliers leave unproven gets them once more by non-negative least squares on the same active
sides (DAQP's dual active set can stall on a degenerate set: more active sides than free
variables, rows active on both sides). Levels met to tolerance
cost nothing, and an answer whose levels are all met is not looked at. Measured in
``benchmarks/bench_certificate.py``.

:func:`repair` starts from an answer whose certificate fails and solves the first failing level
and every level below it exactly (:func:`uvms_qp.hqp.kkt.active_set` on each level's frozen set,
started at the current point), then certifies the result again.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from time import perf_counter
from typing import NamedTuple

import numpy as np
from scipy.optimize import nnls

from .._validation import FloatArray
from .backends.daqp_binding import DaqpBinding, open_daqp
from .kkt import active_set
from .problem import Problem

#: Verdicts of one level.
MET = "met"
CERTIFIED = "certified"
ILL_POSED = "ill_posed"
IMPROVABLE = "improvable"
UNPROVEN = "unproven"

#: default relative tolerance deciding that a level is met (the registry's ``level_tol``)
LEVEL_TOL = 1e-6
#: default relative tolerance on the residual gap ``rho_k(x) - rho_k*`` of a certified level
OPT_TOL = 1e-6
#: freeze allowance of a higher level row, relative to ``max(1, |a_i x|)``
FREEZE_TOL = 1e-9
#: what a least-norm solve may leave of the residual on the variables without a box, relative to
#: the level's gradient (round-off)
STAT_TOL = 1e-9
#: relative distance ``act_tol (1 + |a_i x|)`` within which a side counts as active
ACT_TOL = 1e-7
#: relative tolerance on the box and hard rows of an answer (``x`` must be inside)
HARD_TOL = 1e-9
#: DAQP's settings for the least-distance problems (H = I needs no proximal term)
_LDP_SETTINGS = {"primal_tol": 1e-8, "eps_prox": 0.0, "iter_limit": 2000, "time_limit": 0.0}
_LDP_RETRY = {**_LDP_SETTINGS, "primal_tol": 1e-6}
_INF = 1e30  # DAQP's infinity
_KEEP = 8  # workspaces kept (the problems a solver alternates between: full, relaxed)


class LevelCertificate(NamedTuple):
    """The verdict on one level (a named tuple: cheap to make on every control tick).

    Attributes:
        level: Level index (0 = highest priority).
        verdict: One of ``met``, ``certified``, ``ill_posed``, ``improvable``, ``unproven``
            (module docstring).
        residual: ``rho_k(x)``, the weighted violation norm at x.
        stationarity: Largest ``|r_j|`` left after the multipliers (0 when met).
        gap: Upper bound on ``rho_k(x) - rho_k*`` with the freeze allowance (``inf`` when
            unknown), or the exact difference to the optimum ``better`` when that was computed.
        better: The exact optimum of the level over its frozen set, when computed.
        improvement: ``rho_k(x) - rho_k(better)`` when ``better`` is known, else 0.
    """

    level: int
    verdict: str
    residual: float
    stationarity: float = 0.0
    gap: float = 0.0
    better: FloatArray | None = None
    improvement: float = 0.0

    @property
    def ok(self) -> bool:
        """True when the level is met or certified."""
        return self.verdict in (MET, CERTIFIED)


class Certificate(NamedTuple):
    """Verdicts of every level at one answer (a named tuple).

    Attributes:
        levels: One :class:`LevelCertificate` per level, highest priority first.
        hard_violation: Largest violation of the box and hard rows at x.
        inside: True when x is finite and inside the hard set (to ``hard_tol`` relative).
    """

    levels: tuple[LevelCertificate, ...]
    hard_violation: float
    inside: bool

    @property
    def ok(self) -> bool:
        """True when x is inside the hard set and every level is met or certified."""
        return self.inside and all(c.ok for c in self.levels)

    @property
    def first_failure(self) -> int | None:
        """Index of the first level neither met nor certified (None when there is none)."""
        for c in self.levels:
            if not c.ok:
                return c.level
        return None

    @property
    def ill_posed(self) -> bool:
        """True when the first level that is not proven is ``ill_posed`` (no solver does better)."""
        k = self.first_failure
        return k is not None and self.levels[k].verdict == ILL_POSED

    def reason(self) -> str:
        """A short sentence for a status message (empty when ``ok``)."""
        if not self.inside:
            return "x is not inside the hard set"
        k = self.first_failure
        if k is None:
            return ""
        c = self.levels[k]
        if c.verdict == ILL_POSED:
            return (f"level {k} is ill-posed: a 1e-9 change of the levels above may change its "
                    f"optimum by more than the tolerance (gap bound {c.gap:.2e})")
        if c.verdict == IMPROVABLE:
            return f"level {k} is not optimal (improvable by {c.improvement:.2e})"
        return f"level {k} is not proven optimal (gap bound {c.gap:.2e})"


@dataclass(frozen=True, eq=False)
class Repair:
    """Outcome of :func:`repair`.

    Attributes:
        x: The repaired point: certified, or the exact optimum of every level's frozen set whose
            first unproven level is ill-posed; else the input.
        certificate: Certificate of ``x``.
        repaired: True when ``x`` differs from the input and is certified.
        message: What happened, for a status message.
    """

    x: FloatArray
    certificate: Certificate
    repaired: bool
    message: str


# ------------------------------------------------------------------------------- slacks
def slacks(problem: Problem, x: FloatArray) -> FloatArray:
    """Signed violation ``s = A x - clip(A x, lo, hi)`` of every stacked row."""
    y = problem.A.dot(x)
    return y - np.minimum(np.maximum(y, problem.lo), problem.hi)


def _residuals(problem: Problem, s: FloatArray) -> list[float]:
    return [math.sqrt(max(v, 0.0)) for v in problem.G[1:].dot(s * s).tolist()]


def _gap(df: float, rho: float) -> float:
    """Bound on ``rho - rho*`` from a bound ``df`` on ``f - f*``: ``sqrt(rho^2 - 2 df)``."""
    if not df < math.inf:
        return math.inf
    room = rho * rho - 2.0 * max(df, 0.0)
    return rho - math.sqrt(room) if room > 0.0 else rho


# ---------------------------------------------------------------------- the polar projection
class _Polar:
    """DAQP's least-distance workspace of one problem: every row above the lowest level.

    Rows are read in place from the problem's buffer (the box as DAQP's simple bounds); the
    linear term ``f`` (a level's unit gradient) and the sides ``bu``, ``bl`` (0 on an active
    side, DAQP's infinity elsewhere) are written per level.
    """

    def __init__(self, problem: Problem, binding: DaqpBinding) -> None:
        n = problem.n
        self.m = m = problem.spans[-1][0]
        self.f = np.zeros(n)
        self.bu = np.full(m, _INF)
        self.bl = np.full(m, -_INF)
        self.binding = binding
        flag, _ = binding.setup(np.eye(n), self.f, problem.A[n:m], self.bu, self.bl,
                                np.zeros(m, dtype=np.intc), np.zeros(0, dtype=np.intc))
        self.ok = flag >= 0
        if self.ok:
            binding.settings = _LDP_SETTINGS


class Certifier:
    """The run-time optimality certificate (module docstring), one callable per solver.

    ``certifier(problem, x, s, residuals) -> Certificate``; keeps one DAQP workspace per
    problem it has seen (the last few).

    Args:
        level_tol: Relative tolerance deciding that a level is met.
        opt_tol: Relative tolerance on ``rho_k(x) - rho_k*`` of a certified level.
        freeze_tol: Freeze allowance of higher level rows, relative to ``max(1, |a_i x|)``.
        stat_tol: Round-off left of the residual on variables without a box, relative to the
            level's gradient.
        act_tol: Relative distance within which a side counts as active (any value is sound:
            the bound charges ``|lambda_i| delta_i`` for it).
        hard_tol: Relative tolerance of the box and hard rows.

    Attributes:
        open_binding: Makes the DAQP binding of each workspace (default
            :func:`~uvms_qp.hqp.backends.daqp_binding.open_daqp`).
    """

    def __init__(self, level_tol: float = LEVEL_TOL, opt_tol: float = OPT_TOL,
                 freeze_tol: float = FREEZE_TOL, stat_tol: float = STAT_TOL,
                 act_tol: float = ACT_TOL, hard_tol: float = HARD_TOL) -> None:
        self.level_tol, self.opt_tol, self.freeze_tol = level_tol, opt_tol, freeze_tol
        self.stat_tol, self.act_tol, self.hard_tol = stat_tol, act_tol, hard_tol
        self.open_binding: Callable[[], DaqpBinding] = open_daqp
        self._polars: dict[Problem, _Polar] = {}

    def reset(self) -> None:
        """Forget every workspace."""
        self._polars.clear()

    def _polar(self, problem: Problem) -> _Polar:
        polar = self._polars.get(problem)
        if polar is None:
            polar = _Polar(problem, self.open_binding())
            if len(self._polars) >= _KEEP:
                self._polars.pop(next(iter(self._polars)))
            self._polars[problem] = polar
        return polar

    def __call__(self, problem: Problem, x: FloatArray, s: FloatArray | None = None,
                 residuals: list[float] | None = None, hard_violation: float | None = None
                 ) -> Certificate:
        """The certificate of every level of ``x`` (see the module docstring).

        Args:
            problem: The problem (its buffers are read, never written).
            x: The answer, shape (n,).
            s: ``slacks(problem, x)`` when the caller has them (the measurement's).
            residuals: The level residuals ``rho_k`` when the caller has them.
            hard_violation: ``max |s|`` over the box and hard rows when the caller has it.
        """
        n, p = problem.n, len(problem.sizes)
        x = np.asarray(x, dtype=np.float64)
        if x.shape != (n,) or not math.isfinite(float(x.dot(x))):
            return Certificate(tuple(LevelCertificate(k, UNPROVEN, math.inf, math.inf, math.inf)
                                     for k in range(p)), math.inf, False)
        if s is None:
            s = slacks(problem, x)
        if residuals is None:
            residuals = _residuals(problem, s)
        head, spans, level_tol = problem.head, problem.spans, self.level_tol
        hv = float(np.abs(s[:head]).max(initial=0.0)) if hard_violation is None else (
            hard_violation)
        inside = hv <= self.hard_tol or hv <= self.hard_tol * problem.hard_scale
        unmet, scales = [], []
        for k, r in enumerate(residuals):
            if r > level_tol:
                scale = problem.scale(*spans[k])
                if r > level_tol * scale:
                    unmet.append(k)
                    scales.append(scale)
        if not unmet:
            return Certificate(tuple(LevelCertificate(k, MET, r)
                                     for k, r in enumerate(residuals)), hv, inside)
        verdicts = self._levels(problem, x, s, residuals, unmet, scales)
        out = [verdicts.get(k) or LevelCertificate(k, MET, r) for k, r in enumerate(residuals)]
        return Certificate(tuple(out), hv, inside)

    def _levels(self, problem: Problem, x: FloatArray, s: FloatArray, residuals: list[float],
                unmet: list[int], scales: list[float]) -> dict[int, LevelCertificate]:
        """Verdicts of the unmet levels (the module docstring's bound, multipliers by DAQP)."""
        n, head, spans = problem.n, problem.head, problem.spans
        end = spans[unmet[-1]][0]  # constraint rows: everything above the lowest unmet level
        A = problem.A
        Ae = A[:end]
        y = Ae.dot(x)
        ay = np.abs(y)
        a = np.abs(s[:end])
        # distances to the frozen sides, [lower; upper] (inf where a side is missing)
        D = np.subtract(y, problem.sides[:, :end])
        D *= problem.signs[:, :end]
        D += a
        tol = ay * self.act_tol
        tol += self.act_tol
        act = tol >= D
        # every unmet level's gradient, and the size that makes it a unit vector for DAQP
        WS = problem.G[[k + 1 for k in unmet]]
        WS *= s
        grads = WS.dot(A)
        size = np.sqrt(np.einsum("ij,ij->i", grads, grads))
        np.maximum(size, 1e-300, out=size)
        polar = self._polar(problem)
        u = len(unmet)
        LAM = np.zeros((u, end))
        solved = [False] * u
        if polar.ok:
            # the active sides of every row above the lowest unmet level; the levels from the
            # lowest up, each switching off the rows of the level below it
            f, bu, bl, binding = polar.f, polar.bu, polar.bl, polar.binding
            bu[:end] = np.where(act[1], 0.0, _INF)
            bl[:end] = np.where(act[0], 0.0, -_INF)
            bu[end:] = _INF
            bl[end:] = -_INF
            top = end
            for i in range(u - 1, -1, -1):
                start = spans[unmet[i]][0]
                bu[start:top] = _INF
                bl[start:top] = -_INF
                top = start
                np.divide(grads[i], size[i], out=f)
                solved[i] = binding.solve_cold(i == u - 1) == 1
                if not solved[i]:
                    # DAQP can call a degenerate set of active rows (more than the free
                    # variables, nearly dependent) infeasible at a tight tolerance; a looser one
                    # only loosens the multipliers, which the bound then charges
                    binding.settings = _LDP_RETRY
                    solved[i] = binding.solve_cold(False) == 1
                    binding.settings = _LDP_SETTINGS
                if solved[i]:  # (a failed solve leaves DAQP's multipliers as they were)
                    LAM[i, :start] = binding.lam[:start]
        LAM *= size[:, None]
        width = problem.hi[:n] - problem.lo[:n]
        width += a[:n]
        boxed = bool(math.isfinite(float(width.sum())))  # every variable has a finite box
        unboxed = None if boxed else ~(width < math.inf)
        if unboxed is not None:
            width = np.where(unboxed, 0.0, width)
        bound = _Bound(Ae, grads, act, np.where(act, D, 0.0), width, np.maximum(ay, 1.0), head,
                       self.freeze_tol)
        R, _, df_act, freeze = bound(LAM)
        absR = np.abs(R)
        df = absR.dot(width)
        df += df_act
        stat = absR.max(axis=1).tolist()
        # a residual on a variable without a box is not bounded by a width: such a level is
        # settled by the level's own dual below
        loose: list[bool] = [False] * len(unmet)
        if unboxed is not None:
            loose = [bool(v) for v in np.any(absR[:, unboxed] > 0.0, axis=1).tolist()]
        dfl, frl = df.tolist(), freeze.tolist()
        out = {}
        opt_tol = self.opt_tol
        for i, k in enumerate(unmet):
            rho, tol_k = residuals[k], opt_tol * scales[i]
            verdict, gap = _verdict(dfl[i], frl[i], loose[i], rho, tol_k)
            if verdict == UNPROVEN:
                # the multipliers again by non-negative least squares on the same active sides
                # (DAQP's are accurate to its primal tolerance only, and its dual active set
                # can stall on a degenerate set: more active rows than free variables, rows
                # active on both sides); an unboxed residual left is then moved onto the
                # level's own rows
                R2, _, act2, fr2 = bound(_nnls(Ae, grads[i], act, spans[k][0]), [i])
                r, extra = R2[0], 0.0
                if unboxed is not None:
                    r, extra = _unboxed_dual(problem, k, s, r, unboxed)
                verdict2, gap2 = UNPROVEN, math.inf
                if r is not None:
                    ar = np.abs(r)
                    loose2 = unboxed is not None and bool(
                        (ar[unboxed] > self.stat_tol * float(np.abs(grads[i]).max())).any())
                    # (what the least-norm solve leaves: round-off, or a direction off the
                    # level's rows, which no dual of the level can absorb)
                    verdict2, gap2 = _verdict(float(ar.dot(width)) + float(act2[0]) + extra,
                                              float(fr2[0]), loose2, rho, tol_k)
                if gap2 < gap:
                    verdict, gap, stat[i] = verdict2, gap2, float(np.abs(r).max())
            out[k] = LevelCertificate(k, verdict, rho, stat[i], gap)
        return out


class _Bound:
    """The module docstring's bound for rows of multipliers (one row per unmet level).

    Args:
        Ae: Constraint rows (box, hard, levels above the lowest unmet one), shape (m, n).
        grads: Gradients of the unmet levels, shape (u, n).
        act: Rows whose [lower; upper] frozen side is active, shape (2, m).
        dist: Distances to the frozen sides where active (0 elsewhere), ``[lower; upper]``.
        width: Box width plus the box slack of each variable (0 where unboxed), shape (n,).
        big: ``max(1, |a_i x|)`` of each row, shape (m,).
        head: Box and hard rows (no freeze allowance).
        freeze_tol: The freeze allowance relative to ``big``.
    """

    def __init__(self, Ae: FloatArray, grads: FloatArray, act: np.ndarray, dist: FloatArray,
                 width: FloatArray, big: FloatArray, head: int, freeze_tol: float) -> None:
        self.Ae, self.grads, self.act, self.dist, self.width = Ae, grads, act, dist, width
        self.big, self.head, self.freeze_tol = big, head, freeze_tol

    def __call__(self, LAM: FloatArray, rows: list[int] | None = None
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``(r, signed multipliers, sum |lambda_i| delta_i, freeze allowance)`` per row of LAM.

        Multipliers of the wrong sign are dropped first (any multipliers of the right signs give
        a valid bound). ``rows`` picks the levels the rows of ``LAM`` belong to (default all).
        """
        grads = self.grads if rows is None else self.grads[rows]
        act, dist, head = self.act, self.dist, self.head
        pos = LAM > 0.0
        L = LAM * np.where(pos, act[1], act[0])  # a multiplier only on an active side
        absL = np.abs(L)
        R = L.dot(self.Ae)
        R += grads
        df_act = np.einsum("ij,ij->i", absL, np.where(pos, dist[1], dist[0]))
        freeze = absL[:, head:].dot(self.big[head:])
        freeze *= self.freeze_tol
        return R, L, df_act, freeze


def _nnls(Ae: FloatArray, g: FloatArray, act: np.ndarray, start: int) -> FloatArray:
    """Signed multipliers (1, m) of ``min |g + A' lambda|`` on the active sides of rows < start.

    One :func:`scipy.optimize.nnls` on unit columns (``+a`` at an upper side, ``-a`` at a lower
    one).
    """
    up = np.flatnonzero(act[1, :start])
    dn = np.flatnonzero(act[0, :start])
    lam = np.zeros((1, Ae.shape[0]))
    if not up.size + dn.size:
        return lam
    rows = np.concatenate((up, dn))
    norms = np.sqrt(np.einsum("ij,ij->i", Ae[rows], Ae[rows]))
    live = norms > 0.0
    rows, norms = rows[live], norms[live]
    sign = np.where(np.arange(live.size)[live] < up.size, 1.0, -1.0)
    coef, _ = nnls((Ae[rows] * (sign / norms)[:, None]).T, -g, maxiter=50 * max(rows.size, 10))
    np.add.at(lam[0], rows, sign * coef / norms)
    return lam


def _unboxed_dual(problem: Problem, k: int, s: FloatArray, r: FloatArray, unboxed: np.ndarray
                  ) -> tuple[FloatArray | None, float]:
    """Move the residual ``r`` on the unboxed variables onto level k's own multipliers.

    The level's QP dual: with multipliers ``mu = w s + delta`` on its rows (equality rows and
    violated inequality rows, signs kept), the duality gap grows by ``1/2 sum delta_i^2 / w_i``
    and the residual becomes ``r + A_k' delta``. ``delta`` is the least such change that makes
    the unboxed part vanish (a weighted least-norm solve); None when that leaves the unboxed
    part (the level can be improved along a direction no box limits) or flips a sign.

    Returns:
        ``(new residual or None, the gap's increase in f)``.
    """
    a0, b0 = problem.spans[k]
    h = problem.head
    Ak, w, sk = problem.A[a0:b0], problem.w[a0 - h:b0 - h], s[a0:b0]
    # equality rows, and inequality rows violated by more than round-off (a row at its side
    # to round-off keeps multiplier 0)
    rows = (problem.lo[a0:b0] == problem.hi[a0:b0]) | (
        np.abs(sk) > 1e-12 * problem.scale(a0, b0))
    if not rows.any():
        return None, math.inf
    root = np.sqrt(w[rows])
    M = Ak[rows][:, unboxed].T * root
    z = np.linalg.lstsq(M, -r[unboxed], rcond=None)[0]
    delta = root * z
    ineq = (problem.lo[a0:b0] != problem.hi[a0:b0])[rows]
    mu = w[rows] * sk[rows]
    if ((mu[ineq] + delta[ineq]) * mu[ineq] < 0.0).any():
        return None, math.inf  # an inequality row's multiplier would change side
    r2 = r + delta.dot(Ak[rows])
    return r2, 0.5 * float(z.dot(z))


def _verdict(df: float, freeze: float, loose: bool, rho: float, tol: float
             ) -> tuple[str, float]:
    """Verdict and gap bound of one level from its ``df`` and freeze allowance."""
    if loose:
        return UNPROVEN, math.inf
    gap = _gap(df + freeze, rho)
    if gap <= tol:
        return CERTIFIED, gap
    return (ILL_POSED if _gap(df, rho) <= tol else UNPROVEN), gap


# ------------------------------------------------------------------------------- certify
def certify(problem: Problem, x: FloatArray, s: FloatArray | None = None,
            residuals: list[float] | None = None, *, level_tol: float = LEVEL_TOL,
            opt_tol: float = OPT_TOL, freeze_tol: float = FREEZE_TOL,
            stat_tol: float = STAT_TOL, act_tol: float = ACT_TOL, hard_tol: float = HARD_TOL,
            exact: bool = False, deadline: float | None = None) -> Certificate:
    """Prove each level of ``x`` optimal, or say why not (see the module docstring).

    A one-off :class:`Certifier` (a solver keeps its own, with its DAQP workspaces).

    Args:
        problem: The problem (its buffers are read, never written).
        x: The answer, shape (n,).
        s: ``slacks(problem, x)`` when the caller has them.
        residuals: The level residuals ``rho_k`` when the caller has them.
        level_tol: Relative tolerance deciding that a level is met.
        opt_tol: Relative tolerance on ``rho_k(x) - rho_k*`` of a certified level.
        freeze_tol: Freeze allowance of higher level rows, relative to ``max(1, |a_i x|)``.
        stat_tol: Round-off left of the residual on variables without a box.
        act_tol: Relative distance within which a side counts as active.
        hard_tol: Relative tolerance of the box and hard rows.
        exact: Settle a level the multipliers cannot certify with its exact optimum over the
            frozen set (``improvable`` with the witness, or ``certified``); False leaves it
            ``unproven`` (the run-time path, whose repair does the exact solves).
        deadline: ``time.perf_counter()`` value after which exact solves give up.

    Returns:
        The :class:`Certificate`; levels are judged against the frozen set at ``x`` whatever
        the verdicts above them.
    """
    cert = Certifier(level_tol, opt_tol, freeze_tol, stat_tol, act_tol, hard_tol)(
        problem, x, s, residuals)
    if not exact or cert.ok or not cert.inside:
        return cert
    x = np.asarray(x, dtype=np.float64)
    levels = []
    for c in cert.levels:
        if not c.ok and c.verdict != ILL_POSED:
            scale = problem.scale(*problem.spans[c.level])
            c = _settle(problem, x, c, opt_tol, scale, deadline)
        levels.append(c)
    return Certificate(tuple(levels), cert.hard_violation, cert.inside)


# ------------------------------------------------------------------------ exact level solves
class _Frozen:
    """The frozen set of every row at ``x`` (exact solves; not the run-time path)."""

    def __init__(self, problem: Problem, x: FloatArray) -> None:
        self.problem, self.x = problem, x
        y = problem.A.dot(x)
        s = y - np.minimum(np.maximum(y, problem.lo), problem.hi)
        a = np.abs(s)
        self.y, self.s = y, s
        self.lo_f, self.hi_f = problem.lo - a, problem.hi + a
        self.norms = np.sqrt(np.einsum("ij,ij->i", problem.A, problem.A))

    def residual(self, k: int) -> float:
        a, b = self.problem.spans[k]
        h = self.problem.head
        sk = self.s[a:b]
        return math.sqrt(float(self.problem.w[a - h:b - h].dot(sk * sk)))

    def keeps(self, other: _Frozen, k: int, tol: float = 1e-9) -> bool:
        """True when ``other.x`` lies in the frozen set of level k taken here (to ``tol``)."""
        P = self.problem.spans[k][0]
        y = other.y[:P]
        rel = tol * (1.0 + np.abs(self.y[:P]))
        return bool(np.all((y <= self.hi_f[:P] + rel) & (y >= self.lo_f[:P] - rel)))


def _level_qp(fr: _Frozen, k: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray,
                                              FloatArray, FloatArray, FloatArray]:
    """Level k's QP over ``z = [x; t]`` on the frozen set at ``fr.x``.

    ``min 1/2 z' H z + c' z`` with ``H = diag(A_e' W_e A_e, W_i)``, ``c = [-A_e' W_e b; 0]``
    (equality rows ``e`` of level k in x, one slack ``t_i`` per inequality row ``i``, kept by
    ``lo_i <= a_i x - t_i <= hi_i``), equalities ``E z = e`` (rows whose frozen sides coincide:
    hard equalities, higher equality rows met exactly) and inequalities ``G z <= h`` (the frozen
    sides of every other box, hard and higher-level row, level k's inequality rows). Every
    constraint row is normalised. Returns ``(H, c, E, e, G, h, z0)``.
    """
    problem = fr.problem
    n, head = problem.n, problem.head
    a, b = problem.spans[k]
    Ak, lok, hik = problem.A[a:b], problem.lo[a:b], problem.hi[a:b]
    wk = problem.w[a - head:b - head]
    eqk = lok == hik
    ine = np.flatnonzero(~eqk)
    q = ine.size
    # rows scaled by sqrt(w): H keeps the weights without squaring their spread twice
    Ae, be, we = Ak[eqk], lok[eqk], wk[eqk]
    H = np.zeros((n + q, n + q))
    H[:n, :n] = Ae.T.dot(we[:, None] * Ae)
    H[n:, n:] = np.diag(wk[ine])
    c = np.zeros(n + q)
    c[:n] = -Ae.T.dot(we * be)
    P = a
    live = fr.norms[:P] > 0.0
    lo_f, hi_f, nrm = fr.lo_f[:P], fr.hi_f[:P], fr.norms[:P]
    unit = problem.A[:P] / np.where(live, nrm, 1.0)[:, None]
    pinned = lo_f == hi_f
    pin = np.flatnonzero(live & pinned)
    E = np.hstack((unit[pin], np.zeros((pin.size, q))))
    e = lo_f[pin] / nrm[pin]
    rest = np.flatnonzero(live & ~pinned)
    G_rows, h_rows = [], []
    for side, sign in ((hi_f, 1.0), (lo_f, -1.0)):
        cut = rest[np.isfinite(side[rest])]
        G_rows.append(np.hstack((sign * unit[cut], np.zeros((cut.size, q)))))
        h_rows.append(sign * side[cut] / nrm[cut])
    if q:
        Ai = Ak[ine]
        ni = np.sqrt(np.einsum("ij,ij->i", Ai, Ai) + 1.0)
        T = -np.eye(q)
        for side, sign in ((hik[ine], 1.0), (lok[ine], -1.0)):
            cut = np.isfinite(side)
            G_rows.append(sign * np.hstack((Ai[cut], T[cut])) / ni[cut, None])
            h_rows.append(sign * side[cut] / ni[cut])
    G = np.vstack(G_rows)
    h = np.concatenate(h_rows)
    z0 = np.concatenate((fr.x, fr.s[a:b][ine]))
    return H, c, E, e, G, h, z0


def level_optimum(problem: Problem, x: FloatArray, k: int, deadline: float | None = None,
                  clock: Callable[[], float] = perf_counter) -> FloatArray | None:
    """Exact optimum of level k over its frozen set at ``x`` (None when the solve fails).

    One :func:`uvms_qp.hqp.kkt.active_set` solve started at ``x`` (feasible by construction);
    the answer is clipped into the box (the steps land on it to round-off). ``deadline`` is a
    reading of ``clock`` [s] after which the solve gives up.
    """
    fr = _Frozen(problem, np.asarray(x, dtype=np.float64))
    H, c, E, e, G, h, z0 = _level_qp(fr, k)
    # from a feasible, usually nearly optimal start: a few exchanges of the working set; the
    # cap keeps a degenerate case from grinding (it fails, and is reported unproven)
    z = active_set(H, c, E, e, G, h, z0, max_iter=3 * z0.size + 20,
                   deadline=deadline, clock=clock)
    if z is None:
        return None
    return np.minimum(np.maximum(z[:problem.n], problem.lower), problem.upper)


def _settle(problem: Problem, x: FloatArray, c: LevelCertificate, opt_tol: float, scale: float,
            deadline: float | None) -> LevelCertificate:
    """The exact verdict on level k: the optimum of its frozen set, compared with ``x``."""
    k, rho = c.level, c.residual
    better = level_optimum(problem, x, k, deadline)
    if better is None:
        return c
    fr = _Frozen(problem, x)
    sub = _Frozen(problem, better)
    if not fr.keeps(sub, k):
        return c
    inner = Certifier(level_tol=0.0, opt_tol=opt_tol)(problem, better)
    if inner.levels[k].verdict not in (CERTIFIED, ILL_POSED, MET):
        return c
    diff = rho - sub.residual(k)
    if diff <= opt_tol * scale:
        return LevelCertificate(k, CERTIFIED, rho, c.stationarity, max(diff, 0.0), better,
                                max(diff, 0.0))
    return LevelCertificate(k, IMPROVABLE, rho, c.stationarity, diff, better, diff)


# --------------------------------------------------------------------------------- repair
def repair(problem: Problem, x: FloatArray, certificate: Certificate | None = None, *,
           certifier: Certifier | None = None, deadline: float | None = None,
           clock: Callable[[], float] = perf_counter) -> Repair:
    """Make a certified answer from ``x``: exact level solves from the first failing level down.

    Every unmet level, from the highest, and the first level neither met nor certified, is
    solved exactly over its frozen set at the current point (:func:`level_optimum`, started at
    that point, which is feasible, so a nearly optimal level takes an iteration or two); the
    result is certified again. No level moves beyond the frozen set of the levels above it: a
    repair never costs a higher level anything.

    Args:
        problem: The problem.
        x: The answer to repair, inside the hard set.
        certificate: The certificate of ``x`` when the caller has it.
        certifier: The certificate to use (a solver's, with its workspaces and tolerances;
            default a :class:`Certifier` with the default tolerances).
        deadline: Reading of ``clock`` [s] after which the repair gives up.
        clock: The clock of ``deadline`` (default :func:`time.perf_counter`).

    Returns:
        The :class:`Repair`: ``repaired`` True with a certified ``x``, or the input ``x`` with
        its certificate and a message saying why it could not be repaired.
    """
    x = np.asarray(x, dtype=np.float64)
    certifier = certifier or Certifier()
    level_tol = certifier.level_tol
    cert = certificate or certifier(problem, x)
    if cert.ok:
        return Repair(x, cert, False, "already certified")
    if not cert.inside:
        return Repair(x, cert, False, "x is not inside the hard set")
    first = cert.first_failure
    assert first is not None  # not ok and inside: some level failed
    z = x.copy()
    for k in range(len(problem.sizes)):
        if k != first and _Frozen(problem, z).residual(k) <= level_tol * problem.scale(
                *problem.spans[k]):
            continue  # a met level keeps its point
        # every unmet level from the top: a certified level is optimal to the tolerance, not
        # exactly, and the exact solves below would otherwise trade its rows within their
        # frozen bands (its value kept, its stationarity lost)
        better = level_optimum(problem, z, k, deadline, clock)
        if better is None:
            late = deadline is not None and clock() > deadline
            return Repair(x, cert, False, f"the exact solve of level {k} "
                          + ("ran out of time" if late else "failed"))
        z = better
    new = certifier(problem, z)
    if new.ok:
        return Repair(z, new, True, f"repaired from level {first}")
    if new.inside and new.ill_posed:  # the exact optimum, not provably robust: kept, said so
        return Repair(z, new, False, "the repaired point: " + new.reason())
    return Repair(x, cert, False, "the repaired point: " + new.reason())
