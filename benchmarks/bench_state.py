"""Cost of a control tick's kinematics and rows: the state update, and the demo stack's rows.

Three tables, medians and 10th-90th percentiles in microseconds per tick, each loop interleaved
batch by batch with its comparison (same machine load):

1. *State update*: validate ``q``, forward kinematics + joint Jacobians, the tool Jacobian over
   ``zeta`` (world axes) and the arm-only tool Jacobian (arm_base axes), against bare Pinocchio
   doing the same work with no validation and no caching.
2. *Vehicle pose* (vehicles with roll and pitch): the state update plus ``eta`` and ``J_eta``
   (``State.vehicle_pose_jacobian``, built from plain floats), against the same numbers built
   from Pinocchio's quaternion and roll-pitch-yaw objects and numpy blocks (why the state uses
   plain floats).
3. *Rows*: the demo stack of ``uvms_qp.bench.stacks.demo_stack`` (8 tasks, 31 rows, joint
   position, joint rate and vehicle rate bounds) with a fresh state every tick: ``model.state(q)``
   + every task's ``fill`` into preallocated buffers + every box constraint, as the controller
   does it (static boxes merged once), and the state update alone.

``--instructions N`` counts instructions of table 3 instead (valgrind's callgrind, N ticks minus a
run with none, so start-up cancels), repeatable where wall time on a shared machine is not.

Usage: ``python benchmarks/bench_state.py [--model NAME|all] [--reps N] [--json FILE]``
``[--instructions N]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from uvms_qp import bundled_models, load_model
from uvms_qp.bench.stacks import demo_stack
from uvms_qp.model import State

BATCH = 200  # ticks per timed batch (amortises the timer call)
DT = 0.05  # [s]


def _time(fn, q_list, reps: int) -> np.ndarray:
    """Per-tick time [us] of ``fn(q)``, one sample per batch of ``BATCH`` ticks."""
    n = len(q_list)
    samples = np.empty(reps)
    for r in range(reps):
        start = time.perf_counter()
        for i in range(BATCH):
            fn(q_list[i % n])
        samples[r] = (time.perf_counter() - start) / BATCH * 1e6
    return samples


def _interleaved(ticks, qs, reps: int) -> dict[str, dict[str, float]]:
    """Time the loops of ``ticks`` batch by batch in turn."""
    for _, fn in ticks:  # warm-up
        _time(fn, qs, 5)
    samples: dict[str, list[float]] = {label: [] for label, _ in ticks}
    for _ in range(reps):
        for label, fn in ticks:
            samples[label].extend(_time(fn, qs, 1))
    return {label: {"median_us": float(np.median(s)), "p10_us": float(np.percentile(s, 10)),
                    "p90_us": float(np.percentile(s, 90))} for label, s in samples.items()}


def state_ticks(model):
    """Table 1 and 2 loops of ``model``."""
    pm, data = model.pin_model, model.pin_model.createData()
    arm = model._arm_model
    arm_data = arm.createData()
    fid, arm_fid = model.frame_id("tool"), model._arm_frame_ids["tool"]
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    nqv = model.nq_vehicle
    select = model._select
    columns = list(model.vehicle.actuated_indices)

    def uvms_qp_tick(q):
        state = State(model, q)
        state.jacobian("tool")
        state.arm_jacobian("tool")

    def pinocchio_tick(q):
        pin.computeJointJacobians(pm, data, q)
        J = pin.getFrameJacobian(pm, data, fid, lwa)
        if select is not None:
            J = J[:, select]
        pin.computeJointJacobians(arm, arm_data, q[nqv:])
        pin.getFrameJacobian(arm, arm_data, arm_fid, lwa)

    def uvms_qp_vehicle_tick(q):
        State(model, q).vehicle_pose_jacobian()

    def matrix_vehicle_tick(q):
        """The same eta and J_eta through Pinocchio's rotation objects and numpy blocks."""
        State(model, q)
        qv = q[:nqv]
        R = pin.Quaternion(qv[6], qv[3], qv[4], qv[5]).toRotationMatrix()
        eta = np.concatenate((qv[:3], pin.rpy.matrixToRpy(R)))
        full = np.zeros((6, 6))
        full[:3, :3] = R
        sphi, cphi = math.sin(eta[3]), math.cos(eta[3])
        ctheta, ttheta = math.cos(eta[4]), math.tan(eta[4])
        full[3:, 3:] = ((1.0, sphi * ttheta, cphi * ttheta), (0.0, cphi, -sphi),
                        (0.0, sphi / ctheta, cphi / ctheta))
        out = np.zeros((6, model.nv))
        out[:, : model.n_vehicle] = full[:, columns]

    state = [("uvms_qp", uvms_qp_tick), ("pinocchio", pinocchio_tick)]
    vehicle = [("plain_floats", uvms_qp_vehicle_tick), ("pinocchio_objects", matrix_vehicle_tick)]
    return state, vehicle if model.vehicle_kind == "spatial" else []


def rows_tick(model=None):
    """The demo stack's state + rows + bounds tick: ``(tick(q, t), model, configurations)``."""
    model = model or load_model("bluerov2_heavy_alpha5")
    stack = demo_stack(position=[0.6, 0.1, 0.1]).bind(model)
    slots = []
    for task in stack.tasks:
        A = np.empty((task.dim, model.nv))
        slots.append((task.fill, A, np.empty((2, task.dim))))
    static_lo, static_hi = np.full(model.nv, -np.inf), np.full(model.nv, np.inf)
    dynamic = []
    for c in stack.constraints:
        if c.is_static:
            c.fill_box(None, DT, static_lo, static_hi)
        elif c.has_box:
            dynamic.append(c.fill_box)
    lower, upper = np.empty(model.nv), np.empty(model.nv)

    def tick(q, t=0.0):
        state = model.state(q)
        for fill, A, sides in slots:
            fill(state, t, A, sides)
        lower[:] = static_lo
        upper[:] = static_hi
        for fill_box in dynamic:
            fill_box(state, DT, lower, upper)

    rng = np.random.default_rng(0)
    return tick, model, [model.random_configuration(rng) for _ in range(32)]


def run_rows(ticks: int) -> None:
    """The process callgrind counts: warm-up, then ``ticks`` rows ticks."""
    tick, _, qs = rows_tick()
    for k in range(50 + ticks):
        tick(qs[k % len(qs)], DT * k)


def count_rows_instructions(ticks: int) -> float:
    """Instructions per rows tick (state + rows + bounds), counted by callgrind."""
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind not found: install it (Debian: apt-get install valgrind)")

    def count(n: int) -> int:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "callgrind.out"
            proc = subprocess.run(
                ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
                 __file__, "--run-rows", str(n)],
                capture_output=True, text=True, check=False,
                env={**os.environ, "PYTHONHASHSEED": "0"})
        match = re.search(r"Collected\s*:\s*(\d+)", proc.stderr)
        if proc.returncode != 0 or match is None:
            raise SystemExit(f"valgrind run failed:\n{proc.stderr[-2000:]}")
        return int(match.group(1))

    return (count(ticks) - count(0)) / ticks


def _line(name: str, a: dict[str, float], b: dict[str, float]) -> str:
    return (f"{name:<24}{a['median_us']:>16.2f}{a['p10_us']:>8.2f}-{a['p90_us']:<6.2f}"
            f"{b['median_us']:>16.2f}{b['p10_us']:>8.2f}-{b['p90_us']:<6.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="bluerov2_heavy_alpha5", help="or 'all'")
    parser.add_argument("--reps", type=int, default=300, help="timed batches of 200 ticks")
    parser.add_argument("--json", help="write the numbers to this file")
    parser.add_argument("--instructions", type=int, metavar="N",
                        help="count instructions of N rows ticks with valgrind instead")
    parser.add_argument("--run-rows", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.run_rows is not None:
        run_rows(args.run_rows)
        return
    if args.instructions:
        per_tick = count_rows_instructions(args.instructions)
        print(f"demo stack, state + rows + bounds: {per_tick / 1e3:.1f} k instructions per tick")
        return
    names = bundled_models() if args.model == "all" else [args.model]
    print(f"Python {platform.python_version()}, Pinocchio {pin.__version__}, "
          f"{args.reps} x {BATCH} ticks, loops interleaved batch by batch")
    header = f"{'model':<24}{'median [us]':>16}{'p10-p90':>15}{'median [us]':>16}{'p10-p90':>15}"
    results: dict[str, dict] = {}
    vehicle_lines = []
    print("1. state update + tool Jacobian + arm Jacobian: uvms-qp | bare Pinocchio")
    print(header)
    for name in names:
        model = load_model(name)
        rng = np.random.default_rng(0)
        qs = [model.random_configuration(rng) for _ in range(64)]
        state, vehicle = state_ticks(model)
        r = _interleaved(state + vehicle, qs, args.reps)
        results[name] = r
        print(_line(name, r["uvms_qp"], r["pinocchio"]))
        if vehicle:
            vehicle_lines.append(_line(name, r["plain_floats"], r["pinocchio_objects"]))
    if vehicle_lines:
        print("2. state update + eta + J_eta: plain floats (the state) | Pinocchio objects")
        print(header)
        print("\n".join(vehicle_lines))
    tick, model, qs = rows_tick()
    r = _interleaved([("rows", tick), ("state", model.state)], qs, args.reps)
    results["demo_stack"] = r
    print("3. demo stack, fresh state every tick: state + rows + bounds | state alone")
    print(header)
    print(_line(model.name, r["rows"], r["state"]))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()
