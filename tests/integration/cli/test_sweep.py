"""``uvms-qp sweep``: a sweep end to end, its resume and replay, one-line errors with status 2."""

from __future__ import annotations

import csv
import json
import textwrap
from pathlib import Path

import pytest

from tests.support.scenario_text import bluerov_scenario
from tests.support.sweeps import TINY, write_sweep
from uvms_qp.cli import main
from uvms_qp.cli.sweep import summary_lines
from uvms_qp.sweep import load_sweep
from uvms_qp.sweep.records import RunTask, blank_record, judge
from uvms_qp.sweep.report import summarise
from uvms_qp.sweep.sampling import run_seed


def test_a_sweep_runs_resumes_and_replays(tmp_path, capsys):
    path = write_sweep(tmp_path, runs=3)
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--workers", "2", "--quiet"]) == 0
    assert main(["sweep", str(path), "--out", str(out), "--runs", "4", "--workers", "1",
                 "--no-plots"]) == 0
    printed = capsys.readouterr().out
    assert "4 runs (1 new, 3 resumed, 0 retried) on 1 local worker" in printed
    assert "95 % Wilson interval" in printed
    with (out / "runs.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [int(r["index"]) for r in rows] == [0, 1, 2, 3]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["recorded"] == 4
    for name in ("sweep.json", "runs.jsonl", "metrics.png", "success_by_parameter.png"):
        assert (out / name).is_file(), name
    seed = int(rows[2]["seed"])
    assert seed == run_seed(11, 2)
    replay = tmp_path / "replay"
    assert main(["sweep", str(path), "--out", str(replay), "--replay", str(seed),
                 "--no-plots"]) == 0
    printed = capsys.readouterr().out
    assert f"run of seed {seed}" in printed and "current.direction" in printed
    metrics = json.loads((replay / "results.json").read_text())["metrics"]
    assert metrics["ee_error_max"] == float(rows[2]["ee_error_max"])


@pytest.mark.parametrize(("args", "message"), [
    (["--runs", "0"], "uvms-qp sweep: error: --runs: expected a number of runs in [1, 1000000], "
                      "got 0"),
    (["--workers", "0"], "uvms-qp sweep: error: --workers: expected a positive integer, got 0"),
    (["--workers", "2", "--scheduler", "tcp://127.0.0.1:9"],
     "uvms-qp sweep: error: --workers: give --workers or --scheduler, not both"),
])
def test_bad_options_exit_2_with_one_line(tmp_path, capsys, args, message):
    path = write_sweep(tmp_path)
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_a_bad_sweep_file_exits_2_with_one_line_before_any_run(tmp_path, capsys):
    path = write_sweep(tmp_path, text=TINY.replace("speed = 0.2", "speed = -0.2"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err == ("uvms-qp sweep: error: current.speed: a current speed [m/s] must be >= 0, "
                   "but the spread -0.2 reaches -0.2\n")
    assert not (tmp_path / "out").exists()


def test_a_model_file_named_on_the_command_line_reaches_every_worker(tmp_path, capsys):
    """Each worker process registers the ``--model-path`` files itself: a forkserver or Dask
    worker does not inherit the models its parent registered."""
    from uvms_qp.model import unregister_model

    data = Path(__file__).resolve().parents[2] / "data"
    (tmp_path / "rov.toml").write_text(textwrap.dedent("""
        model = "holdout_rov"
        dt = 0.1
        duration = 0.3

        [initial]
        joints = [0.0, 0.6, 1.2]

        [[levels]]
        [[levels.tasks]]
        type = "end_effector"
        name = "tool"
        position = [0.5707, 0.0, -0.1498]
    """))
    path = write_sweep(tmp_path, runs=2, text="""
        scenario = "rov.toml"
        runs = {runs}
        seed = 3

        [initial]
        joints = {{ uniform = [-0.05, 0.05] }}

        [success]
        ee_error_max = {{ max = 1.0 }}
    """)
    out = tmp_path / "out"
    try:
        assert main(["sweep", str(path), "--out", str(out), "--workers", "2", "--no-plots",
                     "--model-path", str(data / "holdout_rov.toml")]) == 0
    finally:
        unregister_model("holdout_rov")
    printed = capsys.readouterr().out
    records = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    assert "success: 2/2" in printed, records[0]["error"]
    records = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    assert [r["status"] for r in records] == ["ok", "ok"]
    assert main(["sweep", str(path), "--out", str(out)]) == 2
    assert "unknown model 'holdout_rov'" in capsys.readouterr().err


def test_replay_prints_the_run_s_warnings_as_run_does(tmp_path, capsys):
    # the bundled arm is rated 2 kg at full reach: a 3 kg payload is flagged, as by `uvms-qp run`
    (tmp_path / "base.toml").write_text(bluerov_scenario(
        "duration = 0.2", '\n[plant]\ntype = "dynamic"\n'
        '[plant.payload]\ntime = 0.1\nmass = 1.0\n'))
    path = tmp_path / "heavy.toml"
    path.write_text('scenario = "base.toml"\nplant = "dynamic"\nruns = 1\nseed = 3\n'
                    '[payload]\nmass = { uniform = [3.0, 3.5] }\n')
    seed = run_seed(3, 0)
    out = tmp_path / "replay"
    assert main(["sweep", str(path), "--out", str(out), "--replay", str(seed),
                 "--no-plots", "--quiet"]) == 0
    notes = json.loads((out / "results.json").read_text())["warnings"]
    assert notes and "exceeds the arm's rated payload of 2 kg" in notes[0]
    err = capsys.readouterr().err
    assert err.splitlines() == [f"warning: {note}" for note in notes]


def test_the_summary_labels_each_rate_with_its_value_or_range_and_runs(tmp_path):
    spec = load_sweep(write_sweep(tmp_path))
    records = []
    for i in range(6):
        record = blank_record(RunTask.of(spec, i))
        record["status"] = "ok"
        record["parameters"] = {"sensors.delay": 0.05, "current.direction": -0.5 + 0.2 * i}
        record["metrics"] = {"ee_error_max": 0.001 if i < 4 else 0.1, "level_met_share.0": 1.0}
        judge(spec, record)
        records.append(record)
    lines = summary_lines(summarise(spec, records))
    assert "  sensors.delay [s] (one of 0.0, 0.05): 0.0: - (0), 0.05: 67 % (6)" in lines
    direction = next(line for line in lines if line.startswith("  current.direction"))
    assert "[-0.5, -0.333): 100 % (1)" in direction and "[0.333, 0.5]: 0 % (1)" in direction
