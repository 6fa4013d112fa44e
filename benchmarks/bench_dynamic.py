"""Real-time factor of the dynamic demo and where its time goes.

``uvms-qp run bluerov2_demo --plant dynamic`` simulates 30 s: the QP at 20 Hz, the velocity loop,
allocation and joint servos at 100 Hz, the equations of motion at the default physics step. This
script runs it (without figures or the kinematic reference) ``--repeats`` times and reports the
median wall and CPU time and the real-time factor (simulated / wall), then one more run with the
parts timed:

- plant: the physics steps (equations of motion, fourth-order Runge-Kutta) and the thrusters'
  dead band, lag and power;
- servos: the velocity loop and the thrust allocation (once per servo tick);
- QP: the controller's steps;
- the rest: the runner (events, probes, bound checks, records).

The timed run pays for its timers (about a microsecond per timed call), so its split is read as
shares, and the real-time factor comes from the untimed runs. Run it on an idle machine:
``python benchmarks/bench_dynamic.py [--repeats 5] [--duration 30] [--physics-step S]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

from uvms_qp.controller import Controller
from uvms_qp.dynamics import FloatingPlant, ThrustAllocator, ThrusterDynamics, VelocityLoop
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario

PARTS = {
    "plant": [(FloatingPlant, "step"), (ThrusterDynamics, "step")],
    "servos": [(VelocityLoop, "step"), (ThrustAllocator, "allocate")],
    "QP": [(Controller, "step")],
}


def scenario(duration: float, physics_step: float | None) -> Any:
    base = load_scenario("bluerov2_demo").with_plant("dynamic")
    if physics_step is not None:
        base = dataclasses.replace(
            base, plant=dataclasses.replace(base.plant, physics_step=physics_step))
    return base.with_duration(duration)


def timed_run(sc: Any) -> tuple[float, float]:
    wall, cpu = time.perf_counter(), time.process_time()
    simulate(sc)
    return time.perf_counter() - wall, time.process_time() - cpu


def split(sc: Any) -> dict[str, float]:
    """Seconds spent in each part of one run (timers around the parts' methods)."""
    spent: dict[str, float] = defaultdict(float)
    originals: list[tuple[type, str, Callable[..., Any]]] = []

    def wrap(cls: type, name: str, part: str) -> None:
        original = getattr(cls, name)
        originals.append((cls, name, original))

        def timed(*args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                spent[part] += time.perf_counter() - start

        setattr(cls, name, timed)

    for part, methods in PARTS.items():
        for cls, name in methods:
            wrap(cls, name, part)
    try:
        wall, _ = timed_run(sc)
    finally:
        for cls, name, original in originals:
            setattr(cls, name, original)
    spent["rest"] = wall - sum(spent.values())
    spent["total"] = wall
    return dict(spent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--duration", type=float, default=30.0, help="simulated time [s]")
    parser.add_argument("--physics-step", type=float, default=None,
                        help="physics step [s] (default: the plant's)")
    args = parser.parse_args()
    sc = scenario(args.duration, args.physics_step)
    timed_run(scenario(1.0, args.physics_step))  # warm-up: imports, caches
    runs = [timed_run(sc) for _ in range(args.repeats)]
    wall = statistics.median(r[0] for r in runs)
    cpu = statistics.median(r[1] for r in runs)
    plant = sc.make_plant()
    print(f"dynamic demo, {args.duration:g} s simulated, physics step "
          f"{plant.physics_step * 1e3:g} ms, servos {sc.plant.servo_rate:g} Hz, QP every "
          f"{sc.dt * 1e3:g} ms; {args.repeats} runs")
    print(f"  wall median {wall:.2f} s, CPU median {cpu:.2f} s, real-time factor "
          f"{args.duration / wall:.2f} (wall), {args.duration / cpu:.2f} (CPU)")
    parts = split(sc)
    total = parts.pop("total")
    for name, seconds in parts.items():
        print(f"  {name:<7} {seconds:6.2f} s  {100 * seconds / total:5.1f} %")
    steps = args.duration / plant.physics_step
    print(f"  plant per physics step {1e6 * parts['plant'] / steps:.0f} us "
          f"({steps:.0f} steps)")


if __name__ == "__main__":
    main()
