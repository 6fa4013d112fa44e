"""Throughput of a sweep on local workers, and what the engine costs per run.

Two figures on the same sweep (the bundled ``bluerov2_demo_sweep`` by default, ``--runs`` runs):

1. *Scaling*: runs per minute on 1 and on 2 local worker processes (``run_sweep(workers=N)``,
   each into a fresh folder, the pool's start-up included), repeated ``--repeats`` times
   interleaved (1, 2, 1, 2, ...) so that a change of machine load hits both alike; medians and
   their ratio (goal on a 2-core machine: >= 1.8). Beside it, the machine's own speed-up of a
   pure-Python loop on 2 processes over 1, measured before and after each repeat: what the
   cores give at that moment (a shared or virtual machine may give less than its count).
2. *Engine overhead*: the same runs as a plain loop in this process (draw, build, simulate, flat
   metrics: :func:`uvms_qp.sweep.simulate_run` and ``run_outcome``; no pool, no file), against
   the engine on one worker whose pool was opened and warmed before the clock starts (pickling
   each task and its record, the futures, the appended line, the report's bookkeeping), per run
   (goal: <= 5 %); the same in CPU time (this process's, plus each run's as its worker measured
   it: what a loaded machine does not distort; a worker's pickling of its task and record is
   left out of it). The pool's one-time start (a forkserver importing the library, a worker) is
   reported apart: it is paid once per sweep, not per run.

Usage: ``python benchmarks/bench_sweep.py [--sweep NAME|FILE] [--runs N] [--repeats K]``
``[--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from uvms_qp.sweep import Pool, load_sweep, run_seed, run_sweep, simulate_run
from uvms_qp.sweep.outcome import run_outcome

#: Iterations of the pure-Python loop that measures what parallelism the machine gives now.
BURN = 5_000_000


def _burn(count: int) -> float:
    total = 0
    for i in range(count):
        total += i * i
    return float(total > 0)


def _machine_speed_up() -> float:
    """Speed-up of 4 equal pure-Python loops on 2 processes over 1: the cores the machine gives.

    The reference of the sweep's own speed-up: on a machine whose cores other jobs (or other
    virtual machines on the same host) hold, it is below 2 whatever the sweep does.
    """
    times = {}
    for workers in (1, 2):
        with ProcessPoolExecutor(workers) as pool:
            list(pool.map(_burn, [1000] * workers))  # start the processes
            started = time.perf_counter()
            list(pool.map(_burn, [BURN] * 4))
            times[workers] = time.perf_counter() - started
    return times[1] / times[2]


def _sweep_time(spec, workers: int) -> float:
    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        run_sweep(spec, Path(folder) / "out", workers=workers)
        return time.perf_counter() - started


def _loop_times(spec) -> tuple[list[float], float]:
    """Wall time of each run of a plain loop [s], and the loop's CPU time [s]."""
    times = []
    cpu = time.process_time()
    for index in range(spec.runs):
        started = time.perf_counter()
        _, result = simulate_run(spec, run_seed(spec.seed, index))
        run_outcome(result)
        times.append(time.perf_counter() - started)
    return times, time.process_time() - cpu


def _engine_time(spec, pool: Pool) -> float:
    return _engine(spec, pool)[0]


def _engine(spec, pool: Pool) -> tuple[float, float]:
    """Wall time of the sweep [s], and the CPU time of this process plus the runs' [s]."""
    with tempfile.TemporaryDirectory() as folder:
        started, cpu = time.perf_counter(), time.process_time()
        outcome = run_sweep(spec, Path(folder) / "out", pool=pool)
        wall, mine = time.perf_counter() - started, time.process_time() - cpu
    return wall, mine + sum(r["timing"].get("cpu_time_s", 0.0) for r in outcome.records)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep", default="bluerov2_demo_sweep")
    parser.add_argument("--runs", type=int, default=24)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args()
    spec = load_sweep(args.sweep).with_runs(args.runs)
    load = os.getloadavg()

    times: dict[int, list[float]] = {1: [], 2: []}
    machine = [_machine_speed_up()]
    for _ in range(args.repeats):
        for workers in (1, 2):
            times[workers].append(_sweep_time(spec, workers))
        machine.append(_machine_speed_up())
    rate = {w: 60.0 * spec.runs / statistics.median(t) for w, t in times.items()}

    started = time.perf_counter()
    pool = Pool(workers=1)
    _engine_time(spec.with_runs(1), pool)  # starts the worker: not timed below
    first = time.perf_counter() - started
    loop, engine, first_in_loop, loop_cpu, engine_cpu = [], [], [], [], []
    for _ in range(args.repeats):
        each, cpu = _loop_times(spec)
        loop.append(sum(each))
        loop_cpu.append(cpu)
        first_in_loop.append(each[0])
        wall, cpu = _engine(spec, pool)
        engine.append(wall)
        engine_cpu.append(cpu)
    pool.close()
    per_run_loop = statistics.median(loop) / spec.runs
    per_run_engine = statistics.median(engine) / spec.runs
    overhead = per_run_engine / per_run_loop - 1.0
    cpu_overhead = statistics.median(engine_cpu) / statistics.median(loop_cpu) - 1.0

    figures = {
        "sweep": spec.name, "runs": spec.runs, "repeats": args.repeats,
        "loadavg_start": list(load), "loadavg_end": list(os.getloadavg()),
        "seconds_1_worker": times[1], "seconds_2_workers": times[2],
        "runs_per_minute_1": rate[1], "runs_per_minute_2": rate[2],
        "speed_up_2_over_1": rate[2] / rate[1], "machine_speed_up": machine,
        "plain_loop_s_per_run": per_run_loop, "engine_s_per_run": per_run_engine,
        "engine_overhead": overhead, "engine_cpu_overhead": cpu_overhead,
        "first_run_on_a_new_pool_s": first,
        "first_run_in_the_loop_s": statistics.median(first_in_loop),
    }
    print(f"{spec.name}: {spec.runs} runs, {args.repeats} repeats, load "
          f"{' '.join(f'{v:.2f}' for v in load)}")
    print(f"  1 worker : {rate[1]:7.1f} runs/min (median of {times[1]})")
    print(f"  2 workers: {rate[2]:7.1f} runs/min (median of {times[2]})")
    print(f"  speed-up : {rate[2] / rate[1]:.2f}x (goal >= 1.8); the machine's own 2-process "
          f"speed-up on a pure-Python loop, before and after each repeat: "
          f"{', '.join(f'{m:.2f}x' for m in machine)}")
    print(f"  plain loop {1e3 * per_run_loop:.1f} ms/run, engine on a warm worker "
          f"{1e3 * per_run_engine:.1f} ms/run: overhead {100 * overhead:+.1f} % (goal <= 5 %)")
    print(f"  in CPU time (this process + each run's, load-independent): "
          f"{100 * cpu_overhead:+.1f} %")
    start = first - statistics.median(first_in_loop)
    print(f"  run 0 on a new pool took {first:.2f} s, in the loop "
          f"{statistics.median(first_in_loop):.2f} s: about {start:.2f} s of start-up "
          "(forkserver + worker), once per sweep")
    if args.json:
        Path(args.json).write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
