"""Run a sweep: every run not yet recorded, on a pool, each record appended as it completes.

The output folder holds ``sweep.json`` (what the sweep is: its name, fingerprint, seed, scenario,
variables and criteria) and ``runs.jsonl`` (one record per finished run, in the order they
finished, :mod:`uvms_qp.sweep.records`). Nothing is lost:

- each record is appended and flushed as its run completes, so a sweep killed half-way keeps
  every run it finished; the same command resumes it and runs only the missing indices (a
  partial last line, cut by the kill, is dropped);
- a run that raises is a record (``status = "error"``, with its seed), not the end of the sweep;
- a local worker that dies breaks the process pool: the pool is rebuilt and the runs that were in
  flight (at most one per worker) are submitted again, once; a run whose worker dies on its
  second attempt too is recorded as ``lost``. A Dask cluster reschedules the tasks of a dead
  worker itself; a task whose future still fails is submitted again once, the same way.

A folder holding another sweep's records (another file, seed or scenario: another
:meth:`~uvms_qp.sweep.spec.SweepSpec.digest`) is refused, so two sweeps never mix.
"""

from __future__ import annotations

import dataclasses
import json
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from ..sim.results import provenance
from .executors import Pool
from .records import RunTask, lost_record, run_one
from .spec import SweepSpec

SWEEP_FILE = "sweep.json"
RUNS_FILE = "runs.jsonl"
#: Attempts a run gets when its worker dies under it.
MAX_ATTEMPTS = 2

#: ``progress(done, total, failures)`` after each recorded run.
Progress = Callable[[int, int, int], None]


@dataclass
class SweepOutcome:
    """What a sweep produced.

    Attributes:
        records: The record of every run of the sweep (indices below ``spec.runs``), by index.
        new: Runs executed by this call.
        resumed: Runs found already recorded.
        retried: Runs submitted again after their worker died.
        wall_time: Duration of this call [s].
        out: The output folder.
        pool: What the runs executed on (``2 local workers``).
    """

    records: list[dict[str, Any]]
    new: int = 0
    resumed: int = 0
    retried: int = 0
    wall_time: float = 0.0
    out: Path = field(default_factory=Path)
    pool: str = ""


def sweep_identity(spec: SweepSpec) -> dict[str, Any]:
    """The content of ``sweep.json``."""
    return {
        "name": spec.name, "digest": spec.digest(), "seed": spec.seed,
        "scenario": spec.scenario, "plant": spec.plant, "duration": spec.duration,
        "source": None if spec.source is None else str(spec.source),
        "variables": {v.name: {"law": v.dist.describe(), "count": v.count, "unit": v.unit,
                               "varies": v.dist.varies} for v in spec.variables},
        "criteria": [c.describe() for c in spec.criteria],
    }


class Journal:
    """``runs.jsonl`` of an output folder: the records so far, and appending one more."""

    def __init__(self, out: Path, spec: SweepSpec) -> None:
        self.out = out
        self.path = out / RUNS_FILE
        identity = out / SWEEP_FILE
        digest = spec.digest()
        if identity.exists():
            try:
                stored = json.loads(identity.read_text(encoding="utf-8")).get("digest")
            except (OSError, ValueError, AttributeError):
                stored = None
            if stored != digest:
                raise ConfigError(
                    f"{str(out)!r} holds the records of another sweep (fingerprint {stored}, "
                    f"this one {digest}: another file, seed or scenario); give another folder",
                    "--out")
        elif self.path.exists():
            raise ConfigError(f"{str(out)!r} holds a {RUNS_FILE} without {SWEEP_FILE}; give "
                              "another folder", "--out")
        self.identity = {**sweep_identity(spec), "provenance": provenance()}
        self.records = self._read()

    def start(self) -> None:
        """Write ``sweep.json`` (the folder now holds this sweep's records)."""
        self.out.mkdir(parents=True, exist_ok=True)
        (self.out / SWEEP_FILE).write_text(json.dumps(self.identity, indent=1) + "\n",
                                           encoding="utf-8")

    def _read(self) -> dict[int, dict[str, Any]]:
        if not self.path.exists():
            return {}
        raw = self.path.read_bytes()
        keep = raw if raw.endswith(b"\n") or not raw else raw[: raw.rfind(b"\n") + 1]
        if len(keep) != len(raw):  # a line cut by a kill: drop it
            self.path.write_bytes(keep)
        records: dict[int, dict[str, Any]] = {}
        for number, line in enumerate(keep.decode("utf-8").splitlines(), 1):
            if not line.strip():
                continue
            try:
                record = json.loads(line)
                index = int(record["index"])
            except (ValueError, KeyError, TypeError):
                raise ConfigError(f"{self.path}: line {number} is not a run record",
                                  "--out") from None
            records.setdefault(index, record)
        return records

    def append(self, record: dict[str, Any]) -> None:
        """Write one record as a line and flush it (it survives a kill of this process)."""
        line = json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n"
        with self.path.open("a", encoding="utf-8") as handle:
            handle.write(line)
            handle.flush()
        self.records.setdefault(int(record["index"]), record)


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Progress | None = None,
    execute: Callable[[RunTask], dict[str, Any]] = run_one,
    pool: Pool | None = None,
) -> SweepOutcome:
    """Run every run of ``spec`` not yet recorded in ``out`` and return all the records.

    Args:
        spec: The sweep.
        out: Output folder (created; resumed when it holds this sweep's records).
        workers: Local worker processes (default: the usable CPUs).
        scheduler: Dask scheduler address, instead of local workers.
        progress: Called as ``progress(done, total, failures)`` after each recorded run.
        execute: The function a worker calls on a :class:`~uvms_qp.sweep.records.RunTask`
            (default :func:`~uvms_qp.sweep.records.run_one`; a module-level function).
        pool: An open pool to use (and leave open), instead of opening one.

    Raises:
        ConfigError: ``out`` holds another sweep, a bad ``workers``, an unreachable scheduler;
            all before any run starts.
    """
    started = time.perf_counter()
    directory = Path(out)
    journal = Journal(directory, spec)
    done_before = {i for i in journal.records if i < spec.runs}
    todo = deque(RunTask.of(spec, i) for i in range(spec.runs) if i not in done_before)
    outcome = SweepOutcome([], resumed=len(done_before), out=directory)
    failures = sum(1 for i in done_before if not journal.records[i].get("success"))
    own = pool is None
    pool = pool or Pool(workers, scheduler)
    outcome.pool = pool.describe()
    try:
        journal.start()
    except OSError:
        if own:
            pool.close()
        raise

    def record(result: dict[str, Any]) -> None:
        nonlocal failures
        if int(result["index"]) in journal.records:  # finished just as its pool broke
            return
        journal.append(result)
        outcome.new += 1
        failures += 0 if result.get("success") else 1
        if progress is not None:
            progress(len(done_before) + outcome.new, spec.runs, failures)

    def again(task: RunTask, reason: str) -> None:
        if task.attempts < MAX_ATTEMPTS:
            outcome.retried += 1
            todo.appendleft(dataclasses.replace(task, attempts=task.attempts + 1))
        else:
            record(lost_record(task, reason))

    if progress is not None:
        progress(len(done_before), spec.runs, failures)
    inflight: dict[Future[Any], RunTask] = {}
    try:
        while todo or inflight:
            broken = False
            while todo and len(inflight) < pool.window:
                task = todo.popleft()
                try:
                    inflight[pool.submit(execute, task)] = task
                except BrokenProcessPool:
                    todo.appendleft(task)
                    broken = True
                    break
            if not broken:
                finished, _ = wait(list(inflight), return_when=FIRST_COMPLETED)
                for future in finished:
                    task = inflight.pop(future)
                    error = future.exception()
                    if error is None:
                        record(future.result())
                    elif isinstance(error, BrokenProcessPool):
                        broken = True
                        again(task, "its worker process died on each attempt")
                    else:
                        again(task, f"its worker failed on each attempt: "
                                    f"{type(error).__name__}: {error}"[:1000])
            if broken:
                # every run still in the broken pool fails with it: keep what finished, then
                # submit the rest again on a new pool
                for future, task in list(inflight.items()):
                    if future.done() and future.exception() is None:
                        record(future.result())
                    else:
                        again(task, "its worker process died on each attempt")
                inflight.clear()
                pool.rebuild()
    finally:
        if own:
            pool.close()
    outcome.records = [journal.records[i] for i in sorted(journal.records) if i < spec.runs]
    outcome.wall_time = time.perf_counter() - started
    return outcome
