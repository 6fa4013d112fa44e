"""The report: Wilson intervals, the flat table pandas reads, success by parameter."""

from __future__ import annotations

import csv
import math

import pytest

from uvms_qp.sweep.records import RunTask, blank_record, judge
from uvms_qp.sweep.report import (
    all_bins,
    bin_label,
    parameter_bins,
    summarise,
    wilson_interval,
    write_report,
)


def _wilson(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return centre - half, centre + half


@pytest.mark.parametrize(("k", "n"), [(0, 10), (1, 6), (52, 64), (100, 100), (999, 1000)])
def test_the_success_interval_is_wilsons(k, n):
    assert wilson_interval(k, n) == pytest.approx(_wilson(k, n), abs=1e-12)


def _records(spec, values):
    out = []
    for i, (value, error) in enumerate(values):
        record = blank_record(RunTask.of(spec, i))
        record["status"] = "ok"
        record["parameters"] = {"current.direction": 0.1 * i, "initial.joints": [value, 0.0, 0.0,
                                                                                  0.0]}
        record["metrics"] = {"ee_error_max": error, "level_met_share.0": 1.0,
                             "command_reversals_worst_axis": None}
        record["timing"] = {"wall_time_s": 0.5}
        judge(spec, record)
        out.append(record)
    return out


def test_the_table_has_one_row_per_run_and_one_column_per_field(tiny, tmp_path):
    records = _records(tiny, [(0.01, 0.001), (-0.02, 0.02), (0.03, None)])
    summary = write_report(tiny, records, tmp_path, plots=True)
    with (tmp_path / "runs.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["index"]) for r in rows] == [0, 1, 2]
    assert rows[1]["initial.joints[0]"] == "-0.02"
    assert rows[1]["failed"] == "ee_error_max <= 0.01"
    assert rows[2]["ee_error_max"] == ""  # a missing metric is an empty cell
    assert float(rows[0]["timing.wall_time_s"]) == 0.5
    assert summary["successes"] == 1 and summary["recorded"] == 3
    assert summary["criteria"][0]["missed"] == 2
    assert (tmp_path / "metrics.png").stat().st_size > 0
    assert (tmp_path / "success_by_parameter.png").stat().st_size > 0


def test_success_by_parameter_counts_every_run_once(tiny):
    records = _records(tiny, [(0.001 * i, 0.001 if i % 3 else 0.1) for i in range(30)])
    summary = summarise(tiny, records)
    for name in ("current.direction", "initial.joints"):
        bins = parameter_bins(tiny.variable(name), records)
        assert sum(b["runs"] for b in bins) == 30
        assert sum(b["successes"] for b in bins) == summary["successes"] == 20
        for b in bins:
            assert b["ci"][0] <= b["rate"] <= b["ci"][1]
    metric = summary["metrics"]["ee_error_max"]
    assert metric["min"] <= metric["p5"] <= metric["p50"] <= metric["p95"] <= metric["max"]


def test_every_bin_is_kept_the_empty_ones_too(tiny):
    # sensors.delay is one of 0.0, 0.05: only 0.05 drawn; the directions leave bins empty
    records = _records(tiny, [(0.0, 0.001 if i < 4 else 0.1) for i in range(6)])
    for i, record in enumerate(records):
        record["parameters"]["sensors.delay"] = 0.05
        record["parameters"]["current.direction"] = 0.5 if i == 5 else -0.5 + 0.01 * i
    entries = summarise(tiny, records)["parameters"]
    delay = entries["sensors.delay"]
    assert delay["options"] == [0.0, 0.05]
    assert [(b["value"], b["runs"]) for b in delay["bins"]] == [(0.05, 6)]  # as before
    assert [(b["value"], b["runs"], b["rate"]) for b in all_bins(delay)] == [
        (0.0, 0, None), (0.05, 6, pytest.approx(4 / 6))]
    direction = entries["current.direction"]
    assert direction["edges"][0] == -0.5 and direction["edges"][-1] == 0.5
    every = all_bins(direction)
    assert len(every) == 6 and [b["runs"] for b in every] == [5, 0, 0, 0, 0, 1]
    assert [bin_label(b, i, 6) for i, b in enumerate(every)][::5] == ["[-0.5, -0.333)",
                                                                     "[0.333, 0.5]"]
    assert entries["initial.joints"]["binned_by"] == "norm"
    assert len(all_bins(entries["initial.joints"])) == 1  # every run drew the same norm


def test_there_are_no_more_bins_than_values_drawn(tiny):
    records = _records(tiny, [(0.0, 0.001), (0.0, 0.1), (0.0, 0.001)])
    for record, direction in zip(records, (-0.4, 0.4, 0.4), strict=True):
        record["parameters"]["current.direction"] = direction
    entry = summarise(tiny, records)["parameters"]["current.direction"]
    assert entry["edges"] == [-0.4, 0.0, 0.4]
    assert [(b["runs"], b["successes"]) for b in all_bins(entry)] == [(1, 1), (2, 1)]
