"""Step time against the deadline: p50, p99, p99.9 and max, idle and with both cores busy.

Two workloads, each under a deadline:

* ``demo``: the controller on the demo stack (BlueROV2 Heavy + Reach Alpha 5, 4 levels), closed
  loop along a moving tool target, deadline = its control period (the default) and a tight one;
* ``random n=30``: a safe solver (DAQP, the ladder, certificate and repair) on random
  hierarchies of 30 variables from the benchmark's generator (wide, tight and saturated boxes),
  and on the degenerate families of ``uvms_qp.bench.problems``.

"Busy" runs the same loops while two other processes keep both cores busy with numpy matrix
products (their BLAS threads compete with ours). Printed per workload: the deadline, the step
time percentiles [ms] in wall time (``time.perf_counter``) and in this thread's CPU time
(``time.thread_time``: the time the step computed, not the time it waited for a core), the
largest overrun of the deadline [ms], the number of steps more than 1 ms past it in wall time
and, of those, the ones whose CPU time alone is more than 1 ms past it (the rest waited for a
core), the steps during which the scheduler took the core away (involuntary context switches
of this thread, ``getrusage(RUSAGE_THREAD)``), and the statuses seen.

``--realtime PRIO`` runs the measured loops as a vehicle's control process runs: this process at
the real-time priority ``PRIO`` (``SCHED_FIFO``, Linux; needs root or ``CAP_SYS_NICE``, like
``chrt -f PRIO``), the load at the normal priority, the garbage collector frozen after each
workload's set-up
(:func:`uvms_qp.safety.prepare_realtime`), and each step started on the tick of a
periodic loop (``--period``, default 5 ms) instead of back to back, so that the steps own a core
when they run and the process leaves the CPU between them, as a control loop does (a real-time
thread that never sleeps is throttled by the kernel).

Run: ``python benchmarks/bench_deadline.py [--steps 3000] [--problems 300] [--busy-only]
[--realtime 50 [--period 0.005]]``.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import resource
import time
from collections import Counter
from typing import Any

import numpy as np

from uvms_qp.bench.problems import MATRIX_FAMILIES, base_problem, family
from uvms_qp.bench.stacks import demo_stack
from uvms_qp.controller import Controller
from uvms_qp.hqp import normalize_problem
from uvms_qp.model import load_model
from uvms_qp.safety import SafeSolver, prepare_realtime


def _burn(stop: mp.Event) -> None:  # type: ignore[valid-type]
    if hasattr(os, "sched_setscheduler"):  # the load runs at the normal priority
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    a = np.random.default_rng(0).standard_normal((300, 300))
    while not stop.is_set():  # type: ignore[attr-defined]
        a = np.tanh(a @ a.T / 300.0)


class Busy:
    """Two processes keeping both cores busy with BLAS work while the context is open."""

    def __init__(self, on: bool) -> None:
        self.on = on
        self.stop = mp.Event()
        self.procs: list[mp.Process] = []

    def __enter__(self) -> Busy:
        if self.on:
            self.procs = [mp.Process(target=_burn, args=(self.stop,)) for _ in range(2)]
            for p in self.procs:
                p.start()
            time.sleep(1.0)
        return self

    def __exit__(self, *_: object) -> None:
        self.stop.set()
        for p in self.procs:
            p.join()


class Circle:
    """A tool target moving on a circle around ``center`` [m]."""

    def __init__(self, center: np.ndarray, radius: float = 0.15, period: float = 8.0) -> None:
        self.center, self.radius, self.omega = center, radius, 2.0 * np.pi / period

    def sample(self, t: float) -> Any:
        from uvms_qp.sim.trajectories import TrajectorySample

        c, s = np.cos(self.omega * t), np.sin(self.omega * t)
        p = self.center + self.radius * np.array([c - 1.0, s, 0.0])
        v = self.radius * self.omega * np.array([-s, c, 0.0])
        return TrajectorySample(p, v)


def _preemptions() -> int:
    """Involuntary context switches of the calling thread so far (Linux)."""
    return resource.getrusage(resource.RUSAGE_THREAD).ru_nivcsw


class Steps:
    """Wall time, CPU time and preemptions of each step, and the statuses seen.

    With a ``period`` [s], each step starts on the next tick of a periodic loop (sleeping until
    it), as in a control loop; without one, steps run back to back.
    """

    period: float | None = None

    def __init__(self) -> None:
        if self.period is not None:
            prepare_realtime()  # freeze what the set-up made (the priority is already set)
        self.next_tick: float | None = None
        self.wall: list[float] = []
        self.cpu: list[float] = []
        self.preempted: list[int] = []
        self.statuses: Counter[str] = Counter()

    def timed(self, step: Any) -> Any:
        """Run ``step()`` and record its times."""
        if self.period is not None:
            now = time.perf_counter()
            tick = now if self.next_tick is None else max(self.next_tick, now)
            if tick > now:
                time.sleep(tick - now)
            self.next_tick = tick + self.period
        switches, used, began = _preemptions(), time.thread_time(), time.perf_counter()
        out = step()
        self.wall.append(time.perf_counter() - began)
        self.cpu.append(time.thread_time() - used)
        self.preempted.append(_preemptions() - switches)
        return out


def demo_steps(steps: int, deadline: float | None) -> tuple[Steps, float]:
    model = load_model("bluerov2_heavy_alpha5")
    dt = 0.05
    q = model.home()
    stack = demo_stack(trajectory=Circle(model.frame_pose(q, "tool")[:3, 3]))
    ctrl = Controller(model, stack, dt=dt, deadline=deadline)
    ctrl.step(model.state(q), 0.0)  # the first step sets the back-ends up (docs/reliability.md)
    ctrl.reset()
    out = Steps()
    for k in range(steps):
        t = k * dt
        state = model.state(q)
        res = out.timed(lambda: ctrl.step(state, t))  # noqa: B023 - called at once
        out.statuses[res.status.value] += 1
        q = model.integrate(q, res.zeta, dt)
    return out, ctrl.safe.deadline or float("inf")


def random_solves(count: int, deadline: float) -> Steps:
    rng = np.random.default_rng(11)
    problems = []
    for i in range(count):
        box = ("wide", "tight", "saturated")[i % 3]
        levels, lower, upper = base_problem(rng, 30, box)
        problems.append(normalize_problem([[(A, lo, hi)] for A, lo, hi, _ in levels],
                                          lower, upper))
    for fam in MATRIX_FAMILIES:
        for p in family(fam, max(1, count // 20), seed=5):
            problems.append(normalize_problem(p.levels_rows(), p.lower, p.upper,
                                              hard=p.hard_rows()))
    safe = SafeSolver("daqp", deadline=deadline)
    out = Steps()
    for problem in problems:
        result = out.timed(lambda: safe.solve(problem, time.perf_counter()))  # noqa: B023
        out.statuses[f"{result.stage}/{result.result.status.value}"] += 1
    return out


def row(name: str, deadline: float, steps: Steps) -> str:
    ms, cpu = np.array(steps.wall) * 1e3, np.array(steps.cpu) * 1e3
    p50, p99, p999 = np.percentile(ms, [50, 99, 99.9])
    c50, c99 = np.percentile(cpu, [50, 99])
    over = ms - deadline * 1e3
    late = over > 1.0
    late_cpu = int(np.sum(late & (cpu - deadline * 1e3 > 1.0)))
    preempted = int(np.sum(np.array(steps.preempted) > 0))
    top = ", ".join(f"{k} {v}" for k, v in steps.statuses.most_common(4))
    return (f"| {name} | {deadline * 1e3:.1f} | {len(ms)} | {p50:.3f} | {p99:.3f} | {p999:.3f} | "
            f"{ms.max():.3f} | {c50:.3f} | {c99:.3f} | {cpu.max():.3f} | "
            f"{max(over.max(), 0.0):.3f} | {int(late.sum())} | {late_cpu} | {preempted} | "
            f"{top} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--problems", type=int, default=300)
    ap.add_argument("--busy-only", action="store_true")
    ap.add_argument("--realtime", type=int, metavar="PRIO",
                    help="run the loops at this SCHED_FIFO priority, on a periodic loop")
    ap.add_argument("--period", type=float, default=0.005,
                    help="with --realtime: the loop's period [s] (default 0.005)")
    args = ap.parse_args()
    if args.realtime is not None:
        prepare_realtime(args.realtime)
        Steps.period = args.period
        print(f"SCHED_FIFO priority {args.realtime}, one step per {args.period * 1e3:g} ms")
    print("| workload | deadline [ms] | steps | wall p50 [ms] | wall p99 [ms] | wall p99.9 [ms] "
          "| wall max [ms] | CPU p50 [ms] | CPU p99 [ms] | CPU max [ms] | worst overrun [ms] | "
          "> 1 ms late | of which on CPU | steps preempted | stages/statuses |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for busy in ((True,) if args.busy_only else (False, True)):
        label = "busy" if busy else "idle"
        with Busy(busy):
            for deadline in (None, 0.002):
                steps, d = demo_steps(args.steps, deadline)
                print(row(f"demo, {label}", d, steps), flush=True)
            for deadline in (0.01, 0.002):
                steps = random_solves(args.problems, deadline)
                print(row(f"random n=30 + families, {label}", deadline, steps), flush=True)


if __name__ == "__main__":
    main()
