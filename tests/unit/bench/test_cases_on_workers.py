"""The benchmark's cases on worker processes: the same rows as in-process, stored resumably."""

from __future__ import annotations

from uvms_qp.bench import SetConfig, run_benchmark


def _rows(outcome):
    return sorted((r.key, r.trials, r.successes, dict(r.failures), r.levels)
                  for r in outcome.records)


def test_cases_on_two_workers_give_the_rows_of_one_process(tmp_path):
    config = SetConfig(max_steps=4, scenarios=("bluerov2_demo",), random_count=2, raw_per_case=1)
    options = {"sets": ["scenarios", "random", "raw"], "solvers": ["daqp", "weighted"],
               "repetitions": 2, "seed": 3, "config": config}
    alone = run_benchmark(**options)
    stored = tmp_path / "bench.csv"
    parallel = run_benchmark(**options, workers=2, csv_path=str(stored))
    assert _rows(parallel) == _rows(alone)
    assert parallel.new_rows == len(alone.records)
    resumed = run_benchmark(**options, workers=2, csv_path=str(stored))
    assert (resumed.new_rows, resumed.skipped_rows) == (0, len(alone.records))
