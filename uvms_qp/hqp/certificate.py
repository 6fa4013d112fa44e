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

    f_k(x) - f_k(x*) <= sum_j |r_j| (width_j + 2 |s_j|) + sum_i |lambda_i| (delta_i + eps_i) =: df,

with ``r = g + A_act' lambda``, ``width_j`` the box width of variable ``j`` (``width_j + 2 |s_j|``
the distance between its frozen sides, at least ``|x_j - x*_j|``), ``delta_i`` the
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
multipliers are the ``lambda`` above. Each level has its own DAQP workspace reading the box
and the rows above the level in place (the rows a controller writes every tick). Per answer, a
fixed sequence of numpy calls on contiguous buffers gives ``A x``, every distance to a frozen
side (a missing side gets the finite stand-in ``1e150``, and a multiplier on such a side, or a
residual on a variable without a box, fails the bound), the box widths, the freeze allowances
and each unmet level's gradient; the bounds of all levels come from one product of the
multipliers with ``[distances; allowances; missing sides]`` and two more with the rows and
``[widths; missing boxes]``. A closed loop's active sides
hardly change between ticks, so each level first tries only the sides that carried the
multipliers of its latest certified answer, DAQP starting from its latest working set (two C
calls); only a level these leave uncertified gets a cold solve on every active side (the sides
within ``act_tol`` of the frozen set), and a level those leave unproven gets them once more by
non-negative least squares on the same active sides (DAQP's dual active set can stall on a
degenerate set: more active sides than free variables, rows active on both sides). Either way
the verdict is the bound's, whatever the multipliers. Levels met to tolerance cost nothing, and
an answer whose levels are all met is not looked at. Measured in
``benchmarks/bench_certificate.py``.

:func:`repair` starts from an answer whose certificate fails and solves the first failing level
and every level below it exactly (:func:`uvms_qp.hqp.kkt.active_set` on each level's frozen set,
started at the current point), then certifies the result again.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from operator import itemgetter
from time import perf_counter
from typing import Any, NamedTuple, Protocol

import numpy as np

from .._validation import FloatArray
from .kkt import active_set
from .linalg import nnls, one_blas_thread
from .problem import Problem
from .tolerances import ACTIVE_TOL, FREEZE_TOL, HARD_TOL, LEVEL_TOL, OPT_TOL, STAT_TOL

#: Verdicts of one level.
MET = "met"
CERTIFIED = "certified"
ILL_POSED = "ill_posed"
IMPROVABLE = "improvable"
UNPROVEN = "unproven"
LATE = "late"
#: The verdicts that prove a level (``LevelCertificate.ok``).
_PROVEN = frozenset((MET, CERTIFIED))
_VERDICT = itemgetter(1)  # a LevelCertificate's verdict (one C call per level, no frame)

#: DAQP's settings for the least-distance problems (H = I needs no proximal term)
_LDP_SETTINGS = {"primal_tol": 1e-8, "eps_prox": 0.0, "iter_limit": 2000, "time_limit": 0.0}
_LDP_RETRY = {**_LDP_SETTINGS, "primal_tol": 1e-6}
_INF = 1e30  # DAQP's infinity
_SIDES = np.array([[-_INF], [_INF]])  # DAQP's sides of a free [lower; upper] side
_BIG = 1e150  # finite stand-in for the distance to a missing side (no overflow times |lambda|)
_KEEP = 8  # workspaces kept (the problems a solver alternates between: full, relaxed)


class LevelCertificate(NamedTuple):
    """The verdict on one level (a named tuple: cheap to make on every control tick).

    Attributes:
        level: Level index (0 = highest priority).
        verdict: One of ``met``, ``certified``, ``ill_posed``, ``improvable``, ``unproven``
            (module docstring), or ``late`` (the solve's end passed before the level was
            examined: not proven).
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
        return self.verdict in _PROVEN


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
        return self.inside and _PROVEN.issuperset(map(_VERDICT, self.levels))

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
        if c.verdict == LATE:
            return f"level {k} is not proven optimal: the deadline passed before it was examined"
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


# ------------------------------------------------------------------- the least-distance solver
class LeastDistance(Protocol):
    """A least-distance QP workspace (``min 1/2 |d|^2 + f'd`` on two-sided rows and bounds).

    Handed to :class:`Certifier` by its owner (a solver hands DAQP's binding,
    :class:`~uvms_qp.hqp.backends.daqp_binding.NativeDaqp`); the certificate imports no solver.
    ``setup`` keeps the arrays it is given and re-reads them on every ``solve_ldp``; ``lam``
    holds the multipliers of the latest solve (> 0 at an upper side, < 0 at a lower one).
    """

    lam: FloatArray

    def setup(self, H: FloatArray, f: FloatArray, A: FloatArray, bupper: FloatArray,
              blower: FloatArray, sense: np.ndarray, break_points: np.ndarray
              ) -> tuple[int, float]:
        """Set the problem up on these arrays; a negative flag means it cannot be solved."""

    @property
    def settings(self) -> dict[str, Any]:
        """The solver's settings (assign a dict to change some)."""

    @settings.setter
    def settings(self, new: dict[str, Any]) -> None: ...

    def solve_ldp(self, rows: bool, warm: bool) -> int:
        """Re-read ``f`` and the sides (and the rows) and solve; 1 when solved.

        ``warm``: start from the working set of the latest solve.
        """


# ---------------------------------------------------------------------- the polar projection
class _Polar:
    """DAQP's least-distance workspace of one level: the box and every row above the level.

    The rows are read in place from the problem's buffer (the box as DAQP's simple bounds); the
    linear term ``f`` (the level's unit gradient) is written per answer, the sides
    ``B = [bl; bu]`` (0 on a side the multipliers may use, DAQP's infinity elsewhere) only when
    they change. ``support`` says that ``B`` holds the sides that carried the multipliers of
    the level's latest certified answer (the next answer tries them first), ``warm`` that DAQP's
    working set belongs to the current ``B`` (the next solve may start from it).

    Args:
        problem: The problem.
        k: The level.
        binding: A fresh DAQP binding.
        work: The problem's :class:`_Work` (the level's rows of its buffers are used).
    """

    def __init__(self, problem: Problem, k: int, binding: LeastDistance, work: _Work) -> None:
        n, head = problem.n, problem.head
        start, end = problem.spans[k]
        self.f = np.zeros(n)
        self.B = np.empty((2, start))
        self.B[0], self.B[1] = -_INF, _INF
        self.binding = binding
        self.support = self.warm = False
        self.rows = problem.A[start:end]  # the level's own rows and weighted slacks
        self.weighted = work.weighted[start - head:end - head]
        self.grad = work.grads[k]
        self.lam = work.LAMT[:start, k]
        self.free = work.free[:, :start]
        self.size = np.zeros(())  # the gradient's norm (a 0-d array: no conversion per call)
        flag, _ = binding.setup(np.eye(n), self.f, problem.A[n:start], self.B[1], self.B[0],
                                np.zeros(start, dtype=np.intc), np.zeros(0, dtype=np.intc))
        self.ok = flag >= 0
        if self.ok:
            binding.settings = _LDP_SETTINGS

    def gradient(self) -> float:
        """The level's gradient ``A_k' (w_k s_k)`` into its row of ``grads``; returns its norm."""
        g = self.weighted.dot(self.rows, out=self.grad)
        size = math.sqrt(g.dot(g))
        return size if size > 1e-300 else 1e-300

    def solve(self, size: float) -> bool:
        """Multipliers of ``min 1/2 |d|^2 + g'd / size`` on the sides ``B``, times ``size``.

        Written into the level's column of ``LAMT``; False (the column left as it was) when
        DAQP fails.
        """
        self.size[()] = size
        np.divide(self.grad, self.size, out=self.f)
        binding = self.binding
        flag = binding.solve_ldp(True, self.warm)
        self.warm = True
        if flag != 1:
            return False
        np.multiply(binding.lam, self.size, out=self.lam)
        return True

    def set_sides(self, sides: np.ndarray) -> None:
        """``B`` from a (2, start) mask of [lower; upper] sides the multipliers may not use."""
        np.multiply(sides, _SIDES, out=self.B)
        self.support = self.warm = False

    def keep_support(self) -> None:
        """Make the sides of the current multipliers the ones the next answer tries first."""
        lam = self.lam
        self.set_sides(np.vstack((lam >= 0.0, lam <= 0.0)))
        self.support = self.ok


class _Work:
    """The certificate's buffers for one problem, and one :class:`_Polar` per level.

    Rows are those above the lowest level (``m``), read in place; every array has a fixed shape
    and every per-answer operation is on contiguous memory, so that an answer costs a short,
    fixed sequence of numpy calls.
    """

    def __init__(self, problem: Problem, freeze_tol: float) -> None:
        n, p, head, M = problem.n, len(problem.sizes), problem.head, problem.M
        m = problem.spans[-1][0]
        self.rows = problem.A[:m]
        self.lo, self.hi = problem.lo[:m], problem.hi[:m]
        self.y = np.empty(m)  # A x
        self.ay = np.empty(m)  # |A x|
        self.a = np.empty(M)  # |s|
        self.a_m = self.a[:m]
        self.ones = np.ones(m)
        self.big = np.full(2 * m, _BIG)
        # [distances to the frozen lower sides, to the upper ones; the freeze allowance twice],
        # against the multipliers split into [lower parts; upper parts]
        self.V = V = np.zeros((3, 2 * m))
        self.dist, self.dist_lo, self.dist_up = V[0], V[0, :m], V[0, m:]
        self.dist2 = V[0].reshape(2, m)
        self.allow_lo, self.allow_up = V[1, :m], V[1, m:]
        self.missing = V[2]  # 1 on a side at or beyond _BIG (none, in practice)
        self.allow_scale = np.full(m, freeze_tol)
        self.allow_scale[:head] = 0.0  # no allowance on the box and hard rows
        self.box_lo, self.box_up = V[0, :n], V[0, m:m + n]
        self.WU = np.zeros((2, n))  # [widths; 1 where a variable has no box]
        self.width, self.unboxed = self.WU[0], self.WU[1]
        self.big_n = self.big[:n]
        self.weighted = np.empty(M - head)  # w s on the level rows
        self.grads = np.zeros((p, n))  # (rows of met levels: stale or 0, never read)
        self.LAMT = np.zeros((m, p))  # signed multipliers, one column per level
        self.split = np.zeros((2 * m, p))
        self.lower, self.upper = self.split[:m], self.split[m:]
        self.zeros = np.zeros((m, p))
        self.R = np.empty((p, n))
        self.absR = np.empty((p, n))
        self.out = np.empty((6, p))
        self.out_lam, self.out_width, self.out_stat = self.out[:3], self.out[3:5], self.out[5]
        self.tol = np.empty(m)
        self.free = np.empty((2, m), dtype=bool)  # sides not active
        self.polars: list[_Polar | None] = [None] * p

    def prepare(self, problem: Problem, x: FloatArray, s: FloatArray) -> None:
        """Distances to the frozen sides, box widths and freeze allowances at ``x``.

        A missing side's distance becomes a finite stand-in ``_BIG`` (a missing side never
        carries a multiplier, and one it carried would be charged that much), and so does a
        missing box width: a variable whose width is at least ``_BIG`` has no box.
        """
        y = self.rows.dot(x, out=self.y)
        np.abs(s, out=self.a)
        a_m = self.a_m
        np.subtract(y, self.lo, out=self.dist_lo)
        np.add(self.dist_lo, a_m, out=self.dist_lo)
        np.subtract(self.hi, y, out=self.dist_up)
        np.add(self.dist_up, a_m, out=self.dist_up)
        np.minimum(self.dist, self.big, out=self.dist)
        np.greater_equal(self.dist, self.big, out=self.missing)
        np.add(self.box_lo, self.box_up, out=self.width)  # hi - lo + 2 |s| of each variable
        np.greater_equal(self.width, self.big_n, out=self.unboxed)
        np.abs(y, out=self.ay)
        np.maximum(self.ay, self.ones, out=self.allow_lo)
        np.multiply(self.allow_lo, self.allow_scale, out=self.allow_lo)
        self.allow_up[...] = self.allow_lo
        np.multiply(problem.w, s[problem.head:], out=self.weighted)

    def bound(self) -> list[list[float]]:
        """The bound's parts for the multipliers in ``LAMT``, one entry per level.

        Returns:
            ``[sum |lambda_i| delta_i, sum |lambda_i| eps_i, sum |lambda_i| on missing sides,
            sum |r_j| width_j, sum |r_j| on variables without a box, max |r_j|]`` (``r = g +
            A' lambda`` is left in ``R``, ``|r|`` in ``absR``). The first and fourth are the
            bound only where the third and fifth are 0 (widths and distances at or beyond
            ``_BIG`` are stand-ins).
        """
        R = self.LAMT.T.dot(self.rows, out=self.R)
        np.add(R, self.grads, out=R)
        absR = np.abs(R, out=self.absR)
        np.maximum(self.LAMT, self.zeros, out=self.upper)
        np.subtract(self.upper, self.LAMT, out=self.lower)
        self.V.dot(self.split, out=self.out_lam)
        self.WU.dot(absR.T, out=self.out_width)
        np.maximum.reduce(absR, axis=1, out=self.out_stat)
        return self.out.tolist()


class Certifier:
    """The run-time optimality certificate (module docstring), one callable per solver.

    ``certifier(problem, x, s, residuals, hard_violation, level_scales) -> Certificate``;
    keeps the buffers and DAQP workspaces of each problem it has seen (the last few), and per
    level the sides that carried the multipliers of its latest certified answer (tried first
    on the next answer).

    Args:
        least_distance: Makes the least-distance workspace of each level (a solver passes
            :func:`~uvms_qp.hqp.backends.daqp_binding.open_daqp`: DAQP's own problem class).
        level_tol: Relative tolerance deciding that a level is met.
        opt_tol: Relative tolerance on ``rho_k(x) - rho_k*`` of a certified level.
        freeze_tol: Freeze allowance of higher level rows, relative to ``max(1, |a_i x|)``.
        stat_tol: Round-off left of the residual on variables without a box, relative to the
            level's gradient.
        act_tol: Relative distance within which a side counts as active (any value is sound:
            the bound charges ``|lambda_i| delta_i`` for it).
        hard_tol: Relative tolerance of the box and hard rows.

    Attributes:
        least_distance: As given (replace it to observe or fault the workspaces).
        end: Reading of ``clock`` [s] after which the levels not yet settled are left
            ``unproven`` (a solver sets it before each solve; ``inf``: none).
        clock: The clock of ``end``.
    """

    def __init__(self, least_distance: Callable[[], LeastDistance], level_tol: float = LEVEL_TOL,
                 opt_tol: float = OPT_TOL, freeze_tol: float = FREEZE_TOL,
                 stat_tol: float = STAT_TOL, act_tol: float = ACTIVE_TOL,
                 hard_tol: float = HARD_TOL) -> None:
        self.least_distance = least_distance
        self.level_tol, self.opt_tol, self.freeze_tol = level_tol, opt_tol, freeze_tol
        self.stat_tol, self.act_tol, self.hard_tol = stat_tol, act_tol, hard_tol
        self.end = math.inf
        self.clock: Callable[[], float] = perf_counter
        self._works: dict[Problem, _Work] = {}

    def reset(self) -> None:
        """Forget every workspace."""
        self._works.clear()

    def _work(self, problem: Problem) -> _Work:
        work = self._works.get(problem)
        if work is None:
            work = _Work(problem, self.freeze_tol)
            if len(self._works) >= _KEEP:
                self._works.pop(next(iter(self._works)))
            self._works[problem] = work
        return work

    def __call__(self, problem: Problem, x: FloatArray, s: FloatArray | None = None,
                 residuals: list[float] | None = None, hard_violation: float | None = None,
                 level_scales: Sequence[float | None] | None = None) -> Certificate:
        """The certificate of every level of ``x`` (see the module docstring).

        Args:
            problem: The problem (its buffers are read, never written).
            x: The answer, shape (n,).
            s: ``slacks(problem, x)`` when the caller has them (the measurement's).
            residuals: The level residuals ``rho_k`` when the caller has them.
            hard_violation: ``max |s|`` over the box and hard rows when the caller has it
                (``inf`` when one is not finite); finite, with ``s``, it also says that ``x`` is
                finite (the box rows are the identity: ``s`` of a non-finite ``x_j`` is inf or
                NaN).
            level_scales: Per level ``problem.level_scale(k)`` where the caller has it, else None
                (the measurement's, for the levels above its bare tolerance).
        """
        n, p = problem.n, len(problem.sizes)
        x = np.asarray(x, dtype=np.float64)
        # x is finite when the caller's slacks of the box rows are (a finite hard violation
        # with its slacks, as the measurement hands them on); else it is checked here
        if x.shape != (n,) or not (
                (s is not None and hard_violation is not None and hard_violation < math.inf)
                or math.isfinite(float(x.dot(x)))):
            return Certificate(tuple(LevelCertificate(k, UNPROVEN, math.inf, math.inf, math.inf)
                                     for k in range(p)), math.inf, False)
        if s is None:
            s = slacks(problem, x)
        if residuals is None:
            residuals = _residuals(problem, s)
        level_tol = self.level_tol
        hv = float(np.abs(s[:problem.head]).max(initial=0.0)) if hard_violation is None else (
            hard_violation)
        inside = hv <= self.hard_tol or hv <= self.hard_tol * problem.hard_scale
        unmet, scales = [], []
        for k, r in enumerate(residuals):
            if r > level_tol:
                scale = level_scales[k] if level_scales is not None else None
                if scale is None:
                    scale = problem.level_scale(k)
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
        """Verdicts of the unmet levels (the module docstring's bound, multipliers by DAQP).

        Each level first tries the sides that carried the multipliers of its latest certified
        answer (DAQP started from its latest working set); a level these do not certify gets
        multipliers on every active side (:meth:`_active`).
        """
        work = self._work(problem)
        work.prepare(problem, x, s)
        polars, opt_tol = work.polars, self.opt_tol
        sizes, tried, out = [], [], {}
        for k in unmet:
            polar = polars[k]
            if polar is None:
                polar = polars[k] = _Polar(problem, k, self.least_distance(), work)
            size = polar.gradient()
            sizes.append(size)
            if polar.support:
                polar.support = polar.solve(size)
                tried.append(polar.support)
            else:
                tried.append(False)
        rest = []
        if any(tried):
            charge, allow, missing, wide, unboxed, stat = work.bound()
            for i, k in enumerate(unmet):
                if tried[i] and not missing[k] and not unboxed[k]:
                    tol_k = opt_tol * scales[i]
                    verdict, gap = _verdict(charge[k] + wide[k], allow[k], False, residuals[k],
                                            tol_k)
                    if verdict == CERTIFIED:
                        out[k] = LevelCertificate(k, verdict, residuals[k], stat[k], gap)
                        continue
                rest.append(i)
        else:
            rest = list(range(len(unmet)))
        if rest:
            if self.clock() > self.end:  # no time for the cold solves: not proven
                for i in rest:
                    k = unmet[i]
                    out[k] = LevelCertificate(k, LATE, residuals[k], math.inf, math.inf)
                return out
            with one_blas_thread:
                self._active(problem, work, s, residuals, unmet, rest, sizes, scales, out)
        return out

    def _active(self, problem: Problem, work: _Work, s: FloatArray, residuals: list[float],
                unmet: list[int], rest: list[int], sizes: list[float], scales: list[float],
                out: dict[int, LevelCertificate]) -> None:
        """Verdicts of the levels ``unmet[i], i in rest`` with multipliers on every active side.

        DAQP on the active sides of the rows above each level; a level these multipliers leave
        unproven gets them once more by non-negative least squares (DAQP's dual active set can
        stall on a degenerate set: more active sides than free variables, rows active on both
        sides), and an unboxed residual left is then moved onto the level's own rows.
        """
        tol = np.multiply(work.ay, self.act_tol, out=work.tol)
        tol += self.act_tol
        np.less(tol, work.dist2, out=work.free)
        polars = work.polars
        for i in rest:
            polar = polars[unmet[i]]
            assert polar is not None
            polar.set_sides(polar.free)
            solved = polar.ok and polar.solve(sizes[i])
            if polar.ok and not solved:
                # DAQP can call a degenerate set of active rows (more than the free variables,
                # nearly dependent) infeasible at a tight tolerance; a looser one only loosens
                # the multipliers, which the bound then charges
                binding = polar.binding
                binding.settings = _LDP_RETRY
                polar.warm = False
                solved = polar.solve(sizes[i])
                binding.settings = _LDP_SETTINGS
            if not solved:
                polar.lam.fill(0.0)
        charge, allow, missing, wide, loose_r, stat = work.bound()
        width = work.width
        unboxed = None if float(np.maximum.reduce(width)) < _BIG else width >= _BIG
        retry = []
        for i in rest:
            k = unmet[i]
            rho, tol_k = residuals[k], self.opt_tol * scales[i]
            # a residual on a variable without a box is not bounded by a width: such a level
            # is settled by the level's own dual below
            df, loose = charge[k] + wide[k], missing[k] > 0.0 or loose_r[k] > 0.0
            if unboxed is not None:
                df = charge[k] + float(work.absR[k][~unboxed].dot(width[~unboxed]))
            verdict, gap = _verdict(df, allow[k], loose, rho, tol_k)
            out[k] = LevelCertificate(k, verdict, rho, stat[k], gap)
            if verdict == CERTIFIED:
                polars[k].keep_support()  # type: ignore[union-attr]
            elif verdict == UNPROVEN:
                retry.append(i)
        if not retry or self.clock() > self.end:
            return
        # the multipliers again by non-negative least squares on the same active sides (DAQP's
        # are accurate to its primal tolerance only)
        act = ~work.free
        for i in retry:
            polar = polars[unmet[i]]
            assert polar is not None
            _nnls(work.rows, polar.grad, act, polar.lam)
        charge, allow, missing, wide, _, _ = work.bound()
        for i in retry:
            k = unmet[i]
            rho, tol_k, old = residuals[k], self.opt_tol * scales[i], out[k]
            r: FloatArray | None = work.R[k]
            extra = 0.0
            verdict, gap = UNPROVEN, math.inf
            if missing[k] > 0.0:
                pass  # (not from the active sides: a side at or beyond _BIG)
            elif unboxed is None:
                verdict, gap = _verdict(charge[k] + wide[k], allow[k], False, rho, tol_k)
            else:
                r, extra = _unboxed_dual(problem, k, s, work.R[k], unboxed)
                if r is not None:
                    ar = np.abs(r)
                    # (what the least-norm solve leaves: round-off, or a direction off the
                    # level's rows, which no dual of the level can absorb)
                    loose = bool((ar[unboxed] > self.stat_tol * float(
                        np.abs(work.grads[k]).max())).any())
                    verdict, gap = _verdict(
                        float(ar[~unboxed].dot(width[~unboxed])) + charge[k] + extra,
                        allow[k], loose, rho, tol_k)
            if gap < old.gap and r is not None:
                out[k] = LevelCertificate(k, verdict, rho, float(np.abs(r).max()), gap)
                if verdict == CERTIFIED:
                    polars[k].keep_support()  # type: ignore[union-attr]


def _nnls(A: FloatArray, g: FloatArray, act: np.ndarray, lam: FloatArray) -> None:
    """Signed multipliers of ``min |g + A' lambda|`` on the active sides, written into ``lam``.

    ``lam`` has one entry per leading row of ``A`` that may carry one (the rows above the
    level); one :func:`uvms_qp.hqp.linalg.nnls` on unit columns (``+a`` at an upper side, ``-a`` at
    a lower one).
    """
    start = lam.shape[0]
    up = np.flatnonzero(act[1, :start])
    dn = np.flatnonzero(act[0, :start])
    lam.fill(0.0)
    if not up.size + dn.size:
        return
    rows = np.concatenate((up, dn))
    norms = np.sqrt(np.einsum("ij,ij->i", A[rows], A[rows]))
    live = norms > 0.0
    rows, norms = rows[live], norms[live]
    sign = np.where(np.arange(live.size)[live] < up.size, 1.0, -1.0)
    coef, _ = nnls((A[rows] * (sign / norms)[:, None]).T, -g, 50 * max(rows.size, 10))
    np.add.at(lam, rows, sign * coef / norms)


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
        np.abs(sk) > 1e-12 * problem.level_scale(k))
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
            residuals: list[float] | None = None, *,
            least_distance: Callable[[], LeastDistance], level_tol: float = LEVEL_TOL,
            opt_tol: float = OPT_TOL, freeze_tol: float = FREEZE_TOL,
            stat_tol: float = STAT_TOL, act_tol: float = ACTIVE_TOL, hard_tol: float = HARD_TOL,
            exact: bool = False, deadline: float | None = None) -> Certificate:
    """Prove each level of ``x`` optimal, or say why not (see the module docstring).

    A one-off :class:`Certifier` (a solver keeps its own, with its workspaces).

    Args:
        problem: The problem (its buffers are read, never written).
        x: The answer, shape (n,).
        s: ``slacks(problem, x)`` when the caller has them.
        residuals: The level residuals ``rho_k`` when the caller has them.
        least_distance: Makes the least-distance workspaces (:class:`Certifier`).
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
    cert = Certifier(least_distance, level_tol, opt_tol, freeze_tol, stat_tol, act_tol,
                     hard_tol)(problem, x, s, residuals)
    if not exact or cert.ok or not cert.inside:
        return cert
    x = np.asarray(x, dtype=np.float64)
    levels = []
    with one_blas_thread:
        for c in cert.levels:
            if not c.ok and c.verdict != ILL_POSED:
                scale = problem.level_scale(c.level)
                c = _settle(problem, x, c, opt_tol, scale, deadline, least_distance)
            levels.append(c)
    return Certificate(tuple(levels), cert.hard_violation, cert.inside)


# ------------------------------------------------------------------------ exact level solves
class _Frozen:
    """The frozen set of every row at ``x`` (exact solves; not the run-time path)."""

    def __init__(self, problem: Problem, x: FloatArray) -> None:
        self.problem, self.x = problem, x
        y = problem.A.dot(x)
        s = y - np.minimum(np.maximum(y, problem.lo), problem.hi)  # (slacks, keeping A x)
        a = np.abs(s)
        self.y, self.s = y, s
        self.lo_f, self.hi_f = problem.lo - a, problem.hi + a
        self.norms = np.sqrt(np.einsum("ij,ij->i", problem.A, problem.A))
        self.residuals = _residuals(problem, s)

    def residual(self, k: int) -> float:
        """Level k's residual ``rho_k`` at ``x``."""
        return self.residuals[k]

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
                  clock: Callable[[], float] = perf_counter, best_effort: bool = False
                  ) -> FloatArray | None:
    """Exact optimum of level k over its frozen set at ``x`` (None when the solve fails).

    One :func:`uvms_qp.hqp.kkt.active_set` solve started at ``x`` (feasible by construction);
    the answer is clipped into the box (the steps land on it to round-off). ``deadline`` is a
    reading of ``clock`` [s] after which the solve gives up; with ``best_effort`` a solve that
    stagnates or stops early returns the point it reached (in the frozen set, the level no
    worse than at ``x``) instead of None.
    """
    fr = _Frozen(problem, np.asarray(x, dtype=np.float64))
    H, c, E, e, G, h, z0 = _level_qp(fr, k)
    # from a feasible, usually nearly optimal start: a few exchanges of the working set; the
    # cap keeps a degenerate case from grinding (it fails, and is reported unproven)
    z = active_set(H, c, E, e, G, h, z0, max_iter=3 * z0.size + 20,
                   deadline=deadline, clock=clock, best_effort=best_effort)
    if z is None:
        return None
    return np.minimum(np.maximum(z[:problem.n], problem.lower), problem.upper)


def _settle(problem: Problem, x: FloatArray, c: LevelCertificate, opt_tol: float, scale: float,
            deadline: float | None, least_distance: Callable[[], LeastDistance]
            ) -> LevelCertificate:
    """The exact verdict on level k: the optimum of its frozen set, compared with ``x``."""
    k, rho = c.level, c.residual
    better = level_optimum(problem, x, k, deadline)
    if better is None:
        return c
    fr = _Frozen(problem, x)
    sub = _Frozen(problem, better)
    if not fr.keeps(sub, k):
        return c
    inner = Certifier(least_distance, level_tol=0.0, opt_tol=opt_tol)(problem, better)
    if inner.levels[k].verdict not in (CERTIFIED, ILL_POSED, MET):
        return c
    diff = rho - sub.residual(k)
    if diff <= opt_tol * scale:
        return LevelCertificate(k, CERTIFIED, rho, c.stationarity, max(diff, 0.0), better,
                                max(diff, 0.0))
    return LevelCertificate(k, IMPROVABLE, rho, c.stationarity, diff, better, diff)


# --------------------------------------------------------------------------------- repair
def repair(problem: Problem, x: FloatArray, certificate: Certificate | None = None, *,
           certifier: Certifier, deadline: float | None = None,
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
        certifier: The certificate to use (a solver's, with its workspaces and tolerances).
        deadline: Reading of ``clock`` [s] after which the repair gives up.
        clock: The clock of ``deadline`` (default :func:`time.perf_counter`).

    Returns:
        The :class:`Repair`: ``repaired`` True with a certified ``x``, or the input ``x`` with
        its certificate and a message saying why it could not be repaired.
    """
    with one_blas_thread:
        return _repair(problem, np.asarray(x, dtype=np.float64), certificate,
                       certifier, deadline, clock)


def _repair(problem: Problem, x: FloatArray, certificate: Certificate | None,
            certifier: Certifier, deadline: float | None, clock: Callable[[], float]
            ) -> Repair:
    """:func:`repair` on one BLAS thread."""
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
        if k != first and _Frozen(problem, z).residual(k) <= level_tol * problem.level_scale(k):
            continue  # a met level keeps its point
        # every unmet level from the top: a certified level is optimal to the tolerance, not
        # exactly, and the exact solves below would otherwise trade its rows within their
        # frozen bands (its value kept, its stationarity lost)
        better = level_optimum(problem, z, k, deadline, clock, best_effort=True)
        if better is None:
            late = deadline is not None and clock() > deadline
            return Repair(x, cert, False, f"the exact solve of level {k} "
                          + ("ran out of time" if late else "failed"))
        z = better
        if deadline is not None and clock() > deadline:
            return Repair(x, cert, False, f"the deadline passed in the exact solve of level {k}")
    new = certifier(problem, z)
    if new.ok:
        return Repair(z, new, True, f"repaired from level {first}")
    if new.inside and new.ill_posed:  # the exact optimum, not provably robust: kept, said so
        return Repair(z, new, False, "the repaired point: " + new.reason())
    return Repair(x, cert, False, "the repaired point: " + new.reason())
