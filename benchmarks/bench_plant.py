"""Cost and accuracy of the floating plant (``uvms_qp.dynamics.FloatingPlant``).

Cost: median wall time of one physics step (``plant.step``, RK4, four evaluations of the
dynamics) and of one evaluation (``plant.accelerations``), with 10th-90th percentiles, on the
BlueROV2 Heavy + Alpha-5-like arm with the arm moving, in still water and in a constant current;
each sample is a batch of steps, the cases interleaved batch by batch so that machine load hits
them alike; wall time and this process's CPU time (on a loaded machine the CPU time is the cost,
the wall time what a run waits). From the step's median: the plant's cost per simulated
millisecond at the default step and the real-time factor of the plant alone (the dynamic
demo's budget: 30 s simulated in 6 s of wall time, QP and thrusters included, leaves the plant
about 0.15 ms per simulated ms).

Accuracy (``--accuracy``): the same motion (arm sweeping, current, thrust) integrated for 5 s at
steps of 20, 10, 5, 2.5 and 1 ms against a reference at 0.3125 ms (RK4's error there is ~10^-5 of
the 5 ms one): largest error in vehicle position [m], attitude (angle of the rotation error)
[rad], body velocity [m/s, rad/s] and joint angles [rad], and the observed order.

Usage: ``python benchmarks/bench_plant.py [--reps 30] [--batch 50] [--accuracy] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import platform
import time

import numpy as np
import pinocchio as pin

from uvms_qp import load_model
from uvms_qp.dynamics import DEFAULT_STEP, FloatingPlant

WRENCH = np.array([5.0, -3.0, -6.0, 0.3, 2.0, -0.4])  # [N, N m]


def _reference(t: float) -> np.ndarray:
    """Joint velocity references of a sweep [rad/s]."""
    return 0.4 * np.sin(np.array([1.1, 1.7, 2.3, 2.9]) * t)


def _plants():
    model = load_model("bluerov2_heavy_alpha5")
    still = FloatingPlant(model)
    flowing = FloatingPlant(model, current=[0.3, -0.1, 0.05])
    q = model.configuration([0, 0, 0, 0.05, -0.05, 0.3], model.home()[7:])
    v = np.array([0.2, -0.1, 0.05, 0.05, -0.05, 0.1, 0.2, -0.2, 0.2, 0.1])
    return model, still, flowing, q, v


def _timed_steps(plant, q, v, batch: int, t0: float):
    """Wall and CPU time per step [us], and the state reached."""
    h = plant.physics_step
    t = t0
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(batch):
        q, v = plant.step(q, v, WRENCH, _reference(t), t)
        t += h
    return ((time.perf_counter() - wall) / batch * 1e6,
            (time.process_time() - cpu) / batch * 1e6, q, v, t)


def _timed_evaluations(plant, q, v, batch: int) -> tuple[float, float]:
    reference = _reference(0.0)
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(batch):
        plant.accelerations(q, v, WRENCH, reference, 0.0)
    return ((time.perf_counter() - wall) / batch * 1e6,
            (time.process_time() - cpu) / batch * 1e6)


def cost(reps: int, batch: int) -> dict:
    """Median [us] and percentiles of a step and an evaluation, interleaved (wall and CPU)."""
    _, still, flowing, q0, v0 = _plants()
    samples: dict[str, list[tuple[float, float]]] = {
        "step, still water": [], "step, current": [], "evaluation, still water": []}
    states = {"still": (q0, v0, 0.0), "flow": (q0, v0, 0.0)}
    for plant in (still, flowing):  # warm-up
        _timed_steps(plant, q0, v0, 5, 0.0)
    for _ in range(reps):
        q, v, t = states["still"]
        wall, cpu, q, v, t = _timed_steps(still, q, v, batch, t)
        states["still"] = (q, v, t) if t < 20.0 else (q0, v0, 0.0)
        samples["step, still water"].append((wall, cpu))
        q, v, t = states["flow"]
        wall, cpu, q, v, t = _timed_steps(flowing, q, v, batch, t)
        states["flow"] = (q, v, t) if t < 20.0 else (q0, v0, 0.0)
        samples["step, current"].append((wall, cpu))
        samples["evaluation, still water"].append(_timed_evaluations(still, q0, v0, batch))
    out = {}
    for name, values in samples.items():
        a = np.array(values)
        out[name] = {"median_us": float(np.median(a[:, 0])),
                     "p10_us": float(np.percentile(a[:, 0], 10)),
                     "p90_us": float(np.percentile(a[:, 0], 90)),
                     "cpu_median_us": float(np.median(a[:, 1]))}
    return out


def _rotation_angle(R: np.ndarray) -> float:
    return float(np.linalg.norm(pin.log3(R)))


def accuracy(duration: float = 5.0) -> list[dict]:
    """Errors of the state after ``duration`` s against a fine-step reference."""
    _, _, flowing, q0, v0 = _plants()
    # the references change at the coarsest step's instants only (a zero-order hold at 20 ms),
    # so every step size integrates the same inputs
    hold = 0.02

    def held_final(dt: float):
        q, v = q0, v0
        for k in range(round(duration / dt)):
            t = k * dt
            reference = _reference(math.floor(t / hold + 1e-9) * hold)
            q, v = flowing.step(q, v, WRENCH, reference, t, dt)
        return q, v

    q_ref, v_ref = held_final(0.0003125)
    rows = []
    for dt in (0.02, 0.01, 0.005, 0.0025, 0.001):
        q, v = held_final(dt)
        R = pin.Quaternion(q[3:7]).toRotationMatrix()
        R_ref = pin.Quaternion(q_ref[3:7]).toRotationMatrix()
        rows.append({"dt_ms": dt * 1e3,
                     "position_m": float(np.abs(q[:3] - q_ref[:3]).max()),
                     "attitude_rad": _rotation_angle(R_ref.T @ R),
                     "velocity": float(np.abs(v[:6] - v_ref[:6]).max()),
                     "joints_rad": float(np.abs(q[7:] - q_ref[7:]).max())})
    for prev, row in itertools.pairwise(rows):
        ratio = prev["dt_ms"] / row["dt_ms"]
        worst_prev = max(prev["position_m"], prev["attitude_rad"], prev["velocity"])
        worst = max(row["position_m"], row["attitude_rad"], row["velocity"])
        row["order"] = math.log(worst_prev / worst) / math.log(ratio) if worst > 0 else math.nan
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=30, help="timed batches per case")
    parser.add_argument("--batch", type=int, default=50, help="steps per batch")
    parser.add_argument("--accuracy", action="store_true", help="also measure the accuracy")
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args()
    result: dict = {"machine": platform.platform(), "python": platform.python_version(),
                    "default_step_ms": DEFAULT_STEP * 1e3}
    result["cost"] = cost(args.reps, args.batch)
    print(f"floating plant, BlueROV2 Heavy + Alpha-5-like arm, arm sweeping; default step "
          f"{DEFAULT_STEP * 1e3:g} ms (RK4)")
    print(f"{'case':28s} {'wall median us':>15s} {'p10':>8s} {'p90':>8s} {'CPU median us':>14s}")
    for name, row in result["cost"].items():
        print(f"{name:28s} {row['median_us']:15.1f} {row['p10_us']:8.1f} {row['p90_us']:8.1f} "
              f"{row['cpu_median_us']:14.1f}")
    for name in ("step, still water", "step, current"):
        row = result["cost"][name]
        wall, cpu = (row[k] / (DEFAULT_STEP * 1e3) / 1e3 for k in ("median_us", "cpu_median_us"))
        row["ms_per_simulated_ms"], row["cpu_ms_per_simulated_ms"] = wall, cpu
        print(f"{name}: {wall:.3f} ms wall ({cpu:.3f} ms CPU) per simulated ms, "
              f"{wall * 1e3:.0f} ms wall per simulated s; plant alone {1.0 / wall:.0f}x real "
              "time")
    if args.accuracy:
        result["accuracy"] = accuracy()
        print("\naccuracy after 5 s (arm sweeping, current, thrust) against a 0.3125 ms reference")
        print(f"{'dt ms':>6s} {'position m':>11s} {'attitude rad':>13s} {'velocity':>10s} "
              f"{'joints rad':>11s} {'order':>6s}")
        for row in result["accuracy"]:
            order = f"{row['order']:.2f}" if "order" in row else ""
            print(f"{row['dt_ms']:6g} {row['position_m']:11.2e} {row['attitude_rad']:13.2e} "
                  f"{row['velocity']:10.2e} {row['joints_rad']:11.2e} {order:>6s}")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
