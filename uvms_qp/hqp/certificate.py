"""Optimality certificate of each level of a lexicographic answer, and its repair.

The problem is the stacked layout shared by every solver (``docs/developer.md``, "Problem"):
``n`` variables, rows ``A = [I_n; A_H; A_0; ...; A_{p-1}]`` of shape (M, n), sides ``lo``, ``hi``
(``-inf`` / ``+inf`` allowed, equality where ``lo == hi``), ``mh`` hard rows, level sizes and
level row weights ``w``. Level k's weighted violation is ``f_k(x) = 1/2 sum_i w_i s_i^2`` with
``s = A_k x - clip(A_k x, lo_k, hi_k)``; its residual is ``rho_k = sqrt(2 f_k)``.

What a certificate proves. Given an answer ``x`` inside the hard set, level k is optimal when no
point ``x'`` of the *frozen set* has a smaller ``f_k``: the box and hard rows hold and every row
of every higher level keeps at most the violation it has at ``x`` (``lo_i - |s_i| <= a_i x' <=
hi_i + |s_i|``, the lexicographic definition row by row). When a higher level is optimal this is
exactly the set of points that keep its optimum (its violations are unique), so level-by-level
certificates prove the lexicographic optimum. ``f_k`` is convex and continuously differentiable
with gradient ``g = A_k^T (w_k s_k)``, and the frozen set is a polyhedron, so x is optimal iff
``-g`` lies in the cone of the outward normals of the constraints active at x (one-sided: ``+a``
at a frozen upper side, ``-a`` at a frozen lower side; a row held at a value, such as an equality
row met exactly, is active on both sides, i.e. free in sign). The multipliers come from one
non-negative least-squares solve (:func:`scipy.optimize.nnls`, unit columns):

    lambda = argmin_{lambda >= 0} |g + N lambda|,   r = g + N lambda.

By Moreau's decomposition ``d = -r`` lies in the tangent cone of the frozen set (a feasible
direction) and ``g . d = -|r|^2``: when ``r != 0`` it is an improving feasible direction. For any
feasible ``x*``, convexity gives the a-posteriori bound

    f_k(x) - f_k(x*) <= sum_j |r_j| (upper_j - lower_j) + sum_i mu_i delta_i  =: df

(``delta_i`` the distance of a constraint counted as active to its side, ``mu_i`` its multiplier),
so ``rho_k(x) - rho_k* <= min(2 df / rho_k, sqrt(2 df))``. Level k is *certified* when this bound
is at most ``opt_tol * scale_k`` (``scale_k = max(1, max |finite side of level k|)``), the
stationarity residual on variables without a finite box is at round-off level
(``|r_j| <= stat_tol * scale_g``, ``scale_g = sum_i w_i |s_i| |a_i|``), and ``x`` itself lies in
the box. When the bound is inconclusive (a wide or missing box, an inexact answer), the exact
optimum ``x+`` of level k over the frozen set is computed by a primal active-set method started
at ``x`` and certified at round-off; level k is certified when ``rho_k(x) - rho_k(x+) <= opt_tol *
scale_k``, *improvable* (with ``x+`` as the witness) otherwise, and *unproven* when that solve
fails. Levels met to ``level_tol * scale_k`` need no certificate (``met``).

Cost: one ``A x`` and a few vectorised comparisons for the whole problem, then one NNLS per unmet
level on at most ``2 M`` columns of length ``n``; the active-set solve runs only when the bound is
inconclusive. Measured on the demo stack (n = 10, 31 level rows in 4 levels, box bounds) and on
random problems in ``benchmarks/bench_certificate.py``.

:func:`repair` starts from an answer whose certificate fails and solves the first failing level
and every level below it exactly (the same active-set method, frozen sets taken at the current
point), then certifies the result again.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from .._validation import FloatArray
from .problem import Problem

#: Verdicts of one level.
MET = "met"
CERTIFIED = "certified"
IMPROVABLE = "improvable"
UNPROVEN = "unproven"

#: default relative tolerance deciding that a level is met (the registry's ``level_tol``)
LEVEL_TOL = 1e-6
#: default relative tolerance on the residual gap ``rho_k(x) - rho_k*`` of a certified level
OPT_TOL = 1e-6
#: stationarity residual at round-off level, relative to ``scale_g``
STAT_TOL = 1e-9
#: relative distance ``act_tol (1 + |side|)`` within which a constraint counts as active
ACT_TOL = 1e-7
#: relative tolerance on the box and hard rows of an answer (``x`` must be inside)
HARD_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class LevelCertificate:
    """The verdict on one level.

    Attributes:
        level: Level index (0 = highest priority).
        verdict: ``"met"`` (residual within ``level_tol * scale``), ``"certified"`` (proven
            within ``opt_tol * scale`` of the best reachable), ``"improvable"`` (a better point
            of the frozen set is known) or ``"unproven"`` (neither could be shown).
        residual: ``rho_k(x)``, the weighted violation norm at x.
        stationarity: ``|r|_2``, the distance of ``-g`` to the cone of active normals (0 when
            met).
        gap: Upper bound on ``rho_k(x) - rho_k*`` (``inf`` when unknown): the a-posteriori bound,
            or the exact difference to the certified optimum ``x+``.
        direction: ``-r``, a feasible direction with ``g . d = -|r|^2`` (None when met).
        better: ``x+``, the certified optimum of the level over the frozen set, when computed.
        improvement: ``rho_k(x) - rho_k(x+)`` when ``better`` is known, else 0.
    """

    level: int
    verdict: str
    residual: float
    stationarity: float = 0.0
    gap: float = 0.0
    direction: FloatArray | None = None
    better: FloatArray | None = None
    improvement: float = 0.0

    @property
    def ok(self) -> bool:
        """True when the level is met or certified."""
        return self.verdict in (MET, CERTIFIED)


@dataclass(frozen=True, eq=False)
class Certificate:
    """Verdicts of every level at one answer.

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


@dataclass(frozen=True, eq=False)
class Repair:
    """Outcome of :func:`repair`.

    Attributes:
        x: The repaired point (the input when it was already certified or repair failed).
        certificate: Certificate of ``x``.
        repaired: True when ``x`` differs from the input and is certified.
        message: What happened, for a status message.
    """

    x: FloatArray
    certificate: Certificate
    repaired: bool
    message: str


def problem_arrays(problem: Problem) -> tuple[FloatArray, FloatArray, FloatArray, int, int,
                                             tuple[int, ...], FloatArray]:
    """The stacked layout ``(A, lo, hi, n, mh, sizes, w)`` of a :class:`Problem` (its buffers)."""
    return (problem.A, problem.lo, problem.hi, problem.n, problem.mh, problem.sizes,
            problem.w)


# ------------------------------------------------------------------------------------ certify
class _Frame:
    """Everything ``certify`` and ``repair`` measure once per answer.

    The frozen sides of every row are ``lo - |s|`` and ``hi + |s|`` (``s`` its violation at x):
    for box and hard rows ``s`` is round-off (x is inside), for the rows of a level they keep
    the violation the level has at x, which is how a higher level constrains a lower one.
    """

    def __init__(self, A: FloatArray, lo: FloatArray, hi: FloatArray, n: int, mh: int,
                 sizes: Sequence[int], w: FloatArray, x: FloatArray, act_tol: float,
                 frozen: _Frame | None = None) -> None:
        self.A, self.lo, self.hi, self.n, self.mh = A, lo, hi, int(n), int(mh)
        self.sizes = tuple(int(m) for m in sizes)
        self.w = w
        self.head = self.n + self.mh
        self.starts = np.cumsum((0, *self.sizes))  # level k: rows head + starts[k] .. [k+1]
        self.x = x
        y = A @ x
        self.y = y
        s = y - np.minimum(np.maximum(y, lo), hi)
        self.s = s
        a = np.abs(s)
        if frozen is None:
            self.lo_f = lo - a
            self.hi_f = hi + a
        else:  # judge this point against another point's frozen set
            self.lo_f, self.hi_f = frozen.lo_f, frozen.hi_f
        fin_lo, fin_hi = np.isfinite(lo), np.isfinite(hi)
        tol_lo = act_tol * (1.0 + np.abs(np.where(fin_lo, lo, 0.0)))
        tol_hi = act_tol * (1.0 + np.abs(np.where(fin_hi, hi, 0.0)))
        # outward normal +a where a row sits at its frozen upper side, -a at its lower side
        self.d_up = np.where(fin_hi, np.maximum(self.hi_f - y, 0.0), np.inf)
        self.d_dn = np.where(fin_lo, np.maximum(y - self.lo_f, 0.0), np.inf)
        self.up = self.d_up <= tol_hi
        self.dn = self.d_dn <= tol_lo
        self.norms = np.sqrt(np.einsum("ij,ij->i", A, A))
        self.live = self.norms > 0.0
        self.width = hi[: self.n] - lo[: self.n]  # inf for a missing side
        self.boxed = np.isfinite(self.width)
        hv = float(a[: self.head].max(initial=0.0))
        self.hard_violation = hv

    def level(self, k: int) -> slice:
        return slice(self.head + int(self.starts[k]), self.head + int(self.starts[k + 1]))

    def residual(self, k: int) -> float:
        sl = self.level(k)
        sk = self.s[sl]
        return math.sqrt(float(self.w[self.starts[k]: self.starts[k + 1]] @ (sk * sk)))

    def scale(self, k: int) -> float:
        sl = self.level(k)
        sides = np.concatenate((self.lo[sl], self.hi[sl]))
        sides = sides[np.isfinite(sides)]
        return max(1.0, float(np.abs(sides).max(initial=0.0)))


def _stationarity(fr: _Frame, k: int) -> tuple[FloatArray, float, float]:
    """NNLS multipliers of level k's gradient on the active normals above it.

    Returns:
        ``(r, df, scale_g)``: the residual ``g + N lambda``, the convexity bound
        ``sum_i mu_i delta_i`` of the constraints counted as active (the box-width part is added
        by the caller), and the magnitude ``sum_i w_i |s_i| |a_i| + sum_i lambda_i`` of the
        terms that cancel in ``r`` (round-off scale).
    """
    sl = fr.level(k)
    ws = fr.w[fr.starts[k]: fr.starts[k + 1]] * fr.s[sl]
    g = fr.A[sl].T @ ws
    scale_g = float(np.abs(ws) @ fr.norms[sl])
    P = sl.start  # constraint rows: box, hard rows and every higher level
    live = fr.live[:P]
    up = np.flatnonzero(live & fr.up[:P])
    dn = np.flatnonzero(live & fr.dn[:P])
    if not up.size + dn.size:
        return g, 0.0, scale_g
    idx = np.concatenate((up, dn))
    nrm = fr.norms[idx]
    sign = np.concatenate((1.0 / nrm[: up.size], -1.0 / nrm[up.size:]))
    N = fr.A[idx].T * sign  # unit outward normals as columns
    lam, _ = nnls(N, -g, maxiter=max(50, 10 * idx.size))
    r = g + N @ lam
    mu = lam / nrm  # multipliers of the raw rows
    df = float(mu[: up.size] @ fr.d_up[up] + mu[up.size:] @ fr.d_dn[dn])
    return r, df, scale_g + float(lam.sum())


def certify(A: FloatArray, lo: FloatArray, hi: FloatArray, n: int, mh: int,
            sizes: Sequence[int], w: FloatArray, x: FloatArray, *,
            level_tol: float = LEVEL_TOL, opt_tol: float = OPT_TOL, stat_tol: float = STAT_TOL,
            act_tol: float = ACT_TOL, hard_tol: float = HARD_TOL, exact: bool = True,
            keep: Sequence[LevelCertificate] = ()) -> Certificate:
    """Prove each level of ``x`` optimal, or find how to improve it (see the module docstring).

    Args:
        A: Stacked rows ``[I_n; A_H; A_0; ...]``, shape (M, n).
        lo: Lower sides, shape (M,), ``-inf`` allowed.
        hi: Upper sides, shape (M,), ``+inf`` allowed; ``lo == hi`` marks an equality row.
        n: Number of variables.
        mh: Number of hard rows.
        sizes: Rows per level, highest priority first.
        w: Positive level row weights, shape (sum sizes,).
        x: The answer, shape (n,).
        level_tol: Relative tolerance deciding that a level is met.
        opt_tol: Relative tolerance on ``rho_k(x) - rho_k*`` of a certified level.
        stat_tol: Round-off level of the stationarity residual (relative to the gradient's
            terms) on variables without a finite box, and of the exact optimum's certificate.
        act_tol: Relative distance within which a constraint counts as active (any value is
            sound: the bound charges ``mu_i delta_i`` for it).
        hard_tol: Relative tolerance of the box and hard rows.
        exact: Resolve inconclusive bounds with the exact level optimum (an active-set solve);
            False reports them as unproven.
        keep: Verdicts carried over for the first ``len(keep)`` levels (their residuals are
            measured again): for a point that no row of those levels violates more than the
            point they were proven at, as :func:`repair` produces, they still hold.

    Returns:
        The :class:`Certificate`; levels are judged against the frozen set at ``x`` whatever
        the verdicts above them.
    """
    x = np.asarray(x, dtype=np.float64)
    p = len(sizes)
    if x.shape != (n,) or not np.all(np.isfinite(x)):
        return Certificate(tuple(LevelCertificate(k, UNPROVEN, math.inf, math.inf, math.inf)
                                 for k in range(p)), math.inf, False)
    fr = _Frame(A, lo, hi, n, mh, sizes, w, x, act_tol)
    sides = np.concatenate((lo[: fr.head], hi[: fr.head]))
    hard_scale = max(1.0, float(np.abs(sides[np.isfinite(sides)]).max(initial=0.0)))
    inside = fr.hard_violation <= hard_tol * hard_scale
    out = []
    for k in range(p):
        rho = fr.residual(k)
        scale = fr.scale(k)
        if k < len(keep):
            c = keep[k]
            out.append(LevelCertificate(k, c.verdict, rho, c.stationarity, c.gap))
            continue
        if rho <= level_tol * scale:
            out.append(LevelCertificate(k, MET, rho))
            continue
        out.append(_certify_level(fr, k, rho, scale, opt_tol, stat_tol, exact))
    return Certificate(tuple(out), fr.hard_violation, bool(inside))


def _gap(df: float, rho: float) -> float:
    """Bound on ``rho - rho*`` from a bound ``df`` on ``f - f*`` (``f = rho^2 / 2``)."""
    if not math.isfinite(df):
        return math.inf
    df = max(df, 0.0)
    return min(2.0 * df / rho, math.sqrt(2.0 * df)) if rho > 0.0 else math.sqrt(2.0 * df)


def _certify_level(fr: _Frame, k: int, rho: float, scale: float, opt_tol: float,
                   stat_tol: float, exact: bool) -> LevelCertificate:
    r, df_act, scale_g = _stationarity(fr, k)
    nr = float(np.linalg.norm(r))
    rb = np.abs(r[: fr.n])
    unboxed = ~fr.boxed
    round_off = stat_tol * max(scale_g, 1e-300)
    if unboxed.any() and float(rb[unboxed].max()) > round_off:
        df = math.inf
    else:
        df = float(rb[fr.boxed] @ fr.width[fr.boxed]) + df_act
    gap = _gap(df, rho)
    if gap <= opt_tol * scale:
        return LevelCertificate(k, CERTIFIED, rho, nr, gap, -r)
    if not exact:
        return LevelCertificate(k, UNPROVEN, rho, nr, gap, -r)
    better = _level_optimum(fr, k)
    if better is None:
        return LevelCertificate(k, UNPROVEN, rho, nr, gap, -r)
    sub = _Frame(fr.A, fr.lo, fr.hi, fr.n, fr.mh, fr.sizes, fr.w, better, 1e-9, frozen=fr)
    # x+ must keep the frozen set of x and be stationary at round-off on its own active set
    if not _keeps_frozen(fr, sub, k):
        return LevelCertificate(k, UNPROVEN, rho, nr, gap, -r)
    r_plus, _, scale_plus = _stationarity(sub, k)
    if float(np.abs(r_plus).max(initial=0.0)) > max(stat_tol, 1e-12) * 1e3 * max(scale_plus,
                                                                                  1e-300):
        return LevelCertificate(k, UNPROVEN, rho, nr, gap, -r)
    diff = rho - sub.residual(k)
    if diff <= opt_tol * scale:
        return LevelCertificate(k, CERTIFIED, rho, nr, max(diff, 0.0), -r, better,
                                max(diff, 0.0))
    return LevelCertificate(k, IMPROVABLE, rho, nr, diff, -r, better, diff)


def _keeps_frozen(fr: _Frame, sub: _Frame, k: int, tol: float = 1e-9) -> bool:
    """True when ``sub.x`` lies in the frozen set of level k taken at ``fr.x`` (to ``tol``)."""
    P = fr.level(k).start
    y = sub.y[:P]
    rel = tol * (1.0 + np.abs(fr.y[:P]))
    return bool(np.all((y <= fr.hi_f[:P] + rel) & (y >= fr.lo_f[:P] - rel)))


# ------------------------------------------------------------------------ exact level solves
def _level_qp(fr: _Frame, k: int) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray,
                                           FloatArray, FloatArray, FloatArray]:
    """Level k's QP over ``z = [x; t]`` on the frozen set at ``fr.x``.

    ``min 1/2 z' H z + c' z`` with ``H = diag(A_e' W_e A_e, W_i)``, ``c = [-A_e' W_e b; 0]``
    (equality rows ``e`` of level k in x, one slack ``t_i`` per inequality row ``i``, kept by
    ``lo_i <= a_i x - t_i <= hi_i``), equalities ``E z = e`` (rows whose frozen sides coincide:
    hard equalities, higher equality rows met exactly) and inequalities ``G z <= h`` (the frozen
    sides of every other box, hard and higher-level row, level k's inequality rows). Every
    constraint row is normalised. Returns ``(H, c, E, e, G, h, z0)``.
    """
    n = fr.n
    sl = fr.level(k)
    Ak, lok, hik = fr.A[sl], fr.lo[sl], fr.hi[sl]
    wk = fr.w[fr.starts[k]: fr.starts[k + 1]]
    eqk = lok == hik
    ine = np.flatnonzero(~eqk)
    q = ine.size
    Ae, be, we = Ak[eqk], lok[eqk], wk[eqk]
    H = np.zeros((n + q, n + q))
    H[:n, :n] = Ae.T @ (we[:, None] * Ae)
    H[n:, n:] = np.diag(wk[ine])
    c = np.zeros(n + q)
    c[:n] = -Ae.T @ (we * be)
    P = sl.start
    live = fr.live[:P]
    lo_f, hi_f, nrm = fr.lo_f[:P], fr.hi_f[:P], fr.norms[:P]
    unit = fr.A[:P] / np.where(live, nrm, 1.0)[:, None]
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
    z0 = np.concatenate((fr.x, fr.s[sl][ine]))
    return H, c, E, e, G, h, z0


def _level_optimum(fr: _Frame, k: int) -> FloatArray | None:
    """Exact optimum of level k over the frozen set at ``fr.x`` (None when the solve fails)."""
    H, c, E, e, G, h, z0 = _level_qp(fr, k)
    z = active_set(H, c, E, e, G, h, z0)
    return None if z is None else z[: fr.n]


def active_set(H: FloatArray, c: FloatArray, E: FloatArray, e: FloatArray, G: FloatArray,
               h: FloatArray, z0: FloatArray, max_iter: int | None = None,
               tight: float = 1e-9) -> FloatArray | None:
    """Primal active-set solve of ``min 1/2 z'Hz + c'z  s.t.  E z = e, G z <= h`` from ``z0``.

    The textbook method (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Alg. 16.3) from
    a feasible start: each iteration solves the equality-constrained QP on the equalities and
    the working set (its KKT system by least squares, so a singular ``H`` and dependent rows
    are harmless, and the step lands exactly on the working constraints), then steps to the
    first blocking constraint, or releases the working constraint with the most negative
    multiplier (a working set seen before is never entered again, which stops cycling on
    degenerate vertices). Rows of ``E`` and ``G`` are expected normalised.

    Args:
        H: Positive semi-definite Hessian, shape (m, m).
        c: Linear term, shape (m,).
        E: Equality rows, shape (p, m).
        e: Their values, shape (p,).
        G: Inequality rows, shape (q, m).
        h: Their sides, shape (q,).
        z0: Start, feasible to ``tight (1 + |side|)`` (None is returned otherwise).
        max_iter: Iteration cap (default ``10 (m + q) + 50``).
        tight: Relative slack below which an inequality starts in the working set.

    Returns:
        The stationary point with non-negative multipliers, or None (infeasible start, no
        progress, iteration cap).
    """
    m = z0.size
    rel = 1.0 + np.abs(h)
    z = np.asarray(z0, dtype=np.float64).copy()
    if np.any(G @ z - h > 1e-7 * rel) or np.any(np.abs(E @ z - e) > 1e-7 * (1.0 + np.abs(e))):
        return None
    work = h - G @ z <= tight * rel
    seen = {work.tobytes()}
    pe = E.shape[0]
    for _ in range(max_iter or 10 * (m + G.shape[0]) + 50):
        C = np.vstack((E, G[work]))
        mc = C.shape[0]
        K = np.block([[H, C.T], [C, np.zeros((mc, mc))]])
        rhs = np.concatenate((-(H @ z + c), e - E @ z, h[work] - G[work] @ z))
        sol = np.linalg.lstsq(K, rhs, rcond=1e-14)[0]
        if not np.all(np.isfinite(sol)):
            return None
        p, mu = sol[:m], sol[m + pe:]
        if np.abs(p).max(initial=0.0) <= 1e-13 * max(1.0, float(np.abs(z).max(initial=0.0))):
            z = z + p
            if not mu.size or mu.min() >= -1e-12 * max(1.0, float(np.abs(mu).max())):
                return z
            idx = np.flatnonzero(work)
            for j in np.argsort(mu):
                if mu[j] >= 0.0:
                    return z
                trial = work.copy()
                trial[idx[j]] = False
                if trial.tobytes() not in seen:
                    work = trial
                    seen.add(trial.tobytes())
                    break
            else:
                return z
            continue
        Gp = G @ p
        slack = np.maximum(h - G @ z, 0.0)
        block = ~work & (Gp > 1e-14 * rel)
        alpha, hit = 1.0, -1
        if block.any():
            ratios = np.full(G.shape[0], np.inf)
            ratios[block] = slack[block] / Gp[block]
            hit = int(np.argmin(ratios))
            if ratios[hit] < 1.0:
                alpha = float(ratios[hit])
            else:
                hit = -1
        z = z + alpha * p
        if hit >= 0:
            work = work.copy()
            work[hit] = True
            seen.add(work.tobytes())
    return None


# --------------------------------------------------------------------------------- repair
def repair(A: FloatArray, lo: FloatArray, hi: FloatArray, n: int, mh: int,
           sizes: Sequence[int], w: FloatArray, x: FloatArray, *,
           level_tol: float = LEVEL_TOL, opt_tol: float = OPT_TOL, stat_tol: float = STAT_TOL,
           act_tol: float = ACT_TOL, hard_tol: float = HARD_TOL,
           certificate: Certificate | None = None) -> Repair:
    """Make a certified answer from ``x``: exact level solves from the first failing level down.

    Level ``k`` (the first neither met nor certified) is solved exactly over its frozen set at
    the current point (:func:`active_set`, started at that point, which is feasible), then every
    lower level in turn over its frozen set at the new point; the result is certified again.
    Nothing above ``k`` moves: the higher levels keep their rows' values or their satisfied
    sides, so a repair never costs a higher level anything.

    Args:
        A: Stacked rows (see :func:`certify`).
        lo: Lower sides.
        hi: Upper sides.
        n: Number of variables.
        mh: Number of hard rows.
        sizes: Rows per level.
        w: Level row weights.
        x: The answer to repair, inside the hard set.
        level_tol: As in :func:`certify`.
        opt_tol: As in :func:`certify`.
        stat_tol: As in :func:`certify`.
        act_tol: As in :func:`certify`.
        hard_tol: As in :func:`certify`.
        certificate: The certificate of ``x`` when the caller has it.

    Returns:
        The :class:`Repair`: ``repaired`` True with a certified ``x``, or the input ``x`` with
        its certificate and a message saying why it could not be repaired.
    """
    tols = {"level_tol": level_tol, "opt_tol": opt_tol, "stat_tol": stat_tol,
            "act_tol": act_tol, "hard_tol": hard_tol}
    x = np.asarray(x, dtype=np.float64)
    cert = certificate or certify(A, lo, hi, n, mh, sizes, w, x, **tols)
    if cert.ok:
        return Repair(x, cert, False, "already certified")
    if not cert.inside:
        return Repair(x, cert, False, "x is not inside the hard set")
    first = cert.first_failure
    assert first is not None  # not ok and inside: some level failed
    z = x.copy()
    for k in range(first, len(sizes)):
        fr = _Frame(A, lo, hi, n, mh, sizes, w, z, act_tol)
        if fr.residual(k) <= level_tol * fr.scale(k) and k > first:
            continue  # a met lower level keeps its point unless the solve would improve it
        better = _level_optimum(fr, k)
        if better is None:
            return Repair(x, cert, False, f"the exact solve of level {k} failed")
        z = _clip_box(fr, better)
    new = certify(A, lo, hi, n, mh, sizes, w, z, keep=cert.levels[:first], **tols)
    if new.ok:
        return Repair(z, new, True, f"repaired from level {first}")
    bad = new.first_failure
    return Repair(x, cert, False, f"the repaired point still fails at level {bad}"
                  if bad is not None else "the repaired point left the hard set")


def _clip_box(fr: _Frame, x: FloatArray) -> FloatArray:
    """Remove round-off outside the box (the step lands on it to ~1e-16)."""
    return np.minimum(np.maximum(x, fr.lo[: fr.n]), fr.hi[: fr.n])
