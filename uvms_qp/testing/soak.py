"""Soak run of the bundled demo: many steps, re-randomised targets, injected back-end faults.

Used by ``benchmarks/soak.py`` (10^6 steps, by hand) and by the CI test (10^4 steps). Each step
of the ``bluerov2_demo`` stack is checked against the contract of ``docs/reliability.md``:

* *unsafe* output: a non-finite command, a command outside the hard box, or a command from a
  solver stage that breaks the hard rows by more than 1e-7;
* joint positions after integration outside their limits by more than 1e-9 [rad].

Every ``retarget`` steps the tool target is re-drawn (uniform in a 2 m box around the vehicle,
so part of the targets are beyond reach) and the payload force re-drawn; every ``restart`` steps
the state is reset to the scenario's initial configuration and the target sequence restarts from
the same seed, so every cycle repeats the same motion. Faults are injected into the primary
back-end at random (:class:`~uvms_qp.testing.faults.RandomInjector`, their own random stream, so
they differ from cycle to cycle). Memory is traced with :mod:`tracemalloc` after a warm-up;
latency drift compares the median step time of the first cycle after the warm-up with that of
the last cycle (same motion, fault-free steps only).
"""

from __future__ import annotations

import time
import tracemalloc
from collections import Counter
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from ..controller import Controller
from ..sim.scenario import load_scenario
from ..tasks import EndEffectorTask
from .faults import Fault, inject_random


@dataclass
class SoakReport:
    """Figures of a soak run.

    Attributes:
        steps: Steps run.
        unsafe: Steps whose command broke the contract (must be 0).
        limit_excursions: Steps after which a joint was outside its limits by > 1e-9 rad.
        stages: Steps per fallback stage.
        statuses: Steps per status.
        faults: Faults injected, by kind.
        memory_growth: tracemalloc growth after the warm-up [bytes]; None when not traced
            (tracing off, or the run ended within the warm-up).
        median_first_us: Median step time of the first cycle after the warm-up (fault-free
            steps) [us]; None when the run has no complete cycle after the warm-up (this and
            the other first/last-cycle figures).
        median_last_us: Median step time of the last complete cycle (fault-free steps) [us].
        p99_us: 99th percentile of the step time (all steps) [us].
        max_us: Largest step time [us].
        wall: Wall time of the run [s].
        p10_first_us: 10th percentile of the step time, first cycle (less sensitive to other
            load on the machine than the median) [us].
        p10_last_us: Same for the last cycle [us].
        degraded_examples: ``attempts`` of the first degraded steps (why the ladder went down).
        cycle_window: ``(first step, steps per cycle)`` of the first cycle after the warm-up:
            the run needs ``sum(cycle_window)`` steps for the first/last-cycle figures.
    """

    steps: int = 0
    unsafe: int = 0
    limit_excursions: int = 0
    stages: Counter[str] = field(default_factory=Counter)
    statuses: Counter[str] = field(default_factory=Counter)
    faults: dict[str, int] = field(default_factory=dict)
    memory_growth: int | None = None
    median_first_us: float | None = None
    median_last_us: float | None = None
    p99_us: float = 0.0
    max_us: float = 0.0
    wall: float = 0.0
    p10_first_us: float | None = None
    p10_last_us: float | None = None
    degraded_examples: list[str] = field(default_factory=list)
    cycle_window: tuple[int, int] = (0, 0)

    def lines(self) -> list[str]:
        """Readable report lines."""
        total = max(self.steps, 1)
        return [
            f"steps {self.steps}, unsafe outputs {self.unsafe}, joint-limit excursions "
            f"{self.limit_excursions}, wall {self.wall:.1f} s",
            "stages: " + ", ".join(f"{k} {v} ({100 * v / total:.3g} %)"
                                   for k, v in self.stages.most_common()),
            "statuses: " + ", ".join(f"{k} {v}" for k, v in self.statuses.most_common()),
            "faults injected: " + (", ".join(f"{k} {v}" for k, v in self.faults.items())
                                   or "none (the primary back-end is not wrapped)"),
            "tracemalloc growth after warm-up: " + (
                "n/a (not traced: tracing off, or the run ended within the warm-up)"
                if self.memory_growth is None else f"{self.memory_growth / 1024:.1f} KiB"),
            self._cycle_line(),
            f"step time p99 {self.p99_us:.1f} us, max {self.max_us / 1e3:.1f} ms",
            *(f"degraded step: {e}" for e in self.degraded_examples),
        ]

    @property
    def drift(self) -> float | None:
        """Relative change of the median step time, first to last cycle (None: not measured)."""
        if self.median_first_us is None or self.median_last_us is None:
            return None
        return self.median_last_us / self.median_first_us - 1.0

    def _cycle_line(self) -> str:
        """The first/last-cycle step times and their drift, or why they were not measured."""
        if self.median_first_us is None or self.drift is None:
            start, length = self.cycle_window
            return (f"step time first/last cycle: n/a (not measured: needs a complete cycle of "
                    f"{length} steps after the warm-up, at least {start + length} steps)")
        return (f"step time median first cycle {self.median_first_us:.1f} us, last cycle "
                f"{self.median_last_us:.1f} us (drift {self.drift:+.1%}); 10th percentile first "
                f"cycle {self.p10_first_us:.1f} us, last cycle {self.p10_last_us:.1f} us")


def run_soak(steps: int, *, seed: int = 0, fault_rate: float = 0.01, solver: str = "daqp",
             deadline: float = 0.02, retarget: int = 200, restart: int = 5000,
             trace_memory: bool = True, warmup: int = 5000, sleep: float = 0.03,
             progress: bool = False) -> SoakReport:
    """Run the demo stack for ``steps`` steps and check every command.

    Args:
        steps: Number of control steps.
        seed: Seed of targets and faults.
        fault_rate: Share of back-end calls that fail (random kind).
        solver: Primary solver.
        deadline: Step deadline [s] given to the controller.
        retarget: Steps between re-drawn tool targets.
        restart: Steps between resets to the initial state (one cycle).
        trace_memory: Trace allocations with :mod:`tracemalloc` (slower).
        warmup: Steps before the memory baseline is taken and the latency windows start
            (caches and lazily built fallback back-ends settle in the first few thousand steps).
        sleep: Sleep of the injected solve-time spikes [s].
        progress: Print a line every 10 % of the run.
    """
    fault_rng = np.random.default_rng(seed + 1)
    rng = np.random.default_rng(seed)
    scenario = load_scenario("bluerov2_demo")
    model, dt = scenario.model, scenario.dt
    stack = scenario.build_stack()
    ctrl = Controller(model, stack, solver=solver, dt=dt, metric=scenario.metric,
                      deadline=deadline)
    # the controller has one path: a wrapped back-end is called exactly where the real one is
    faults = (inject_random(ctrl, fault_rate, fault_rng, sleep=sleep)
              if fault_rate > 0 else None)
    tool = cast(EndEffectorTask, stack.task("tool"))
    payload = stack.task("payload")
    lower_q, upper_q = model.joint_lower, model.joint_upper
    q0 = np.array(scenario.q0, dtype=np.float64)
    q = q0.copy()
    times = np.zeros(steps)
    faulted = np.zeros(steps, dtype=bool)
    report = SoakReport()
    baseline = 0
    started = time.perf_counter()
    for k in range(steps):
        if k % restart == 0:
            q = q0.copy()
            ctrl.reset()
            rng = np.random.default_rng(seed)
        if k % retarget == 0:
            centre = model.state(q).position("vehicle")
            tool.set_target(position=centre + rng.uniform(-1.0, 1.0, 3))
            payload.update(force=float(rng.uniform(0.0, 30.0)))
        if trace_memory and k == warmup:
            tracemalloc.start()
            baseline = tracemalloc.get_traced_memory()[0]
        n_faults = faults.n_faults if faults is not None else 0
        res = ctrl.step(model.state(q), k * dt)
        faulted[k] = faults is not None and faults.n_faults != n_faults
        times[k] = res.step_time
        zeta = res.zeta
        report.stages[res.stage] += 1
        if res.stage in ("decayed_previous", "zero", "hold_zero") and len(
                report.degraded_examples) < 5:
            report.degraded_examples.append(f"step {k}: {res.stage}: " + " | ".join(res.attempts))
        report.statuses[res.status.value] += 1
        unsafe = not np.all(np.isfinite(zeta)) or bool(
            np.any(zeta < res.lower) or np.any(zeta > res.upper))
        if not unsafe and res.stage in ("primary", "cold_retry", "alternate", "relaxed"):
            unsafe = res.bound_violation > 1e-7
        if unsafe:
            report.unsafe += 1
            zeta = np.zeros_like(zeta)
        q = model.integrate(q, zeta, dt)
        joints = model.split(q)[1]
        if np.any(joints < lower_q - 1e-9) or np.any(joints > upper_q + 1e-9):
            report.limit_excursions += 1
        if progress and steps >= 10 and (k + 1) % (steps // 10) == 0:
            print(f"  {k + 1} steps, {time.perf_counter() - started:.0f} s", flush=True)
    if trace_memory and tracemalloc.is_tracing():
        report.memory_growth = tracemalloc.get_traced_memory()[0] - baseline
        tracemalloc.stop()
    report.wall = time.perf_counter() - started
    report.steps = steps
    report.faults = ({str(kind): n for kind, n in faults.by_kind.items()}
                     if faults is not None else {})
    start = -(-warmup // restart) * restart  # first cycle after the warm-up
    cycles = max((steps - start) // restart, 0)
    clean = ~faulted
    first = last = times[:0]
    if cycles >= 1:
        a, b = start, start + restart
        first = times[a:b][clean[a:b]]
        a, b = start + (cycles - 1) * restart, start + cycles * restart
        last = times[a:b][clean[a:b]]
    report.cycle_window = (start, restart)
    if first.size and last.size:
        report.median_first_us = float(np.median(first)) * 1e6
        report.median_last_us = float(np.median(last)) * 1e6
        report.p10_first_us = float(np.percentile(first, 10)) * 1e6
        report.p10_last_us = float(np.percentile(last, 10)) * 1e6
    report.p99_us = float(np.percentile(times, 99)) * 1e6
    report.max_us = float(times.max()) * 1e6
    return report


__all__ = ["Fault", "SoakReport", "run_soak"]
