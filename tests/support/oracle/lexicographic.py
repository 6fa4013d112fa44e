"""Independent oracle of lexicographic optimality: one exact QP per level, by Clarabel directly.

For an answer ``x`` of a stacked problem (``A = [I_n; A_H; A_0; ...]``, sides ``lo``/``hi``,
level sizes, row weights ``w``), level k is judged by solving

    min_{x', t}  1/2 sum_{i in k} w_i t_i^2
    s.t.         lo_i <= a_i x' - t_i <= hi_i                        (rows of level k)
                 lower <= x' <= upper,  lo_H <= A_H x' <= hi_H        (hard, exact)
                 |s_i(x')| <= |s_i(x)| + eps_i                        (every row of every
                                                                       higher level)

with ``s_i`` the signed violation of row i and ``eps_i = 1e-9 max(1, |a_i x|)``: each higher row
keeps the violation it has at ``x`` (to 1e-9). The per-row freeze is the exact optimal set of
an optimal higher level; an aggregated freeze ``rho_j(x') <= rho_j(x) + 1e-9`` would let x' move
by ``sqrt(1e-9)`` along directions where ``rho_j`` is flat to first order and report phantom
improvements of 1e-5.

Nothing here comes from the library: the QP is written out in the full x-space (no
elimination, no freezing margins, no certificate code) and handed to Clarabel's interior-point
solver directly, and every candidate point (Clarabel's, or any the caller supplies, such as a
certificate's witness) is *verified* in plain NumPy (clipped into the box, hard rows to 1e-9,
frozen rows to ``eps_i``) before its residual counts. An answer is wrong at level k when a
verified point beats it by more than ``tol * scale_k`` (``scale_k = max(1, max |finite side|)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import clarabel
import numpy as np
from scipy import sparse

SLACK = 1e-9
TOL = 1e-6


@dataclass
class LevelJudgement:
    level: int
    residual: float  # rho_k at the answer
    best: float  # best verified rho_k over the frozen set
    scale: float
    witness: np.ndarray | None

    @property
    def improvement(self) -> float:
        return self.residual - self.best

    def wrong(self, tol: float = TOL) -> bool:
        return self.improvement > tol * self.scale


def _slacks(A, lo, hi, x):
    y = A @ x
    return y, y - np.minimum(np.maximum(y, lo), hi)


def _level_scale(lo, hi):
    sides = np.concatenate((lo, hi))
    sides = sides[np.isfinite(sides)]
    return max(1.0, float(np.abs(sides).max(initial=0.0)))


class Oracle:
    """Judge answers of one stacked problem ``(A, lo, hi, n, mh, sizes, w)``."""

    def __init__(self, A, lo, hi, n, mh, sizes, w, slack=SLACK):
        self.A, self.lo, self.hi = (np.asarray(v, dtype=np.float64) for v in (A, lo, hi))
        self.n, self.mh = int(n), int(mh)
        self.sizes = tuple(int(m) for m in sizes)
        self.w = np.asarray(w, dtype=np.float64)
        self.head = self.n + self.mh
        self.starts = np.cumsum((0, *self.sizes))
        self.slack = slack

    def rows(self, k):
        return slice(self.head + self.starts[k], self.head + self.starts[k + 1])

    def residual(self, k, x):
        sl = self.rows(k)
        _, s = _slacks(self.A[sl], self.lo[sl], self.hi[sl], x)
        return math.sqrt(float(self.w[self.starts[k]:self.starts[k + 1]] @ (s * s)))

    # ------------------------------------------------------------------------- verification
    def verified(self, k, x, cand):
        """rho_k of ``cand`` clipped into the box, or inf when it leaves the frozen set."""
        if cand is None or not np.all(np.isfinite(cand)):
            return math.inf, None
        n, head = self.n, self.head
        c = np.clip(cand, self.lo[:n], self.hi[:n])
        if self.mh:
            _, sh = _slacks(self.A[n:head], self.lo[n:head], self.hi[n:head], c)
            side = np.maximum(np.abs(np.where(np.isfinite(self.lo[n:head]), self.lo[n:head], 0)),
                              np.abs(np.where(np.isfinite(self.hi[n:head]), self.hi[n:head], 0)))
            if np.any(np.abs(sh) > SLACK * (1.0 + side)):
                return math.inf, None
        P = self.rows(k).start
        y0, s0 = _slacks(self.A[head:P], self.lo[head:P], self.hi[head:P], x)
        _, s1 = _slacks(self.A[head:P], self.lo[head:P], self.hi[head:P], c)
        eps = self.slack * np.maximum(1.0, np.abs(y0))
        if np.any(np.abs(s1) > np.abs(s0) + eps):
            return math.inf, None
        return self.residual(k, c), c

    # ------------------------------------------------------------------------------- the QP
    def level_qp(self, k, x):
        """Clarabel's solution x' of level k's QP over the frozen set at x (None on failure)."""
        n, head = self.n, self.head
        sl = self.rows(k)
        Ak, lok, hik = self.A[sl], self.lo[sl], self.hi[sl]
        wk = self.w[self.starts[k]:self.starts[k + 1]]
        m = Ak.shape[0]
        nz = n + m
        eq_rows, eq_rhs, in_rows, in_rhs = [], [], [], []

        def add_sides(R, lo, hi, relax):
            norms = np.linalg.norm(R, axis=1)
            norms[norms == 0.0] = 1.0
            for i in range(R.shape[0]):
                r = R[i] / norms[i]
                if lo[i] == hi[i] and relax is None:
                    eq_rows.append(r)
                    eq_rhs.append(lo[i] / norms[i])
                    continue
                grow = 0.0 if relax is None else relax[i]
                if np.isfinite(hi[i]):
                    in_rows.append(r)
                    in_rhs.append((hi[i] + grow) / norms[i])
                if np.isfinite(lo[i]):
                    in_rows.append(-r)
                    in_rhs.append(-(lo[i] - grow) / norms[i])

        pad = lambda R: np.hstack((R, np.zeros((R.shape[0], m))))  # noqa: E731
        # box and hard rows, exact
        add_sides(pad(self.A[:head]), self.lo[:head], self.hi[:head], None)
        # higher rows: violation kept (half the verification slack, for the solver's round-off)
        if sl.start > head:
            y0, s0 = _slacks(self.A[head:sl.start], self.lo[head:sl.start],
                             self.hi[head:sl.start], x)
            grow = np.abs(s0) + 0.5 * self.slack * np.maximum(1.0, np.abs(y0))
            add_sides(pad(self.A[head:sl.start]), self.lo[head:sl.start], self.hi[head:sl.start],
                      grow)
        # level k rows with their slack t: lo <= a x - t <= hi
        Rk = np.hstack((Ak, -np.eye(m)))
        add_sides(Rk, lok, hik, None)
        blocks = [np.array(eq_rows).reshape(-1, nz), np.array(in_rows).reshape(-1, nz)]
        Acon = np.vstack(blocks)
        b = np.concatenate((np.array(eq_rhs), np.array(in_rhs)))
        Pm = sparse.csc_matrix(sparse.block_diag((sparse.csc_matrix((n, n)), sparse.diags(wk))))
        Pm = sparse.triu(Pm, format="csc")
        q = np.zeros(nz)
        cones = []
        if eq_rows:
            cones.append(clarabel.ZeroConeT(len(eq_rows)))
        if in_rows:
            cones.append(clarabel.NonnegativeConeT(len(in_rows)))
        st = clarabel.DefaultSettings()
        st.verbose = False
        st.tol_gap_abs = st.tol_gap_rel = 1e-12
        st.tol_feas = 1e-12
        st.max_iter = 400
        try:
            sol = clarabel.DefaultSolver(Pm, q, sparse.csc_matrix(Acon), b, cones, st).solve()
        except Exception:
            return None
        z = np.asarray(sol.x)
        if z.size != nz or not np.all(np.isfinite(z)):
            return None
        return z[:n]

    def judge(self, x, candidates=(), met=0.0):
        """One :class:`LevelJudgement` per level of the answer ``x``.

        A level whose residual is at most ``met * scale`` is not solved (it cannot be improved
        by more than that): ``met = TOL`` skips the met levels, which can never be wrong.
        """
        x = np.asarray(x, dtype=np.float64)
        out = []
        for k in range(len(self.sizes)):
            sl = self.rows(k)
            rho = self.residual(k, x)
            scale = _level_scale(self.lo[sl], self.hi[sl])
            best, witness = rho, None
            if rho > met * scale:
                for cand in (self.level_qp(k, x), *candidates):
                    val, c = self.verified(k, x, cand)
                    if val < best:
                        best, witness = val, c
            out.append(LevelJudgement(k, rho, best, scale, witness))
        return out


def first_wrong(judgements, tol=TOL):
    """Index of the first level a verified point improves by more than ``tol * scale``."""
    for j in judgements:
        if j.wrong(tol):
            return j.level
    return None
