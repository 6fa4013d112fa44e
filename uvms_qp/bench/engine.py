"""Run the benchmark: every selected runner on every problem of the selected sets, resumably.

A problem is a case: every runner runs on it in turn (same process, interleaved so that a change
of machine load hits every solver alike). By default the cases run one after the other in this
process, in set order. With ``workers`` or ``scheduler`` they run on the sweep's executors
(:class:`~uvms_qp.sweep.executors.Pool`: local processes, or a Dask cluster), each case in one
worker, which rebuilds the sets from their seed (:func:`bench_case`). After each case its rows
are appended to the JSON and CSV stores; rows whose ``(set, problem, solver)`` key is already
stored are skipped. Cases running side by side share the machine: their times are comparable
within a case, not across a loaded machine.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from concurrent.futures import as_completed
from dataclasses import dataclass, field
from typing import Any

from ..errors import InputError
from ..sweep.executors import Pool
from .metrics import Summary, summarize
from .record import Record
from .report import CsvStore, JsonStore, machine_info
from .runners import make_runner, quiet_stdout, select_runners
from .sets import SET_NAMES, BenchProblem, SetConfig, build_sets

#: Sets built in this process, by (set names, seed, config): a worker builds each once.
_SETS: dict[tuple[tuple[str, ...], int, SetConfig], list[BenchProblem]] = {}


@dataclass(frozen=True)
class BenchCase:
    """One problem to run in a worker: how to rebuild it, and which runners to run on it.

    Attributes:
        sets: The selected set names (the problems are rebuilt from them, the seed and config).
        seed: Seed of the random problems.
        config: Set sizes.
        index: The problem's position in the built sets.
        runners: Names of the runners to run (those whose row is not stored yet).
        repetitions: Timed solves per random/raw problem.
    """

    sets: tuple[str, ...]
    seed: int
    config: SetConfig
    index: int
    runners: tuple[str, ...]
    repetitions: int


def _problems(sets: tuple[str, ...], seed: int, config: SetConfig) -> list[BenchProblem]:
    key = (sets, seed, config)
    if key not in _SETS:
        _SETS[key] = build_sets(list(sets), seed, config)
    return _SETS[key]


def bench_case(case: BenchCase) -> list[Record]:
    """Run the runners of ``case`` on its problem (in a worker) and return their rows."""
    problem = _problems(case.sets, case.seed, case.config)[case.index]
    rows = []
    for name in case.runners:
        with quiet_stdout():
            rows.append(make_runner(name).run(problem, case.repetitions))
    return rows


@dataclass
class BenchOutcome:
    """What a benchmark run produced.

    Attributes:
        records: Every row (stored earlier and new).
        summaries: One line per (set, solver) over all rows.
        notes: Skipped runners and similar remarks.
        new_rows: Rows computed by this run.
        skipped_rows: Rows already stored (resumed).
        wall_time: Duration of this run [s].
        machine: Machine facts at the start of the run.
    """

    records: list[Record]
    summaries: list[Summary]
    notes: list[str] = field(default_factory=list)
    new_rows: int = 0
    skipped_rows: int = 0
    wall_time: float = 0.0
    machine: dict[str, Any] = field(default_factory=dict)


def run_benchmark(
    sets: list[str] | None = None,
    solvers: list[str] | None = None,
    *,
    repetitions: int = 10,
    seed: int = 0,
    config: SetConfig | None = None,
    json_path: str | None = None,
    csv_path: str | None = None,
    progress: Callable[[int, int, str], None] | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
) -> BenchOutcome:
    """Run the benchmark and return its rows and table.

    Args:
        sets: Set names (default: all of :data:`~uvms_qp.bench.sets.SET_NAMES`).
        solvers: Runner name patterns (shell globs; default: every available runner).
        repetitions: Timed solves per problem in the ``random`` and ``raw`` sets.
        seed: Seed of the random problems.
        config: Set sizes (default :class:`~uvms_qp.bench.sets.SetConfig`).
        json_path: JSON store to append to (resumable), or None.
        csv_path: CSV store to append to (resumable), or None.
        progress: Called as ``progress(done, total, label)`` after each row (after each case
            when the cases run on workers).
        workers: Run the cases on this many local worker processes.
        scheduler: Run the cases on the Dask cluster of this scheduler (``tcp://host:8786``).

    Raises:
        InputError: unknown set, a solver pattern matching nothing, a bad repetition count or a
            store file that is not a benchmark file.
        ConfigError: a bad ``workers``, an unreachable ``scheduler`` (before any case runs).
    """
    if not isinstance(repetitions, int) or repetitions < 1:
        raise InputError(f"--repetitions: expected a positive integer, got {repetitions!r}")
    config = config or SetConfig()
    runners, notes = select_runners(solvers)
    chosen_sets = tuple(sets or SET_NAMES)
    problems = _problems(chosen_sets, seed, config)
    json_store = JsonStore(json_path) if json_path else None
    csv_store = CsvStore(csv_path) if csv_path else None
    stored: dict[tuple[str, str, str], Record] = {}
    json_keys: set[tuple[str, str, str]] = set()
    csv_keys: set[tuple[str, str, str]] = set()
    for store, keys in ((json_store, json_keys), (csv_store, csv_keys)):
        if store is not None:
            for rec in store.records():
                stored.setdefault(rec.key, rec)
                keys.add(rec.key)
    machine = machine_info()
    options = {"sets": list(chosen_sets), "solvers": [r.name for r in runners],
               "repetitions": repetitions, "seed": seed, "config": config.__dict__}
    if json_store is not None:
        json_store.start_run({"machine": machine, "options": options,
                              "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})
    started = time.perf_counter()
    total = len(problems) * len(runners)
    done = 0
    new: list[Record] = []
    skipped = 0
    def store_rows(problem: BenchProblem, batch: list[Record]) -> None:
        # a row stored in only one of the two files is copied into the other
        for store, has in ((json_store, json_keys), (csv_store, csv_keys)):
            if store is None:
                continue
            missing = [rec for k, rec in stored.items()
                       if k not in has and k[:2] == (problem.set, problem.name)]
            rows = batch + missing
            if rows:
                store.append(rows)
                has.update(r.key for r in rows)
        new.extend(batch)

    if workers is None and scheduler is None:
        for problem in problems:
            batch: list[Record] = []
            for runner in runners:
                key = (problem.set, problem.name, runner.name)
                done += 1
                if key in stored:
                    skipped += 1
                else:
                    with quiet_stdout():
                        rec = runner.run(problem, repetitions)
                    batch.append(rec)
                if progress is not None:
                    progress(done, total, f"{problem.set}/{problem.name} {runner.name}")
            store_rows(problem, batch)
    else:
        cases: dict[Any, BenchProblem] = {}
        with Pool(workers, scheduler) as pool:
            for index, problem in enumerate(problems):
                names = tuple(r.name for r in runners
                              if (problem.set, problem.name, r.name) not in stored)
                skipped += len(runners) - len(names)
                case = BenchCase(chosen_sets, seed, config, index, names, repetitions)
                cases[pool.submit(bench_case, case)] = problem
            for future in as_completed(cases):
                problem = cases[future]
                store_rows(problem, future.result())
                done += len(runners)
                if progress is not None:
                    progress(done, total, f"{problem.set}/{problem.name}")
    wall = time.perf_counter() - started
    if json_store is not None:
        json_store.finish_run({"wall_time_s": wall, "new_rows": len(new),
                               "skipped_rows": skipped, "loadavg_end": list(os.getloadavg())})
    current = {(p.set, p.name) for p in problems}
    chosen = {r.name for r in runners}
    records = [r for r in stored.values() if (r.set, r.problem) in current and r.solver in chosen]
    records += new
    return BenchOutcome(records, summarize(records), notes, len(new), skipped, wall, machine)

