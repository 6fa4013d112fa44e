"""One run of a sweep, from its index to its record: the function the workers execute.

:func:`run_one` draws the run's parameters from its seed, builds its scenario, simulates it and
returns its record, a plain dict that is one line of ``runs.jsonl``:

- ``index``, ``seed``: the run's index in the sweep and its seed (``--replay SEED`` re-runs it);
- ``status``: ``ok`` (ran to the end), ``stopped`` (the plant diverged: the metrics are those of
  the steps before), ``error`` (the run raised: ``error`` says what) or ``lost`` (its worker
  died on each attempt);
- ``success``: status ``ok`` and every criterion of ``[success]`` met; ``failed``: the criteria
  the run missed (``ee_error_final <= 0.005``);
- ``parameters``: every value the run drew, by its name in the sweep file;
- ``metrics``: the run's metrics, flat (:mod:`uvms_qp.sweep.outcome`); ``status_counts``,
  ``stage_counts``: steps per controller status and per fallback stage; ``timing``: what
  measures the machine (step times, wall time);
- ``error``, ``stopped``: the exception (``Type: message``) or the early stop, else None;
- ``attempts``: how many times the run was started (2 after a dead worker).

A run never raises out of :func:`run_one`: an exception becomes an ``error`` record with the
seed, so the sweep goes on. Runs in one process take turns (a lock): the model's buffers are the
process's, and a Dask worker may run several tasks in threads.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..hqp.linalg import one_blas_thread
from ..model import model_names
from ..sim.model_file import register_model_file
from ..sim.runner import simulate
from .outcome import run_outcome
from .realise import realise
from .sampling import draw, run_seed
from .spec import SweepSpec

#: Statuses of a record.
STATUSES = ("ok", "stopped", "error", "lost")
_LOCK = threading.Lock()
#: Model files this process registered, with their model's name.
_REGISTERED: dict[Path, str] = {}


@dataclass(frozen=True)
class RunTask:
    """One run to execute: the sweep and the run's index and seed (plain, picklable data)."""

    spec: SweepSpec
    index: int
    seed: int
    attempts: int = 1

    @classmethod
    def of(cls, spec: SweepSpec, index: int) -> RunTask:
        """Run ``index`` of ``spec``, with its seed."""
        return cls(spec, index, run_seed(spec.seed, index))


def blank_record(task: RunTask, parameters: dict[str, Any] | None = None) -> dict[str, Any]:
    """A record with the run's identity and no outcome yet."""
    return {
        "index": task.index, "seed": task.seed, "status": "error", "success": False,
        "failed": [], "parameters": parameters or {}, "metrics": {}, "status_counts": {},
        "stage_counts": {}, "timing": {}, "error": None, "stopped": None,
        "attempts": task.attempts,
    }


def judge(spec: SweepSpec, record: dict[str, Any]) -> None:
    """Set ``success`` and ``failed`` of a record from its status and the criteria."""
    failed = [c.describe() for c in spec.criteria if not c.holds(record["metrics"])]
    record["failed"] = failed
    record["success"] = record["status"] == "ok" and not failed


def register_model_files(paths: tuple[Path, ...]) -> None:
    """Register the models of ``paths`` in this process, each file once.

    A worker process does not inherit the models its parent registered (a forkserver or a Dask
    worker starts from a fresh import), so each registers the sweep's model files itself.
    """
    for path in paths:
        if _REGISTERED.get(path) not in model_names():
            _REGISTERED[path] = register_model_file(path, replace=True)


def simulate_run(spec: SweepSpec, seed: int, parameters: dict[str, Any] | None = None
                 ) -> tuple[dict[str, Any], Any]:
    """Draw, build and simulate the run of seed ``seed``: its parameters and its result.

    The run's linear algebra uses one BLAS thread (:data:`~uvms_qp.hqp.linalg.one_blas_thread`):
    its matrices are small, and the sweep's parallelism is its processes (a second BLAS thread
    per worker would contend for the cores the other workers use).

    Args:
        spec: The sweep.
        seed: The run's seed.
        parameters: The run's draws, when already made (``draw(spec.variables, seed)``).
    """
    register_model_files(spec.model_files)
    if parameters is None:
        parameters = draw(spec.variables, seed)
    with one_blas_thread:
        return parameters, simulate(realise(spec, parameters, seed))


def run_one(task: RunTask) -> dict[str, Any]:
    """Execute one run and return its record (never raises for a failure of the run)."""
    record = blank_record(task)
    try:
        record["parameters"] = draw(task.spec.variables, task.seed)
        with _LOCK:
            started = time.process_time()
            _, result = simulate_run(task.spec, task.seed, record["parameters"])
            cpu = time.process_time() - started
        record.update(run_outcome(result))
        record["timing"]["cpu_time_s"] = cpu
        stopped = getattr(result, "stopped", None)
        record["stopped"] = stopped
        record["status"] = "ok" if stopped is None else "stopped"
    except Exception as exc:  # recorded with the seed: the sweep goes on
        record["status"] = "error"
        record["error"] = f"{type(exc).__name__}: {exc}"[:1000]
    judge(task.spec, record)
    return record


def lost_record(task: RunTask, reason: str) -> dict[str, Any]:
    """The record of a run whose worker died on each of its attempts."""
    record = blank_record(task, draw(task.spec.variables, task.seed))
    record["status"] = "lost"
    record["error"] = reason
    judge(task.spec, record)
    return record
