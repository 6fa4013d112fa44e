"""The fault matrix: every step path under every back-end fault, and how the run recovers.

For each path (the default DAQP path faulted at its C binding and at the back-end object, a
qpsolvers cascade, the weighted scheme, the closed-form null-space scheme), a controller is
stepped along the states of a clean closed-loop run of the same controller; during step ``K``
every call of the primary back-end (or of DAQP's binding) fails in one way
(:class:`uvms_qp.testing.faults.Fault`); afterwards it behaves. Printed per path and fault: the
stage and status of the faulted step, whether its command is finite and inside the box with
the hard rows held (``safe``), whether it equals the clean run's command to 1e-7
(``clean``: an answer repaired or replaced by the ladder, not a wrong one believed), and
``recovery``: the number of steps after the fault until the
stage is ``primary`` again with the clean command (to 1e-7). A second table takes every
back-end down (primary and alternate raise) for six steps: the stages the ladder walks through,
and the recovery once the back-ends answer again.

The slowness fault advances a fake clock (no real sleep) past a 50 ms deadline, so the run
does not depend on the machine's speed.

Run: ``python benchmarks/bench_safety.py [--steps 30] [--at 12]``.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from uvms_qp.bench.stacks import demo_stack, tool_posture_stack
from uvms_qp.controller import Controller
from uvms_qp.model import load_model
from uvms_qp.tasks import EndEffectorTask
from uvms_qp.testing.faults import Fault, inject

PATHS: dict[str, dict[str, Any]] = {
    "hqp/daqp @binding": {"solver": "daqp", "at": "binding"},
    "hqp/daqp @backend": {"solver": "daqp"},
    "hqp/cascade:quadprog": {"solver": "cascade:quadprog"},
    "weighted/cascade:daqp": {"solver": "daqp", "scheme": "weighted"},
    "nullspace (closed form)": {"scheme": "nullspace", "stack": "equality"},
}


class Clock:
    """A fake clock: the SLEEP fault advances it instead of sleeping."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += seconds


def _controller(model: Any, path: dict[str, Any], clock: Clock | None = None) -> Controller:
    target = [0.55, 0.12, 0.05]
    stack = (tool_posture_stack(EndEffectorTask(position=target, gain=1.0))
             if path.get("stack") == "equality" else demo_stack(position=target))
    ctrl = Controller(model, stack, solver=path.get("solver", "daqp"), dt=0.05,
                      scheme=path.get("scheme", "hqp"), deadline=0.05)
    if clock is not None:
        ctrl.safe.clock = clock
    return ctrl


def _clean_run(model: Any, path: dict[str, Any], steps: int) -> tuple[list[Any], list[Any]]:
    """The configurations and commands of ``steps`` unfaulted closed-loop steps from home."""
    clean = _controller(model, path)
    q = model.home()
    states, zetas = [], []
    for k in range(steps):
        states.append(q)
        res = clean.step(model.state(q), 0.05 * k)
        zetas.append(res.zeta)
        q = model.integrate(q, res.zeta, 0.05)
    return states, zetas


def run(path_name: str, fault: Fault, steps: int, at: int,
        uncertified: bool = False) -> tuple[str, str, bool, bool, str]:
    model = load_model("bluerov2_heavy_alpha5")
    path = PATHS[path_name]
    states, zetas = _clean_run(model, path, steps)
    clock = Clock()
    ctrl = _controller(model, path, clock)
    if uncertified:
        ctrl.safe.primary.certify = None  # the optimality certificate switched off
    injector = inject(ctrl, fault, at=path.get("at", "backend"), sleep=0.08)
    injector.sleeper = clock.advance
    faulted = None
    recovery = "-"
    for k, q in enumerate(states):
        injector.armed = k == at
        res = ctrl.step(model.state(q), 0.05 * k)
        if k == at:
            faulted = res
        elif k > at and recovery == "-" and res.stage == "primary" and (
                np.max(np.abs(res.zeta - zetas[k])) <= 1e-7):
            recovery = str(k - at)
    assert faulted is not None
    safe = bool(np.all(np.isfinite(faulted.zeta)) and np.all(faulted.zeta >= faulted.lower)
                and np.all(faulted.zeta <= faulted.upper) and faulted.bound_violation <= 1e-9)
    stage = faulted.stage + (" (late)" if faulted.deadline_missed else "")
    clean_command = bool(np.max(np.abs(faulted.zeta - zetas[at])) <= 1e-7)
    return stage, faulted.status.value, safe, clean_command, recovery


def all_down(path_name: str, steps: int, at: int, down: int = 6) -> tuple[list[str], str]:
    """Stages of steps ``at .. at + down`` with every back-end raising, and the recovery."""
    model = load_model("bluerov2_heavy_alpha5")
    path = PATHS[path_name]
    states, zetas = _clean_run(model, path, steps)
    ctrl = _controller(model, path)
    injectors = [inject(ctrl, Fault.RAISE_FOREIGN, at=path.get("at", "backend"))]
    if ctrl.safe.alternate is not None:
        injectors.append(inject(ctrl.safe.alternate, Fault.RAISE_FOREIGN))
    stages, recovery = [], "-"
    for k, q in enumerate(states):
        for injector in injectors:
            injector.armed = at <= k < at + down
        res = ctrl.step(model.state(q), 0.05 * k)
        assert np.all(np.isfinite(res.zeta)) and res.bound_violation <= 1e-9
        if at <= k < at + down:
            stages.append(res.stage)
        elif k >= at + down and recovery == "-" and res.stage == "primary" and (
                np.max(np.abs(res.zeta - zetas[k])) <= 1e-7):
            recovery = str(k - at - down + 1)
    return stages, recovery


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--at", type=int, default=12, help="faulted step")
    args = parser.parse_args()
    print(f"{'path':<26} {'fault':<16} {'stage':<22} {'status':<17} {'safe':<5} {'clean':<6} "
          "recovery")
    for path_name in PATHS:
        for fault in Fault:
            stage, status, safe, right, recovery = run(path_name, fault, args.steps,
                                                       args.at)
            print(f"{path_name:<26} {fault.value:<16} {stage:<22} {status:<17} "
                  f"{'yes' if safe else 'NO':<5} {'yes' if right else 'no':<6} {recovery}")
    print("\nwith the optimality certificate switched off (certify = None):")
    for path_name in PATHS:
        stage, status, safe, right, recovery = run(path_name, Fault.FEASIBLE_WRONG, args.steps,
                                                   args.at, uncertified=True)
        print(f"{path_name:<26} {'feasible_wrong':<16} {stage:<22} {status:<17} "
              f"{'yes' if safe else 'NO':<5} {'yes' if right else 'no':<6} {recovery}")
    print(f"\nevery back-end down for 6 steps (from step {args.at}):")
    for path_name in PATHS:
        stages, recovery = all_down(path_name, args.steps, args.at)
        print(f"{path_name:<26} {' > '.join(stages)}; recovery {recovery}")


if __name__ == "__main__":
    main()
