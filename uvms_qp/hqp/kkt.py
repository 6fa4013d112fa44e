"""One QP's optimality: the KKT check, the active-set polish and the one exact active-set solver.

Inexact back-ends (ADMM, interior-point, HiGHS) stop at a tolerance, and their own "solved" is
not a proof. For one level's QP

    min_z  0.5 z'Pz + q'z   s.t.  G z <= h,  lb <= z <= ub

a point ``z`` is optimal exactly when it is feasible and there are multipliers ``nu >= 0`` on
the constraints tight at ``z`` with ``P z + q + C_J' nu = 0`` (``C_J`` the tight rows of ``G``,
``+I`` for tight upper and ``-I`` for tight lower bounds): the Karush-Kuhn-Tucker conditions of
a convex QP, necessary and sufficient. :func:`certify_qp` finds the best such ``nu`` by
non-negative least squares and accepts ``z`` only when the stationarity residual is at round-off
level (a :class:`QpCertificate`: one QP's optimum; the lexicographic optimum of a whole problem
has its own certificate, level by level, in :mod:`uvms_qp.hqp.certificate`);
:func:`certified_point` first sharpens the back-end's answer on candidate active sets (an
equality-constrained QP solved through its KKT system) so that a nearly right answer becomes an
exactly right one, then certifies it. A point that cannot be certified is reported as a failed
QP, never passed on as a success.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from time import perf_counter

import numpy as np

from .._validation import FloatArray
from .linalg import nnls
from .tolerances import FEAS_TOL, ROUND_OFF, STAT_TOL, TIGHT_TOL

#: relative activity thresholds tried when sharpening an inexact answer
ACTIVE_TOLS = (1e-9, 1e-7, 1e-6, 1e-5, 1e-4)


@dataclass(frozen=True)
class QpCertificate:
    """A certified optimum of one QP (the KKT conditions hold at ``z``).

    Attributes:
        z: The optimal point.
        lam: Multipliers of the rows of ``G`` (0 where not tight), shape (m,).
        lam_box: Multipliers of the bounds (``> 0`` upper, ``< 0`` lower, 0 inactive), shape (n,).
        stationarity: ``|P z + q + C_J' nu|_inf`` relative to the scale of the gradient.
    """

    z: FloatArray
    lam: FloatArray
    lam_box: FloatArray
    stationarity: float


def _finite_abs(v: FloatArray) -> FloatArray:
    return np.abs(np.where(np.isfinite(v), v, 0.0))


def feasible(G: FloatArray | None, h: FloatArray | None, lb: FloatArray | None,
             ub: FloatArray | None, z: FloatArray, tol: float = FEAS_TOL) -> bool:
    """True when ``z`` satisfies ``G z <= h`` and the bounds to ``tol (1 + |side|)``."""
    if not np.all(np.isfinite(z)):
        return False
    if G is not None and h is not None and G.shape[0] and np.any(
            G @ z - h > tol * (1.0 + np.abs(h))):
        return False
    if lb is not None and np.any(z < lb - tol * (1.0 + _finite_abs(lb))):
        return False
    return not (ub is not None and np.any(z > ub + tol * (1.0 + _finite_abs(ub))))


def certify_qp(P: FloatArray, q: FloatArray, G: FloatArray | None, h: FloatArray | None,
            lb: FloatArray | None, ub: FloatArray | None, z: FloatArray) -> QpCertificate | None:
    """Check the KKT conditions of the QP at ``z``; return the certificate or None.

    Multipliers are searched only on constraints tight at ``z`` (complementary slackness) and
    kept non-negative (dual feasibility) by :func:`uvms_qp.hqp.linalg.nnls`; ``z`` must be feasible.
    """
    n = z.size
    if not feasible(G, h, lb, ub, z):
        return None
    g = P @ z + q
    blocks: list[FloatArray] = []
    m = 0 if G is None else G.shape[0]
    tight_g = np.zeros(m, dtype=bool)
    if G is not None and h is not None and m:
        tight_g = h - G @ z <= TIGHT_TOL * (1.0 + np.abs(h))
        blocks.append(G[tight_g])
    eye = np.eye(n)
    tight_u = np.zeros(n, dtype=bool) if ub is None else np.isfinite(ub) & (
        ub - z <= TIGHT_TOL * (1.0 + _finite_abs(ub)))
    tight_l = np.zeros(n, dtype=bool) if lb is None else np.isfinite(lb) & (
        z - lb <= TIGHT_TOL * (1.0 + _finite_abs(lb)))
    blocks.append(eye[tight_u])
    blocks.append(-eye[tight_l])
    C = np.vstack(blocks)
    if C.shape[0]:
        nu, _ = nnls(C.T, -g, 50 * max(C.shape))
        r = g + C.T @ nu
        reach = float(np.abs(C.T @ nu).max())
    else:
        nu, r, reach = np.zeros(0), g, 0.0
    # relative to the gradient's own terms (no floor at 1: a QP in other units is judged
    # alike), and never below what round-off leaves of ``P z`` (``ROUND_OFF |P| |z|``)
    scale = max(ROUND_OFF * float(np.abs(P).max(initial=0.0)) * float(np.abs(z).max(
        initial=0.0)), float(np.abs(P @ z).max(initial=0.0)), float(np.abs(q).max(initial=0.0)),
                reach) or 1.0
    stat = float(np.abs(r).max(initial=0.0)) / scale
    if not np.isfinite(stat) or stat > STAT_TOL:
        return None
    lam = np.zeros(m)
    k = int(tight_g.sum())
    lam[tight_g] = nu[:k]
    lam_box = np.zeros(n)
    ku = int(tight_u.sum())
    lam_box[tight_u] = nu[k:k + ku]
    lam_box[tight_l] -= nu[k + ku:]
    return QpCertificate(z, lam, lam_box, stat)


def kkt_point(P: FloatArray, q: FloatArray, C: FloatArray, d: FloatArray, rcond: float = 1e-13
              ) -> tuple[FloatArray, FloatArray]:
    """Solve ``min 0.5 z'Pz + q'z s.t. C z = d`` through its KKT system (least squares).

    Least squares (cut-off ``rcond`` relative to the largest singular value) makes dependent
    rows of ``C`` and a singular ``P`` harmless.

    Returns:
        ``(z, mu)``: the point and the multipliers of the rows of ``C``.
    """
    n, m = q.size, C.shape[0]
    K = np.block([[P, C.T], [C, np.zeros((m, m))]])
    sol = np.linalg.lstsq(K, np.concatenate((-q, d)), rcond=rcond)[0]
    return sol[:n], sol[n:]


def certified_point(P: FloatArray, q: FloatArray, G: FloatArray | None, h: FloatArray | None,
                    lb: FloatArray | None, ub: FloatArray | None, z: FloatArray,
                    tols: tuple[float, ...] = ACTIVE_TOLS, *, deadline: float | None = None,
                    clock: Callable[[], float] = perf_counter) -> QpCertificate | None:
    """Sharpen an inexact answer on candidate active sets and certify it.

    For each activity threshold ``tau`` the constraints within ``tau`` (relative) of being
    active at ``z`` are imposed as equalities and the equality-constrained QP is solved; a
    constraint whose multiplier comes out negative is released and the QP solved again (one
    primal active-set step, up to 5 times). The first feasible candidate that passes
    :func:`certify_qp` is returned; the raw ``z`` itself is tried first.

    Returns:
        The certificate of the sharpened optimum, or None when no candidate can be certified
        (or ``deadline``, a reading of ``clock`` [s], passes first).
    """
    cert = certify_qp(P, q, G, h, lb, ub, z)
    if cert is not None:
        return cert
    n = z.size
    eye = np.eye(n)
    rows = np.zeros((0, n)) if G is None else G
    rhs = np.zeros(0) if h is None else h
    all_rows = np.vstack((rows, eye, -eye))
    lo_side = np.full(n, np.inf) if lb is None else -lb
    up_side = np.full(n, np.inf) if ub is None else ub
    all_rhs = np.concatenate((rhs, up_side, lo_side))
    finite = np.isfinite(all_rhs)
    slack = np.where(finite, all_rhs - all_rows @ z, np.inf)
    rel = 1.0 + _finite_abs(all_rhs)
    tried: list[bytes] = []
    for tau in tols:
        work = finite & (slack <= tau * rel)
        for _ in range(6):
            if deadline is not None and clock() > deadline:
                return None
            key = work.tobytes()
            if key in tried:
                break
            tried.append(key)
            zp, mu = kkt_point(P, q, all_rows[work], all_rhs[work])
            if not np.all(np.isfinite(zp)):
                break
            if feasible(G, h, lb, ub, zp):
                cert = certify_qp(P, q, G, h, lb, ub, zp)
                if cert is not None:
                    return cert
            neg = mu < -STAT_TOL * max(1.0, float(np.abs(mu).max(initial=0.0)))
            if not neg.any():
                break
            idx = np.flatnonzero(work)
            work = work.copy()
            work[idx[neg]] = False
    return None


def active_set(H: FloatArray, c: FloatArray, E: FloatArray, e: FloatArray, G: FloatArray,
               h: FloatArray, z0: FloatArray, *, max_iter: int | None = None,
               tight: float = TIGHT_TOL, start_tol: float = 1e-7, rcond: float = 1e-13,
               deadline: float | None = None, clock: Callable[[], float] = perf_counter,
               best_effort: bool = False) -> FloatArray | None:
    """Primal active-set solve of ``min 1/2 z'Hz + c'z  s.t.  E z = e, G z <= h`` from ``z0``.

    The textbook method (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Alg. 16.3) from
    a feasible start: each iteration solves the equality-constrained QP on the equalities and
    the working set (its KKT system by least squares, :func:`kkt_point`, so a singular ``H`` and
    dependent rows are harmless, and the step lands exactly on the working constraints), then
    steps to the first blocking constraint, or releases the working constraint with the most
    negative multiplier (a working set seen before is never entered again, which stops cycling
    on degenerate vertices). The one exact QP solver of the package: the cascades' rescue
    (:func:`active_set_from`) and the certificate's repair
    (:func:`uvms_qp.hqp.certificate.repair`) both run it.

    Args:
        H: Positive semi-definite Hessian, shape (m, m).
        c: Linear term, shape (m,).
        E: Equality rows, shape (p, m) (normalised rows keep the tolerances meaningful).
        e: Their values, shape (p,).
        G: Inequality rows, shape (q, m).
        h: Their sides, shape (q,).
        z0: Start, feasible to ``start_tol (1 + |side|)`` (None is returned otherwise).
        max_iter: Iteration cap (default ``10 (m + q) + 50``).
        tight: Relative slack below which an inequality starts in the working set.
        start_tol: Relative feasibility tolerance of the start.
        rcond: Cut-off of the KKT least squares (:func:`kkt_point`).
        deadline: Reading of ``clock`` [s] after which the solve gives up (None: none).
        clock: The clock of ``deadline`` (default :func:`time.perf_counter`).
        best_effort: Stop when the solve stagnates (``m + 10`` iterations in a row without
            lowering the objective), and when it stops early (stagnation, the iteration cap,
            the deadline) return the point it has (feasible, its objective at most the
            start's) instead of None.

    Returns:
        The stationary point with non-negative multipliers, or None (infeasible start, no
        minimiser, or an early stop without ``best_effort``).
    """
    m = z0.size
    rel = 1.0 + np.abs(h)
    z = np.asarray(z0, dtype=np.float64).copy()
    if np.any(G @ z - h > start_tol * rel) or np.any(
            np.abs(E @ z - e) > start_tol * (1.0 + np.abs(e))):
        return None
    work = h - G @ z <= tight * rel
    seen = {work.tobytes()}
    pe = E.shape[0]
    landed = False  # the last step was a full one: z is the optimum on its working set
    best = _objective(H, c, z) if best_effort else 0.0
    stall, patience = 0, m + 10
    for _ in range(max_iter or 10 * (m + G.shape[0]) + 50):
        if deadline is not None and clock() > deadline:
            return z if best_effort else None
        if best_effort:
            value = _objective(H, c, z)
            if value < best - 1e-15 * max(1.0, abs(best)):
                best, stall = value, 0
            else:
                stall += 1
                if stall > patience:  # no progress: degenerate exchanges only
                    return z
        C = np.vstack((E, G[work]))
        grad = H @ z + c
        d = np.concatenate((e - E @ z, h[work] - G[work] @ z))
        p, mu_all = kkt_point(H, grad, C, d, rcond=rcond)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(mu_all))):
            return None
        if _unsolved(H, C, grad, d, p, mu_all):
            # the working set's equality QP has no minimiser (H is only semi-definite): descend
            # along a direction of zero curvature that keeps the working constraints, to the
            # first blocking constraint
            flat = _flat_descent(H, C, grad)
            if flat is None:
                return None
            hit, alpha = _blocking(G, h, z, flat, work, rel, cap=math.inf)
            if hit < 0:
                return None  # unbounded below
            z = z + alpha * flat
            landed = False
            work = work.copy()
            work[hit] = True
            seen.add(work.tobytes())
            continue
        mu = mu_all[pe:]
        if landed or np.abs(p).max(initial=0.0) <= 1e-13 * max(
                1.0, float(np.abs(z).max(initial=0.0))):
            # stationary on the working set (after a full step, p is round-off of the least
            # squares, relative to the scale of H: z stays where the step put it, exactly on
            # its working constraints)
            landed = False
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
        hit, alpha = _blocking(G, h, z, p, work, rel, cap=1.0)
        z = z + alpha * p
        landed = hit < 0
        if hit >= 0:
            work = work.copy()
            work[hit] = True
            seen.add(work.tobytes())
    return z if best_effort else None


def _objective(H: FloatArray, c: FloatArray, z: FloatArray) -> float:
    """``1/2 z'Hz + c'z``."""
    return float(z.dot(0.5 * H.dot(z) + c))


def _unsolved(H: FloatArray, C: FloatArray, grad: FloatArray, d: FloatArray, p: FloatArray,
              mu: FloatArray) -> bool:
    """True when ``(p, mu)`` does not solve the KKT system (it has no solution)."""
    Hp = H @ p
    stat = Hp + grad
    if C.shape[0]:
        stat += C.T @ mu
    scale = max(1.0, float(np.abs(grad).max(initial=0.0)), float(np.abs(Hp).max(initial=0.0)))
    if float(np.abs(stat).max(initial=0.0)) > 1e-9 * scale:
        return True
    return bool(C.shape[0]) and float(np.abs(C @ p - d).max()) > 1e-9 * max(
        1.0, float(np.abs(d).max(initial=0.0)))


def _flat_descent(H: FloatArray, C: FloatArray, grad: FloatArray) -> FloatArray | None:
    """``-grad`` projected on the null space of ``[H; C]`` (None when that is ~0)."""
    M = np.vstack((H, C))
    _, s, Vt = np.linalg.svd(M)
    top = float(s[0]) if s.size else 0.0
    rank = int(np.sum(s > 1e-12 * max(top, 1e-300)))
    N = Vt[rank:]
    p = -(N.T @ (N @ grad))
    if float(np.abs(p).max(initial=0.0)) <= 1e-12 * max(1.0, float(np.abs(grad).max())):
        return None
    return p


def _blocking(G: FloatArray, h: FloatArray, z: FloatArray, p: FloatArray, work: np.ndarray,
              rel: FloatArray, cap: float) -> tuple[int, float]:
    """The first constraint outside the working set that the step ``z + alpha p`` meets.

    Returns:
        ``(index, alpha)``, or ``(-1, cap)`` when none is met before ``alpha = cap``.
    """
    Gp = G @ p
    block = ~work & (Gp > 1e-14 * rel)
    if block.any():
        slack = np.maximum(h - G @ z, 0.0)
        ratios = np.full(G.shape[0], np.inf)
        ratios[block] = slack[block] / Gp[block]
        hit = int(np.argmin(ratios))
        if ratios[hit] < cap:
            return hit, float(ratios[hit])
    return -1, cap


def active_set_from(P: FloatArray, q: FloatArray, G: FloatArray | None, h: FloatArray | None,
                    lb: FloatArray | None, ub: FloatArray | None, z0: FloatArray,
                    max_iter: int = 200, deadline: float | None = None,
                    clock: Callable[[], float] = perf_counter) -> QpCertificate | None:
    """Exact solve of the QP from a feasible point (:func:`active_set`), then certified.

    The recovery when a back-end gives up (e.g. calls a 1e-10-thin feasible set infeasible):
    :func:`active_set` started from a point known to be feasible, for a cascade the previous
    level's answer (``y = 0``) with the smallest slacks of the level's own rows; the bounds
    become rows of ``G``. The answer is returned only when :func:`certify_qp` proves it optimal.

    Args:
        P: Hessian, shape (k, k), positive semi-definite.
        q: Linear term, shape (k,).
        G: Inequality rows ``G z <= h``, shape (m, k), or None.
        h: Their right-hand sides, shape (m,), or None.
        lb: Lower bounds on z (``-inf`` allowed) or None.
        ub: Upper bounds on z (``+inf`` allowed) or None.
        z0: Feasible starting point (checked to :data:`FEAS_TOL`; None is returned otherwise).
        max_iter: Iteration cap (each iteration adds or releases one constraint).
        deadline: Reading of ``clock`` [s] after which the solve gives up (None: none).
        clock: The clock of ``deadline``.

    Returns:
        The certificate of the optimum, or None.
    """
    if not feasible(G, h, lb, ub, z0):
        return None
    n = z0.size
    eye = np.eye(n)
    rows = np.vstack((np.zeros((0, n)) if G is None else G, eye, -eye))
    rhs = np.concatenate((np.zeros(0) if h is None else h,
                          np.full(n, np.inf) if ub is None else ub,
                          np.full(n, np.inf) if lb is None else -lb))
    live = np.isfinite(rhs)
    rows, rhs = rows[live], rhs[live]
    z = active_set(P, q, np.zeros((0, n)), np.zeros(0), rows, rhs, z0, max_iter=max_iter,
                   start_tol=FEAS_TOL, deadline=deadline, clock=clock)
    return None if z is None else certify_qp(P, q, G, h, lb, ub, z)
