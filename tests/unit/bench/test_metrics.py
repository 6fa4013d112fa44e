"""Aggregation of benchmark rows: ranking, gaps, ratios, percentiles, row round trips."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uvms_qp.bench.metrics import (
    _lexicographic_best,
    level_gap,
    shifted_geometric_mean,
    summarize,
)
from uvms_qp.bench.record import (
    OWN_PROBLEM,
    SATURATED,
    Record,
    tail_percentile,
    tail_samples,
)


def test_shifted_geometric_mean_matches_definition():
    values = [1.0, 10.0, 100.0]
    expected = (11.0 * 20.0 * 110.0) ** (1 / 3) - 10.0
    assert shifted_geometric_mean(values) == pytest.approx(expected, rel=1e-12)
    assert shifted_geometric_mean([5.0, 5.0]) == pytest.approx(5.0)
    assert math.isnan(shifted_geometric_mean([]))


def test_lexicographic_best_prefers_higher_levels():
    # b is better at level 0, so its worse level 1 does not matter
    a, b, c = [1.0, 0.0], [0.5, 3.0], [0.5, 2.0]
    assert _lexicographic_best([a, b]) == [0.5, 3.0]
    assert _lexicographic_best([a, b, c]) == [0.5, 2.0]


def test_level_gap_stops_at_first_worse_level():
    best = [0.5, 2.0, 1.0]
    assert level_gap([0.5, 2.0, 1.0], best) == 0.0
    # worse at level 1 by 1.0 (relative to max(1, 2.0) -> 0.5); level 2 is not considered
    assert level_gap([0.5, 3.0, 0.0], best) == pytest.approx(0.5)
    assert level_gap([0.5 + 1e-9, 2.0, 5.0], best) == pytest.approx(4.0, rel=1e-6)


def _rec(solver, problem, times, ok=True, levels=None, set_="raw"):
    r = Record(set_, problem, solver, trials=len(times), successes=len(times) if ok else 0,
               times_us=list(times), levels=levels)
    if not ok:
        r.fail("backend_error", len(times))
    return r


def test_summarize_rates_ratios_gaps_and_ranking():
    recs = [
        _rec("daqp", "p1", [10, 10, 10], levels=[0.0, 1.0]),
        _rec("daqp", "p2", [20, 20], levels=[1.0]),
        _rec("slow", "p1", [40, 40, 40], levels=[0.0, 1.5]),
        _rec("slow", "p2", [60, 60], ok=False),
        _rec("pink", "p1", [20, 20, 20], levels=[0.0, 0.0]),  # never the reference
        Record("raw", "p2", "pink", note="n/a: not expressible"),
    ]
    by = {s.solver: s for s in summarize(recs)}
    daqp, slow, pink = by["daqp"], by["slow"], by["pink"]
    assert daqp.success_rate == 1.0 and slow.success_rate == pytest.approx(3 / 5)
    assert slow.failures == {"backend_error": 2}
    assert slow.vs_daqp == pytest.approx(np.median([4.0, 3.0]))
    assert daqp.vs_pink == pytest.approx(0.5) and pink.not_applicable == 1
    assert daqp.gap == 0.0 and slow.gap == pytest.approx(0.5)
    assert daqp.tiers == {"high": 1.0, "low": 1.0}
    assert slow.tiers == {"high": 0.0, "low": 0.0}
    assert daqp.sgm_ratio == pytest.approx(1.0) and slow.sgm_ratio > 1.0
    assert daqp.median_us == 10.0 and daqp.max_us == 20.0


def test_record_round_trips_through_csv_and_json():
    r = Record("random", "uvms-s0-001", "cascade:osqp", trials=3, successes=1,
               failures={"backend_error": 1, "hard_violation": 1}, times_us=[1.5, 2.25, 3.0],
               hard_violation=2e-6, claimed_violation=2e-6, nan_count=0,
               levels=[0.1, 0.0, 1e-12], backend_us=float("nan"), note="x")
    for back in (Record.from_row(r.to_row()), Record.from_dict(r.to_dict())):
        assert back.key == r.key and back.failures == r.failures
        assert back.times_us == pytest.approx(r.times_us)
        assert back.levels == pytest.approx(r.levels, rel=1e-11)
        assert math.isnan(back.backend_us) and back.trials == back.successes + back.failed


def test_tail_percentiles_need_enough_samples():
    """A p99 of fewer than 100 samples (a p95 of fewer than 20) is the maximum under another
    name: it is not reported."""
    assert tail_samples(95) == 20 and tail_samples(99) == 100
    few = [float(v) for v in range(1, 31)]
    assert math.isnan(tail_percentile(few, 99))
    assert tail_percentile(few, 95) == pytest.approx(np.percentile(few, 95))
    many = [float(v) for v in range(1, 101)]
    assert tail_percentile(many, 99) == pytest.approx(99.01)
    line = summarize([_rec("daqp", "p1", few)])[0]
    assert line.timed == 30 and line.median_us == 15.5 and line.max_us == 30.0
    assert math.isnan(line.p99_us) and not math.isnan(line.p95_us)
    row = _rec("daqp", "p1", few[:10]).to_row()
    assert row["p95_us"] == "nan" and float(row["median_us"]) == 5.5


def test_a_row_of_its_own_problem_gets_no_ratio_and_sets_no_ranking():
    """Pink on a scenario solves the tracked frame alone: no time ratio against the stack."""
    recs = [
        _rec("daqp", "s1", [100, 100], set_="scenarios"),
        _rec("slow", "s1", [300, 300], set_="scenarios"),
        _rec("pink", "s1", [50, 50], set_="scenarios"),
        _rec("daqp", "u1", [10, 10], set_="random"),
        _rec("pink", "u1", [20, 20], set_="random"),
    ]
    recs[2].note = OWN_PROBLEM
    by = {(s.set, s.solver): s for s in summarize(recs)}
    pink = by["scenarios", "pink"]
    assert pink.own_problem and pink.success_rate == 1.0
    assert math.isnan(pink.vs_daqp) and math.isnan(pink.sgm_ratio)
    assert math.isnan(by["scenarios", "daqp"].vs_pink)
    assert by["scenarios", "daqp"].sgm_ratio == pytest.approx(1.0)  # not pink's faster time
    assert by["scenarios", "slow"].vs_daqp == pytest.approx(3.0)
    # the same solver on a problem it solves as the others do keeps its ratios
    assert not by["random", "pink"].own_problem
    assert by["random", "pink"].vs_daqp == pytest.approx(2.0)


def test_saturated_rows_are_counted_and_never_the_nullspace_reference():
    clipped = _rec("nullspace", "p1", [5, 5], levels=[0.0, 9.0])
    clipped.note = SATURATED
    exact = _rec("nullspace", "p2", [5, 5], levels=[0.0, 1.0])
    others = [_rec("daqp", p, [1, 1], levels=[0.0, 1.0]) for p in ("p1", "p2")]
    by = {s.solver: s for s in summarize([clipped, exact, *others])}
    assert by["nullspace"].saturated == 1
    assert by["daqp"].gap_nullspace == 0.0  # compared on p2 only (on p1 it would be 8)
