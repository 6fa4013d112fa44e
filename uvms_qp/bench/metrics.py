"""Aggregate benchmark rows into one line per (set, solver).

Definitions (times in microseconds):

* success rate: verified successes / trials, over every problem of the set the solver applies to
  (a closed-loop scenario contributes one trial per control step);
* median / p95 / p99 / max: over every timed trial of the set; a tail percentile from fewer
  samples than it needs (:func:`~uvms_qp.bench.record.tail_samples`: 20 for p95, 100 for p99) is
  NaN, not the maximum under another name;
* shifted geometric mean (qpbenchmark's ranking): ``SGM = prod_i (t_i + s)^(1/N) - s`` over the
  N problems of the set (``t_i`` the per-problem median time, shift ``s = 10 us``); a problem with
  any failed trial counts with the penalty time ``10 x`` the slowest per-problem median of the set;
  the column reports ``SGM / min SGM`` of the set (1.0 = fastest), rows that solved their own
  problem (:data:`~uvms_qp.bench.record.OWN_PROBLEM`) neither setting nor getting it;
* per-level optimality gap: for a problem whose answers share a reference (``random`` and ``raw``),
  the best solution found is the lexicographic minimum of the level violation vectors over every
  verified success (levels compared to ``GAP_TOL`` relative); a row's gap is the largest excess
  ``(v_k - best_k) / max(1, best_k)`` over the levels down to (and including) the first level where
  it is worse than the best; the set column is the largest row gap;
* gap vs nullspace: ``max_k |v_k - v_k(nullspace)|`` on problems where ``nullspace`` succeeded
  without being clipped into the box (where it is the exact lexicographic answer);
* accuracy tiers (as qpbenchmark's high/low accuracy): share of problems solved (every trial
  verified) with gap <= 1e-6 (high) and <= 1e-3 (low);
* ratio vs daqp / vs Pink: median over the problems both ran of the per-problem ratio of median
  times, leaving out the problems where either row solved its own problem (NaN when none is
  left).
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .record import OWN_PROBLEM, SATURATED, Record, percentile, tail_percentile

#: Shift of the shifted geometric mean [us].
SGM_SHIFT_US = 10.0
#: Penalty factor applied to the slowest per-problem median time for a failed problem.
FAIL_PENALTY = 10.0
#: Relative tolerance of the lexicographic comparison of level violations.
GAP_TOL = 1e-7
#: Accuracy tiers: name -> largest gap.
TIERS: dict[str, float] = {"high": 1e-6, "low": 1e-3}
#: Rows excluded from the "best solution found": they solve another problem (soft priorities),
#: so within the comparison tolerance they may trade a higher level for a lower one.
NOT_REFERENCE = ("pink", "weighted")


def shifted_geometric_mean(values: Sequence[float], shift: float = SGM_SHIFT_US) -> float:
    """``prod (v_i + shift)^(1/N) - shift`` (NaN when empty)."""
    if not len(values):
        return math.nan
    v = np.asarray(values, dtype=float)
    return float(np.exp(np.mean(np.log(v + shift))) - shift)


@dataclass
class Summary:
    """One line of the table: a solver on a set."""

    set: str
    solver: str
    problems: int = 0
    trials: int = 0
    successes: int = 0
    failures: dict[str, int] = field(default_factory=dict)
    timed: int = 0
    median_us: float = math.nan
    p95_us: float = math.nan
    p99_us: float = math.nan
    max_us: float = math.nan
    sgm: float = math.nan
    sgm_ratio: float = math.nan
    hard_violation: float = 0.0
    claimed_violation: float = 0.0
    gap: float = math.nan
    gap_nullspace: float = math.nan
    tiers: dict[str, float] = field(default_factory=dict)
    nan_count: int = 0
    vs_daqp: float = math.nan
    vs_pink: float = math.nan
    backend_us: float = math.nan
    not_applicable: int = 0
    own_problem: bool = False
    saturated: int = 0

    @property
    def success_rate(self) -> float:
        """Verified successes / trials (NaN without trials)."""
        return self.successes / self.trials if self.trials else math.nan


def _lexicographic_best(vectors: list[list[float]]) -> list[float]:
    """The lexicographic minimum of level-violation vectors (with relative tolerance)."""
    candidates = [v for v in vectors if v]
    if not candidates:
        return []
    best = []
    for k in range(len(candidates[0])):
        m = min(v[k] for v in candidates)
        best.append(m)
        candidates = [v for v in candidates if v[k] <= m + GAP_TOL * max(1.0, m)]
    return best


def level_gap(levels: list[float], best: list[float]) -> float:
    """Largest relative excess over ``best`` down to the first level that is worse."""
    gap = 0.0
    for v, b in zip(levels, best, strict=False):
        excess = (v - b) / max(1.0, b)
        gap = max(gap, excess)
        if excess > GAP_TOL:
            break
    return gap


def _median_time(record: Record) -> float:
    return float(np.median(record.times_us)) if record.times_us else math.nan


def _solved(record: Record) -> bool:
    return record.trials > 0 and record.successes == record.trials


def _own_problem(record: Record) -> bool:
    return record.note.startswith(OWN_PROBLEM)


def _paired_ratio(rows: dict[str, Record], ref: dict[str, Record]) -> float:
    ratios = []
    for problem, rec in rows.items():
        other = ref.get(problem)
        if other is None or not rec.times_us or not other.times_us:
            continue
        if _own_problem(rec) or _own_problem(other):
            continue
        a, b = _median_time(rec), _median_time(other)
        if b > 0.0:
            ratios.append(a / b)
    return float(np.median(ratios)) if ratios else math.nan


def summarize(records: Iterable[Record]) -> list[Summary]:
    """One :class:`Summary` per (set, solver), in the order solvers first appear."""
    by_set: dict[str, dict[str, dict[str, Record]]] = defaultdict(lambda: defaultdict(dict))
    order: list[tuple[str, str]] = []
    for rec in records:
        if (rec.set, rec.solver) not in order:
            order.append((rec.set, rec.solver))
        by_set[rec.set][rec.solver][rec.problem] = rec
    out: list[Summary] = []
    for set_name, solvers in by_set.items():
        best, null = _references(solvers)
        penalty = FAIL_PENALTY * max(
            (_median_time(r) for rows in solvers.values() for r in rows.values() if r.times_us),
            default=1.0)
        lines = {}
        for solver, rows in solvers.items():
            lines[solver] = _summarize_solver(set_name, solver, rows, best, null, penalty)
        for solver, line in lines.items():
            if "daqp" in solvers and solver != "daqp":
                line.vs_daqp = _paired_ratio(solvers[solver], solvers["daqp"])
            elif solver == "daqp":
                line.vs_daqp = 1.0
            if "pink" in solvers and solver != "pink":
                line.vs_pink = _paired_ratio(solvers[solver], solvers["pink"])
            elif solver == "pink":
                line.vs_pink = 1.0
        fastest = min((ln.sgm for ln in lines.values()
                       if not math.isnan(ln.sgm) and not ln.own_problem), default=math.nan)
        for line in lines.values():
            if line.own_problem:  # another problem: no ratio to the rows of the set
                line.vs_daqp = line.vs_pink = math.nan
            elif fastest and not math.isnan(fastest):
                line.sgm_ratio = (line.sgm + SGM_SHIFT_US) / (fastest + SGM_SHIFT_US)
        out.extend(lines.values())
    rank = {key: i for i, key in enumerate(order)}
    out.sort(key=lambda s: rank[(s.set, s.solver)])
    return out


def _references(solvers: dict[str, dict[str, Record]]) -> tuple[dict[str, list[float]],
                                                                 dict[str, list[float]]]:
    """Best level vector per problem and the nullspace one where it succeeded."""
    vectors: dict[str, list[list[float]]] = defaultdict(list)
    null: dict[str, list[float]] = {}
    for solver, rows in solvers.items():
        for problem, rec in rows.items():
            if rec.levels is None or not _solved(rec) or solver in NOT_REFERENCE:
                continue
            vectors[problem].append(rec.levels)
            if solver == "nullspace" and not rec.note.startswith(SATURATED):
                null[problem] = rec.levels
    return {p: _lexicographic_best(v) for p, v in vectors.items()}, null


def _summarize_solver(set_name: str, solver: str, rows: dict[str, Record],
                      best: dict[str, list[float]], null: dict[str, list[float]],
                      penalty: float) -> Summary:
    line = Summary(set_name, solver)
    times: list[float] = []
    sgm_values: list[float] = []
    gaps: list[float] = []
    null_gaps: list[float] = []
    tier_hits = dict.fromkeys(TIERS, 0)
    backend: list[float] = []
    for problem, rec in rows.items():
        if not rec.applicable:
            line.not_applicable += 1
            continue
        line.problems += 1
        line.own_problem |= _own_problem(rec)
        line.saturated += int(rec.note.startswith(SATURATED))
        line.trials += rec.trials
        line.successes += rec.successes
        for reason, count in rec.failures.items():
            line.failures[reason] = line.failures.get(reason, 0) + count
        times.extend(rec.times_us)
        line.hard_violation = max(line.hard_violation, rec.hard_violation)
        line.claimed_violation = max(line.claimed_violation, rec.claimed_violation)
        line.nan_count += rec.nan_count
        if not math.isnan(rec.backend_us):
            backend.append(rec.backend_us)
        solved = _solved(rec)
        sgm_values.append(_median_time(rec) if solved and rec.times_us else penalty)
        if rec.levels is not None and problem in best:
            gap = level_gap(rec.levels, best[problem]) if solved else math.inf
            if solved:
                gaps.append(gap)
            for tier, tol in TIERS.items():
                tier_hits[tier] += int(gap <= tol)
            if solved and problem in null:
                null_gaps.append(max(abs(a - b) for a, b in zip(rec.levels, null[problem],
                                                                strict=False)))
    line.timed = len(times)
    if times:
        line.median_us = percentile(times, 50)
        line.p95_us = tail_percentile(times, 95)
        line.p99_us = tail_percentile(times, 99)
        line.max_us = max(times)
    line.sgm = shifted_geometric_mean(sgm_values)
    if gaps:
        line.gap = max(gaps)
    if null_gaps:
        line.gap_nullspace = max(null_gaps)
    if any(p in best for p in rows) and line.problems:
        line.tiers = {tier: hits / line.problems for tier, hits in tier_hits.items()}
    if backend:
        line.backend_us = float(np.median(backend))
    return line
