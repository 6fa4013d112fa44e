"""Cost of one control-tick state update, uvms-qp versus bare Pinocchio.

One tick = validate q, forward kinematics + joint Jacobians + frame placements, the tool Jacobian
over zeta (world axes) and the arm-only tool Jacobian (arm_base axes). Bare Pinocchio does the
same work with no validation and no caching: ``computeJointJacobians`` + ``updateFramePlacements``
+ ``getFrameJacobian`` on the whole model, ``computeJointJacobians`` + ``getFrameJacobian`` on the
bare arm.

A second table (vehicles with roll and pitch) times the state update plus the vehicle pose ``eta``
and ``J_eta`` (``State.vehicle_pose_jacobian``, plain floats) against the same numbers built from
Pinocchio's quaternion and roll-pitch-yaw objects and numpy blocks.

Usage: ``python benchmarks/bench_state.py [--model NAME] [--reps N] [--json FILE]``.
Prints the median and the 10th/90th percentiles in microseconds per tick.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time

import numpy as np
import pinocchio as pin

from uvms_qp import bundled_models, load_model
from uvms_qp.model import State

BATCH = 200  # ticks per timed batch (amortises the timer call)


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


def bench(name: str, reps: int) -> dict[str, dict[str, float]]:
    model = load_model(name)
    rng = np.random.default_rng(0)
    qs = [model.random_configuration(rng) for _ in range(64)]

    def uvms_qp_tick(q):
        state = State(model, q)
        state.jacobian("tool")
        state.arm_jacobian("tool")

    pm, data = model.pin_model, model.pin_model.createData()
    arm = model._arm_model
    arm_data = arm.createData()
    fid, arm_fid = model.frame_id("tool"), model._arm_frame_ids["tool"]
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    nqv = model.nq_vehicle
    select = model._select

    def pinocchio_tick(q):
        pin.computeJointJacobians(pm, data, q)
        pin.updateFramePlacements(pm, data)
        J = pin.getFrameJacobian(pm, data, fid, lwa)
        if select is not None:
            J = J[:, select]
        pin.computeJointJacobians(arm, arm_data, q[nqv:])
        pin.getFrameJacobian(arm, arm_data, arm_fid, lwa)

    def uvms_qp_vehicle_tick(q):
        State(model, q).vehicle_pose_jacobian()

    vehicle = model.vehicle
    columns = list(vehicle.actuated_indices)

    def matrix_vehicle_tick(q):
        """The same J_eta through Pinocchio's rotation/RPY objects and numpy blocks."""
        State(model, q)
        if model.vehicle_kind == "spatial":
            qv = q[:nqv]
            R = pin.Quaternion(qv[6], qv[3], qv[4], qv[5]).toRotationMatrix()
            eta = np.concatenate((qv[:3], pin.rpy.matrixToRpy(R)))
            full = np.zeros((6, 6))
            full[:3, :3] = pin.rpy.rpyToMatrix(eta[3], eta[4], eta[5])
            sphi, cphi = math.sin(eta[3]), math.cos(eta[3])
            ctheta, ttheta = math.cos(eta[4]), math.tan(eta[4])
            full[3:, 3:] = ((1.0, sphi * ttheta, cphi * ttheta), (0.0, cphi, -sphi),
                            (0.0, sphi / ctheta, cphi / ctheta))
            out = np.zeros((6, model.nv))
            out[:, : model.n_vehicle] = full[:, columns]

    ticks = [("uvms_qp", uvms_qp_tick), ("pinocchio", pinocchio_tick),
             ("uvms_qp_vehicle", uvms_qp_vehicle_tick), ("matrix_vehicle", matrix_vehicle_tick)]
    for _, fn in ticks:  # warm-up
        _time(fn, qs, 20)
    out = {}
    for label, fn in ticks:
        s = _time(fn, qs, reps)
        out[label] = {
            "median_us": float(np.median(s)),
            "p10_us": float(np.percentile(s, 10)),
            "p90_us": float(np.percentile(s, 90)),
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="bluerov2_heavy_alpha5", help="or 'all'")
    parser.add_argument("--reps", type=int, default=300, help="timed batches of 200 ticks")
    parser.add_argument("--json", help="write the numbers to this file")
    args = parser.parse_args()
    names = bundled_models() if args.model == "all" else [args.model]
    print(
        f"state update + tool Jacobian + arm Jacobian; {platform.python_version()}, "
        f"Pinocchio {pin.__version__}, {args.reps} x {BATCH} ticks"
    )
    print(
        f"{'model':<24}{'uvms-qp median [us]':>22}{'p10-p90':>14}"
        f"{'Pinocchio median [us]':>24}{'p10-p90':>14}"
    )
    results = {}
    vehicle_lines = []
    for name in names:
        r = bench(name, args.reps)
        results[name] = r
        a, b = r["uvms_qp"], r["pinocchio"]
        print(
            f"{name:<24}{a['median_us']:>22.2f}{a['p10_us']:>7.2f}-{a['p90_us']:<6.2f}"
            f"{b['median_us']:>24.2f}{b['p10_us']:>7.2f}-{b['p90_us']:<6.2f}"
        )
        c, d = r["uvms_qp_vehicle"], r["matrix_vehicle"]
        if load_model(name).vehicle_kind == "spatial":
            vehicle_lines.append(
                f"{name:<24}{c['median_us']:>22.2f}{c['p10_us']:>7.2f}-{c['p90_us']:<6.2f}"
                f"{d['median_us']:>24.2f}{d['p10_us']:>7.2f}-{d['p90_us']:<6.2f}"
            )
    if vehicle_lines:
        print("state update + vehicle_pose_jacobian (eta and J_eta); same numbers both ways")
        print(f"{'model':<24}{'plain floats [us]':>22}{'p10-p90':>14}"
              f"{'Pinocchio objects [us]':>24}{'p10-p90':>14}")
        print("\n".join(vehicle_lines))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(results, fh, indent=2)


if __name__ == "__main__":
    main()
