"""The engine: records appended as runs finish, resume, dead workers, Dask, replay, errors."""

from __future__ import annotations

import json

import pytest

import uvms_qp.sweep.executors as executors
import uvms_qp.sweep.records as records_module
from uvms_qp.errors import ConfigError
from uvms_qp.sweep import Pool, RunTask, run_one, run_seed, run_sweep, simulate_run
from uvms_qp.sweep.outcome import run_outcome
from uvms_qp.testing.sweep_faults import AlwaysKill, KillOnce

#: What a run's record says about the run itself (not the machine, nor how it was scheduled).
SAME = ("index", "seed", "status", "success", "failed", "parameters", "metrics",
        "status_counts", "stage_counts", "error")


def comparable(records):
    return [{key: r[key] for key in SAME} for r in records]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted 6-run sweep on two local workers: its spec and records."""
    from tests.support.sweeps import write_sweep
    from uvms_qp.sweep import load_sweep

    folder = tmp_path_factory.mktemp("reference")
    spec = load_sweep(write_sweep(folder))
    outcome = run_sweep(spec, folder / "out", workers=2)
    return spec, outcome.records


def test_every_run_is_recorded_once_with_its_outcome(reference, tmp_path):
    spec, records = reference
    assert [r["index"] for r in records] == list(range(spec.runs))
    assert all(r["status"] == "ok" and r["attempts"] == 1 for r in records)
    assert len({r["seed"] for r in records}) == spec.runs
    assert 0 < sum(r["success"] for r in records) < spec.runs  # the criteria decide
    for r in records:
        assert r["success"] == (not r["failed"])
        assert r["metrics"]["ee_error_max"] is not None


def test_a_resumed_sweep_runs_only_what_is_missing(reference, tmp_path):
    spec, expected = reference
    stopped_at = []

    def stop_after_three(done, total, failures):
        if done == 3 and not stopped_at:
            stopped_at.append(done)
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path, workers=2, progress=stop_after_three)
    journal = tmp_path / "runs.jsonl"
    kept = journal.read_text().splitlines()
    assert len(kept) == 3
    with journal.open("a") as handle:  # a line cut by the kill
        handle.write('{"index": 5, "seed": 1')
    outcome = run_sweep(spec, tmp_path, workers=2)
    assert (outcome.resumed, outcome.new) == (3, spec.runs - 3)
    assert comparable(outcome.records) == comparable(expected)
    lines = [json.loads(line) for line in journal.read_text().splitlines()]
    assert sorted(r["index"] for r in lines) == list(range(spec.runs))
    again = run_sweep(spec, tmp_path, workers=1)
    assert (again.resumed, again.new) == (spec.runs, 0)


def test_a_killed_worker_costs_only_its_runs_which_are_retried_once(reference, tmp_path):
    spec, expected = reference
    marker = tmp_path / "killed"
    outcome = run_sweep(spec, tmp_path / "out", workers=2,
                        execute=KillOnce(index=2, marker=str(marker)))
    assert marker.exists()  # a worker did die
    assert [r["index"] for r in outcome.records] == list(range(spec.runs))
    lines = (tmp_path / "out" / "runs.jsonl").read_text().splitlines()
    assert len(lines) == spec.runs
    assert outcome.records[2]["attempts"] == 2
    assert 1 <= outcome.retried <= 2  # run 2 and at most the run the other worker held
    assert comparable(outcome.records) == comparable(expected)


def test_a_run_whose_worker_always_dies_is_recorded_lost(tiny, tmp_path):
    spec = tiny.with_runs(3)
    outcome = run_sweep(spec, tmp_path, workers=1, execute=AlwaysKill(index=1))
    statuses = [r["status"] for r in outcome.records]
    assert statuses == ["ok", "lost", "ok"]
    lost = outcome.records[1]
    assert lost["attempts"] == 2 and not lost["success"]
    assert "died" in lost["error"] and lost["parameters"]


def test_a_run_that_raises_is_recorded_with_its_error_and_seed(tiny, monkeypatch):
    def broken(*args, **kwargs):
        raise FloatingPointError("the plant blew up")

    monkeypatch.setattr(records_module, "simulate_run", broken)
    record = run_one(RunTask.of(tiny, 4))
    assert record["status"] == "error" and not record["success"]
    assert record["error"] == "FloatingPointError: the plant blew up"
    assert record["seed"] == RunTask.of(tiny, 4).seed
    assert set(record["parameters"]) == {v.name for v in tiny.variables}


def test_a_run_replayed_from_its_seed_gives_the_same_metrics(reference):
    spec, records = reference
    record = records[4]
    parameters, result = simulate_run(spec, record["seed"])
    assert parameters == record["parameters"]
    assert run_outcome(result)["metrics"] == record["metrics"]


def test_a_dask_cluster_gives_the_same_records_as_the_local_pool(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    spec, expected = reference
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        outcome = run_sweep(spec, tmp_path, scheduler=cluster.scheduler_address)
    assert outcome.pool.startswith("Dask at tcp://127.0.0.1:")
    assert comparable(outcome.records) == comparable(expected)


def test_a_dask_worker_killed_mid_sweep_costs_nothing_but_its_runs(reference, tmp_path):
    """Dask reschedules a dead worker's runs on the survivors (its nanny restarts the dead one)."""
    distributed = pytest.importorskip("distributed")
    spec, expected = reference
    marker = tmp_path / "killed"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        outcome = run_sweep(spec, tmp_path / "out", scheduler=cluster.scheduler_address,
                            execute=KillOnce(index=2, marker=str(marker)))
    assert marker.exists()  # a worker did die
    lines = (tmp_path / "out" / "runs.jsonl").read_text().splitlines()
    assert sorted(json.loads(line)["index"] for line in lines) == list(range(spec.runs))
    assert comparable(outcome.records) == comparable(expected)


def test_an_unreachable_scheduler_fails_before_any_run(tiny, tmp_path, monkeypatch):
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 0.5)
    with pytest.raises(ConfigError, match=r"^--scheduler: cannot reach the Dask scheduler at "
                                          r"'tcp://127.0.0.1:9'"):
        run_sweep(tiny, tmp_path / "out", scheduler="tcp://127.0.0.1:9")
    assert not (tmp_path / "out" / "runs.jsonl").exists()


def test_another_sweep_in_the_same_folder_is_refused(reference, tiny, tmp_path):
    spec, _ = reference
    run_sweep(spec.with_runs(1), tmp_path, workers=1)
    with pytest.raises(ConfigError, match=r"^--out: .* holds the records of another sweep"):
        run_sweep(tiny.__class__(**{**tiny.__dict__, "seed": 12}), tmp_path, workers=1)


def test_bad_worker_counts_are_refused():
    with pytest.raises(ConfigError, match=r"^--workers: expected a positive integer, got 0"):
        Pool(workers=0)


def test_a_perturbed_start_does_not_warn_for_every_run(tiny):
    import warnings

    from uvms_qp.errors import ScenarioWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error", ScenarioWarning)
        # run 4 starts with the tool 1.4 cm off its path: the base scenario would warn
        simulate_run(tiny, run_seed(tiny.seed, 4))
