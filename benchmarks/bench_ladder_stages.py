"""Which ladder stage answers closed-loop runs, and what a step costs: two workloads.

* ``sweep``: six runs of 5 s of a small sweep of the bundled demo (perturbed initial joints,
  a noisy measured vehicle position, a sensor delay, a drifting current, a payload), the
  kinematic plant;
* ``dynamic``: the bundled demo on the dynamic plant with arm-vehicle coordination, 30 s.

Printed per workload: the steps per stage of the fallback ladder (``stage_counts``), the
statuses, and the median and p99 of the controller's step time [ms] (the runner's wall clock
around ``step``). With ``--save FILE`` the commands of every run are written to an ``.npz``; with
``--compare FILE`` the largest difference to the commands saved there is printed (answers of two
checkouts compared: run one with ``PYTHONPATH`` pointing at the other checkout, e.g.
``git worktree add``).

Run: ``python benchmarks/bench_ladder_stages.py [--only sweep|dynamic] [--save F] [--compare F]``.
"""

from __future__ import annotations

import argparse
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

import uvms_qp
from uvms_qp.sim.runner import SimulationResult, simulate
from uvms_qp.sim.scenario import load_scenario, resolve_scenario
from uvms_qp.sweep.records import simulate_run
from uvms_qp.sweep.sampling import run_seed
from uvms_qp.sweep.spec import load_sweep

SWEEP = """
scenario = "bluerov2_demo"
runs = 6
seed = 11
duration = 5.0

[current]
direction = { uniform = [-0.5, 0.5] }
drift = { uniform = [0.0, 0.5] }
speed = 0.2

[sensors]
position_noise = { uniform = [0.0, 0.01] }
delay = { choice = [0.0, 0.05] }

[initial]
joints = { normal = [0.0, 0.02], within = [-0.05, 0.05] }

[payload]
mass = { uniform = [0.0, 3.0] }
"""


def sweep_runs(folder: Path) -> list[SimulationResult]:
    path = folder / "sweep.toml"
    path.write_text(SWEEP)
    spec = load_sweep(path)
    return [simulate_run(spec, run_seed(spec.seed, i))[1] for i in range(spec.runs)]


def dynamic_run(folder: Path) -> list[SimulationResult]:
    text = resolve_scenario("bluerov2_demo").read_text()
    text = text.replace('type = "kinematic"', 'type = "dynamic"\ncoordination = true', 1)
    path = folder / "dynamic.toml"
    path.write_text(text)
    return [simulate(load_scenario(path))]


def report(name: str, runs: list[SimulationResult], saved: dict[str, np.ndarray],
           other: dict[str, np.ndarray] | None) -> None:
    stages: Counter[str] = Counter()
    statuses: Counter[str] = Counter()
    for run in runs:
        stages.update(run.fallback_metrics()["stage_counts"])
        statuses.update(run.status)
    times = np.concatenate([run.step_time for run in runs]) * 1e3
    print(f"{name}: {len(times)} steps, stages {dict(stages)}, statuses {dict(statuses)}")
    print(f"  step time [ms]: median {np.median(times):.3f}, p99 {np.percentile(times, 99):.3f}")
    for k, run in enumerate(runs):
        saved[f"{name}_{k}"] = run.zeta
    if other is not None:
        diff = max(float(np.max(np.abs(run.zeta - other[f"{name}_{k}"])))
                   for k, run in enumerate(runs))
        print(f"  largest command difference to the compared checkout: {diff:.3g}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=("sweep", "dynamic"))
    parser.add_argument("--save", type=Path)
    parser.add_argument("--compare", type=Path)
    args = parser.parse_args()
    print("uvms_qp from", Path(uvms_qp.__file__).parent)
    other = dict(np.load(args.compare)) if args.compare else None
    saved: dict[str, np.ndarray] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, make in (("sweep", sweep_runs), ("dynamic", dynamic_run)):
            if args.only in (None, name):
                report(name, make(Path(tmp)), saved, other)
    if args.save:
        np.savez(args.save, **saved)


if __name__ == "__main__":
    main()
