"""Benchmark the thrust allocation and the vehicle's velocity loop (median wall time, us).

The BlueROV2 Heavy's eight T200s at 16 V. A sequence of demanded wrenches (a random walk, about
a third of them beyond what the thrusters can give) is allocated by

* ``ThrustAllocator.allocate`` (DAQP, set up once, only the linear term updated per call), and
* ``scipy.optimize.lsq_linear`` on the same regularised bounded least-squares problem, with the
  ``bvls`` method (an active-set method, the fastest of scipy's two here) and ``trf``,

both producing the same outputs (forces, produced and unmet wrench, saturation flags). All
variants are called once per round on the same wrench (interleaved: machine load hits them
alike). The same is timed with the PI velocity loop's step before the allocation (one 100 Hz
servo period), and the thrusters' dynamics over one servo period (the command held, ten 1 ms
physics steps). The last lines give what each costs over a 30 s run (3000 servo periods,
30000 physics steps) and how far the two solvers' forces are apart.

Run: ``python benchmarks/bench_allocation.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.optimize import lsq_linear

from uvms_qp.dynamics import (
    Allocation,
    ThrustAllocator,
    ThrusterDynamics,
    ThrusterLayout,
    VelocityLoop,
)

# von Benzon et al. (2022), J. Mar. Sci. Eng. 10(12):1898 (BlueROV2 Heavy)
MASS, INERTIA = 13.5, (0.26, 0.23, 0.37)
ADDED = (6.36, 7.12, 18.68, 0.189, 0.135, 0.222)
LINEAR = (13.7, 0.0, 33.0, 0.0, 0.8, 0.0)
QUADRATIC = (141.0, 217.0, 190.0, 1.19, 0.47, 1.5)
SCALE = np.array([90.0, 90.0, 120.0, 25.0, 15.0, 20.0])  # wrench walk scale [N, N m]


class LsqLinearAllocator:
    """The same allocation on scipy's ``lsq_linear`` (the alternative measured)."""

    def __init__(self, allocator: ThrustAllocator, method: str) -> None:
        layout = allocator.layout
        B = layout.matrix
        n = layout.size
        w = np.sqrt(allocator.wrench_weights)
        gram = (B.T * allocator.wrench_weights) @ B
        eps = allocator.regularization * float(np.linalg.eigvalsh(gram)[-1])
        self.A = np.vstack([w[:, None] * B, np.sqrt(eps) * np.eye(n)])
        self.w = w
        self.B = B
        self.rhs = np.zeros(6 + n)
        self.bounds = (layout.lower, layout.upper)
        self.tol = 1e-9 * np.maximum(layout.upper, -layout.lower)
        self.method = method

    def allocate(self, wrench: np.ndarray) -> Allocation:
        self.rhs[:6] = self.w * wrench
        x = lsq_linear(self.A, self.rhs, bounds=self.bounds, method=self.method).x
        lower, upper = self.bounds
        forces = np.clip(x, lower, upper)
        produced = self.B @ forces
        saturated = (forces >= upper - self.tol) | (forces <= lower + self.tol)
        return Allocation(forces, wrench.copy(), produced, wrench - produced, saturated)


def wrenches(count: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    walk = np.cumsum(rng.normal(size=(count, 6)) * 0.15, axis=0)
    return np.sin(walk) * SCALE * 0.8


def interleaved(fns: dict[str, Callable[[int], Any]], repeat: int
                ) -> tuple[dict[str, float], dict[str, list[Any]]]:
    times: dict[str, list[float]] = {k: [] for k in fns}
    outs: dict[str, list[Any]] = {k: [] for k in fns}
    for i in range(repeat):
        for k, fn in fns.items():
            t = time.perf_counter()
            out = fn(i)
            times[k].append(time.perf_counter() - t)
            outs[k].append(out)
    return {k: float(np.median(v) * 1e6) for k, v in times.items()}, outs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=2000, help="wrenches (rounds), default 2000")
    parser.add_argument("--trf-repeat", type=int, default=200,
                        help="rounds that also run lsq_linear 'trf' (slow), default 200")
    args = parser.parse_args()

    layout = ThrusterLayout.bluerov2_heavy(16.0)
    daqp_alloc = ThrustAllocator(layout)
    bvls = LsqLinearAllocator(daqp_alloc, "bvls")
    trf = LsqLinearAllocator(daqp_alloc, "trf")
    demands = wrenches(args.repeat)
    # warm-up (imports, first set-up)
    daqp_alloc.allocate(demands[0])
    bvls.allocate(demands[0])
    trf.allocate(demands[0])

    def loop() -> VelocityLoop:
        return VelocityLoop.for_body(MASS, INERTIA, ADDED, LINEAR, dt=0.01,
                                     quadratic_damping=QUADRATIC, layout=layout,
                                     restoring=lambda q: np.array([0, 0, -1.5, 0, 0, 0.0]))

    loops = {"daqp": loop(), "bvls": loop()}
    unmet: dict[str, Any] = {"daqp": None, "bvls": None}
    nu = np.zeros(6)
    q = np.zeros(7)
    refs = demands / SCALE * 0.3  # velocity references [m/s, rad/s]

    def with_loop(name: str, allocator: Any) -> Callable[[int], Any]:
        def run(i: int) -> Any:
            wrench = loops[name].step(refs[i], nu, q, unmet[name])
            result = allocator.allocate(wrench)
            unmet[name] = result.unmet
            return result
        return run

    dynamics = ThrusterDynamics(layout)
    commands = [ThrustAllocator(layout).allocate(d).forces for d in demands]

    def actuators(i: int) -> Any:
        dynamics.set_command(commands[i])
        for _ in range(10):
            dynamics.step(0.001)
        return None

    fns: dict[str, Callable[[int], Any]] = {
        "allocate: DAQP": lambda i: daqp_alloc.allocate(demands[i]),
        "allocate: lsq_linear bvls": lambda i: bvls.allocate(demands[i]),
        "PI + allocate: DAQP": with_loop("daqp", daqp_alloc),
        "PI + allocate: lsq_linear bvls": with_loop("bvls", bvls),
        "thrusters: command + 10 x 1 ms": actuators,
    }
    medians, outs = interleaved(fns, args.repeat)
    trf_medians, trf_outs = interleaved({
        "allocate: DAQP": lambda i: daqp_alloc.allocate(demands[i]),
        "allocate: lsq_linear trf": lambda i: trf.allocate(demands[i]),
    }, args.trf_repeat)

    base = medians["allocate: DAQP"]
    print(f"BlueROV2 Heavy, 8 T200 at 16 V; {args.repeat} wrenches, "
          f"{sum(not r.feasible for r in outs['allocate: DAQP'])} beyond the thrusters")
    print(f"{'variant':34s} {'median us':>10s} {'x DAQP':>8s} {'30 s run [ms]':>14s}")
    for name, us in medians.items():
        ratio = f"{us / base:8.1f}" if name.startswith("allocate") else " " * 8
        if name.startswith("PI"):
            ratio = f"{us / medians['PI + allocate: DAQP']:8.1f}"
        print(f"{name:34s} {us:10.1f} {ratio} {us * 3000 / 1000:14.1f}")
    trf_base = trf_medians["allocate: DAQP"]
    us = trf_medians["allocate: lsq_linear trf"]
    print(f"{'allocate: lsq_linear trf':34s} {us:10.1f} {us / trf_base:8.1f} "
          f"{us * 3000 / 1000:14.1f}   ({args.trf_repeat} rounds, DAQP {trf_base:.1f} us there)")
    diff = max(float(np.abs(a.forces - b.forces).max())
               for a, b in zip(outs["allocate: DAQP"], outs["allocate: lsq_linear bvls"],
                               strict=True))
    cost = max(abs(float(np.sum(a.unmet ** 2)) - float(np.sum(b.unmet ** 2)))
               for a, b in zip(outs["allocate: DAQP"], outs["allocate: lsq_linear bvls"],
                               strict=True))
    trf_diff = max(float(np.abs(a.forces - b.forces).max())
                   for a, b in zip(trf_outs["allocate: DAQP"], trf_outs["allocate: lsq_linear trf"],
                                   strict=True))
    print(f"largest force difference DAQP vs bvls {diff:.2e} N (unmet |.|^2 {cost:.2e}), "
          f"vs trf {trf_diff:.2e} N")


if __name__ == "__main__":
    main()
