"""One QP's optimality: the KKT check, the active-set polish and the exact active-set solve.

Inexact back-ends (ADMM, interior-point, HiGHS) stop at a tolerance, and their own "solved" is
not a proof. For one level's QP

    min_z  0.5 z'Pz + q'z   s.t.  G z <= h,  lb <= z <= ub

a point ``z`` is optimal exactly when it is feasible and there are multipliers ``nu >= 0`` on
the constraints tight at ``z`` with ``P z + q + C_J' nu = 0`` (``C_J`` the tight rows of ``G``,
``+I`` for tight upper and ``-I`` for tight lower bounds): the Karush-Kuhn-Tucker conditions of
a convex QP, necessary and sufficient. :func:`certify` finds the best such ``nu`` by non-negative
least squares and accepts ``z`` only when the stationarity residual is at round-off level;
:func:`certified_point` first sharpens the back-end's answer on candidate active sets (an
equality-constrained QP solved through its KKT system) so that a nearly right answer becomes an
exactly right one, then certifies it. A point that cannot be certified is reported as a failed
QP, never passed on as a success.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from .._validation import FloatArray

#: relative feasibility tolerance of a certified point, ``G z - h <= FEAS_TOL (1 + |h|)``
FEAS_TOL = 1e-10
#: relative slack below which a constraint counts as tight (may carry a multiplier)
TIGHT_TOL = 1e-9
#: stationarity residual allowed, relative to ``max(1, |P z|, |q|, |C_J' nu|)``
STAT_TOL = 1e-9
#: relative activity thresholds tried when sharpening an inexact answer
ACTIVE_TOLS = (1e-9, 1e-7, 1e-6, 1e-5, 1e-4)


@dataclass(frozen=True)
class Certificate:
    """A certified optimum of one QP.

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


def certify(P: FloatArray, q: FloatArray, G: FloatArray | None, h: FloatArray | None,
            lb: FloatArray | None, ub: FloatArray | None, z: FloatArray) -> Certificate | None:
    """Check the KKT conditions of the QP at ``z``; return the certificate or None.

    Multipliers are searched only on constraints tight at ``z`` (complementary slackness) and
    kept non-negative (dual feasibility) by :func:`scipy.optimize.nnls`; ``z`` must be feasible.
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
        nu, _ = nnls(C.T, -g, maxiter=50 * max(C.shape))
        r = g + C.T @ nu
        reach = float(np.abs(C.T @ nu).max())
    else:
        nu, r, reach = np.zeros(0), g, 0.0
    scale = max(1.0, float(np.abs(P @ z).max(initial=0.0)), float(np.abs(q).max(initial=0.0)),
                reach)
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
    return Certificate(z, lam, lam_box, stat)


def kkt_point(P: FloatArray, q: FloatArray, C: FloatArray, d: FloatArray
              ) -> tuple[FloatArray, FloatArray]:
    """Solve ``min 0.5 z'Pz + q'z s.t. C z = d`` through its KKT system (least squares).

    Least squares (``rcond`` 1e-13) makes dependent rows of ``C`` and a singular ``P`` harmless.

    Returns:
        ``(z, mu)``: the point and the multipliers of the rows of ``C``.
    """
    n, m = q.size, C.shape[0]
    K = np.block([[P, C.T], [C, np.zeros((m, m))]])
    sol = np.linalg.lstsq(K, np.concatenate((-q, d)), rcond=1e-13)[0]
    return sol[:n], sol[n:]


def certified_point(P: FloatArray, q: FloatArray, G: FloatArray | None, h: FloatArray | None,
                    lb: FloatArray | None, ub: FloatArray | None, z: FloatArray,
                    tols: tuple[float, ...] = ACTIVE_TOLS) -> Certificate | None:
    """Sharpen an inexact answer on candidate active sets and certify it.

    For each activity threshold ``tau`` the constraints within ``tau`` (relative) of being
    active at ``z`` are imposed as equalities and the equality-constrained QP is solved; a
    constraint whose multiplier comes out negative is released and the QP solved again (one
    primal active-set step, up to 5 times). The first feasible candidate that passes
    :func:`certify` is returned; the raw ``z`` itself is tried first.

    Returns:
        The certificate of the sharpened optimum, or None when no candidate can be certified.
    """
    cert = certify(P, q, G, h, lb, ub, z)
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
            key = work.tobytes()
            if key in tried:
                break
            tried.append(key)
            zp, mu = kkt_point(P, q, all_rows[work], all_rhs[work])
            if not np.all(np.isfinite(zp)):
                break
            if feasible(G, h, lb, ub, zp):
                cert = certify(P, q, G, h, lb, ub, zp)
                if cert is not None:
                    return cert
            neg = mu < -STAT_TOL * max(1.0, float(np.abs(mu).max(initial=0.0)))
            if not neg.any():
                break
            idx = np.flatnonzero(work)
            work = work.copy()
            work[idx[neg]] = False
    return None


def active_set_from(P: FloatArray, q: FloatArray, G: FloatArray | None, h: FloatArray | None,
                    lb: FloatArray | None, ub: FloatArray | None, z0: FloatArray,
                    max_iter: int = 200) -> Certificate | None:
    """Exact primal active-set solve of the QP from a feasible point, then certified.

    The recovery when a back-end gives up (e.g. calls a 1e-10-thin feasible set infeasible):
    the textbook primal active-set method (Nocedal & Wright, *Numerical Optimization*, Alg. 16.3)
    started from a point known to be feasible, for a cascade the previous level's answer
    (``y = 0``) with the smallest slacks of the level's own rows. Each iteration solves the
    equality-constrained QP on the working set (KKT system by least squares, so dependent rows
    and a singular ``P`` are harmless), steps to the first blocking constraint, or releases the
    working constraint with the most negative multiplier. The answer is returned only when
    :func:`certify` proves it optimal.

    Args:
        P: Hessian, shape (k, k), positive semi-definite.
        q: Linear term, shape (k,).
        G: Inequality rows ``G z <= h``, shape (m, k), or None.
        h: Their right-hand sides, shape (m,), or None.
        lb: Lower bounds on z (``-inf`` allowed) or None.
        ub: Upper bounds on z (``+inf`` allowed) or None.
        z0: Feasible starting point (checked to :data:`FEAS_TOL`; None is returned otherwise).
        max_iter: Iteration cap (each iteration adds or releases one constraint).

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
    rel = 1.0 + np.abs(rhs)
    z = z0.astype(np.float64, copy=True)
    work = rhs - rows @ z <= TIGHT_TOL * rel
    seen = {work.tobytes()}
    for _ in range(max_iter):
        cert = certify(P, q, G, h, lb, ub, z)
        if cert is not None:
            return cert
        C = rows[work]
        m = C.shape[0]
        # the step p also lands exactly on the working constraints (they may start 1e-9 away)
        p, mu = kkt_point(P, P @ z + q, C, rhs[work] - C @ z)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(mu))):
            return None
        if np.abs(p).max(initial=0.0) <= 1e-12 * max(1.0, float(np.abs(z).max(initial=0.0))):
            if not m or mu.min() >= 0.0:
                return None  # stationary on the working set yet not certified: give up
            # release the most negative multiplier whose release leads to a working set not
            # seen before (degenerate, nearly parallel rows would otherwise cycle)
            idx = np.flatnonzero(work)
            for j in np.argsort(mu):
                if mu[j] >= 0.0:
                    return None
                trial = work.copy()
                trial[idx[j]] = False
                if trial.tobytes() not in seen:
                    work = trial
                    break
            else:
                return None
            seen.add(work.tobytes())
            continue
        Cp = rows @ p
        slack = np.maximum(rhs - rows @ z, 0.0)
        block = ~work & (Cp > 1e-14 * rel)
        alpha, hit = 1.0, -1
        if block.any():
            ratios = np.full(rows.shape[0], np.inf)
            ratios[block] = slack[block] / Cp[block]
            hit = int(np.argmin(ratios))
            if ratios[hit] < 1.0:
                alpha = float(ratios[hit])
            else:
                hit = -1
        z = z + alpha * p
        if hit >= 0:
            work[hit] = True
    return certify(P, q, G, h, lb, ub, z)
