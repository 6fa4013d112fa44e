"""Full control step of uvms-qp vs Pink on the BlueROV2 Heavy + Reach Alpha 5, same run.

Ours: state update (``model.state(q)``) + all task rows + hard bounds + HQP solve + StepResult,
for a 4-level stack with joint position, joint velocity and vehicle rate bounds.
Pink: ``Configuration(model, data, q)`` (forward kinematics) + ``solve_ik`` with a FrameTask and a
PostureTask in one weighted level, its ConfigurationLimit and VelocityLimit, through qpsolvers.
Both follow the same moving target (a circle around the start tool position) and integrate
their own zeta, so warm-start conditions are realistic. Prints medians, p99 and the ratio.

    python benchmarks/bench_controller.py [--steps 2000] [--solver daqp]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.controller import Controller
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import (
    CurrentAlignmentTask,
    EndEffectorTask,
    JointLimitTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
    VehicleMotionTask,
)

DT = 0.05


class Sample:
    """One trajectory sample (position-only)."""

    __slots__ = ("angular_velocity", "position", "rotation", "velocity")

    def __init__(self, position, velocity):
        self.position, self.velocity = position, velocity
        self.rotation = self.angular_velocity = None


class Circle:
    def __init__(self, center, radius=0.15, period=8.0):
        self.c, self.r, self.w = np.asarray(center), radius, 2 * math.pi / period
        self.duration = period

    def sample(self, t):
        a = self.w * t
        c, s = math.cos(a), math.sin(a)
        r, rw = self.r, self.r * self.w
        return Sample(self.c + np.array([r * (c - 1.0), r * s, 0.0]),
                      np.array([-rw * s, rw * c, 0.0]))


def stats(samples):
    us = np.asarray(samples) * 1e6
    return float(np.median(us)), float(np.percentile(us, 99))


def small_stack(traj):
    """The content of the Pink problem: tool position + posture in one level, same limits."""
    return Stack(
        levels=[Level(EndEffectorTask(trajectory=traj, gain=2.0),
                      PostureTask(gain=0.1, weight=1e-3))],
        constraints=[JointPositionBounds(gain=0.5), JointVelocityBounds(),
                     VehicleRateBounds(linear=0.5, angular=0.3)],
    )


def run_ours(model, q0, traj, steps, solver, stack=None):
    stack = stack or Stack(
        levels=[
            Level(EndEffectorTask(trajectory=traj, gain=2.0)),                       # [1/s]
            Level(ManipulabilityTask(mode="floor", minimum=0.002, gain=2.0),
                  JointLimitTask(mode="margin", margin=0.1, gain=2.0)),
            Level(PayloadMomentTask(force=10.0, gain=0.5), StationKeepingTask(gain=1.0),
                  CurrentAlignmentTask(heading=0.78, gain=0.5)),                     # [rad]
            Level(VehicleMotionTask(beta=0.8), PostureTask(gain=0.2)),
        ],
        constraints=[JointPositionBounds(gain=0.5), JointVelocityBounds(),
                     VehicleRateBounds(linear=0.5, angular=0.3)],
    )
    ctrl = Controller(model, stack, solver=solver, dt=DT)
    q = q0.copy()
    times, statuses = [], {}
    for k in range(steps):
        t = k * DT
        start = time.perf_counter()
        state = model.state(q)
        result = ctrl.step(state, t)
        times.append(time.perf_counter() - start)
        statuses[result.status.value] = statuses.get(result.status.value, 0) + 1
        q = model.integrate(q, result.zeta, DT)
    err = np.linalg.norm(model.frame_pose(q, "tool")[:3, 3] - traj.sample(steps * DT).position)
    return times, statuses, err, ctrl


def run_pink(model, q0, traj, steps, solver):
    import pink
    from pink.limits import ConfigurationLimit, VelocityLimit
    from pink.tasks import FrameTask
    from pink.tasks import PostureTask as PinkPosture

    pm = model.pin_model
    data = pm.createData()
    frame = pink.tasks.FrameTask("tool", position_cost=1.0, orientation_cost=0.0, gain=0.1)
    posture = PinkPosture(cost=1e-3)
    posture.set_target(q0)
    vlim = np.minimum(np.r_[np.full(3, 0.5), np.full(3, 0.3), model.joint_rate_limit], 1e3)
    limits = [ConfigurationLimit(pm, config_limit_gain=0.5), VelocityLimit(pm, vlim)]
    tasks = [frame, posture]
    q = q0.copy()
    times = []
    import pinocchio as pin
    for k in range(steps):
        t = k * DT
        start = time.perf_counter()
        conf = pink.Configuration(pm, data, q, copy_data=False)
        frame.set_target(pin.SE3(np.eye(3), traj.sample(t).position))
        v = pink.solve_ik(conf, tasks, DT, solver=solver, limits=limits, safety_break=False)
        times.append(time.perf_counter() - start)
        q = pin.integrate(pm, q, v * DT)
    err = np.linalg.norm(model.frame_pose(q, "tool")[:3, 3] - traj.sample(steps * DT).position)
    return times, err, FrameTask


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--solver", default="daqp", help="our back-end (default daqp)")
    parser.add_argument("--pink-solver", default="daqp", help="qpsolvers name used by Pink")
    args = parser.parse_args()

    model = load_model("bluerov2_heavy_alpha5")
    q0 = model.home()
    traj = Circle(model.frame_pose(q0, "tool")[:3, 3])

    ours, statuses, err_ours, ctrl = run_ours(model, q0, traj, args.steps, args.solver)
    pink_times, err_pink, _ = run_pink(model, q0, traj, args.steps, args.pink_solver)
    small, _, err_small, _ = run_ours(model, q0, traj, args.steps, args.solver, small_stack(traj))
    o_med, o_p99 = stats(ours[10:])
    p_med, p_p99 = stats(pink_times[10:])
    # split of our step: rows + bounds + solve (no state update)
    state = model.state(q0)
    solve_only = []
    for _ in range(500):
        start = time.perf_counter()
        ctrl._solver.solve_problem(ctrl._new_problem())
        solve_only.append(time.perf_counter() - start)
    backend_only = []
    for _ in range(500):
        problem = ctrl._new_problem()
        start = time.perf_counter()
        ctrl._solver._backend.solve(problem)
        backend_only.append(time.perf_counter() - start)
    fill_only = []
    for _ in range(500):
        start = time.perf_counter()
        ctrl._fill(state, 0.0)
        ctrl._fill_box(state)
        fill_only.append(time.perf_counter() - start)
    state_only = []
    for _ in range(500):
        start = time.perf_counter()
        model.state(q0)
        state_only.append(time.perf_counter() - start)
    print(f"model {model.name}, nv {model.nv}, {args.steps} steps, dt {DT} s")
    print(f"uvms-qp ({args.solver}, 4 levels, {sum(t.dim for t in ctrl.tasks)} task rows, "
          f"3 bound sets): median {o_med:7.1f} us  p99 {o_p99:7.1f} us  statuses {statuses}  "
          f"final tool error {err_ours:.2e} m")
    print(f"  of which: state {stats(state_only)[0]:.1f} us, rows+bounds "
          f"{stats(fill_only)[0]:.1f} us, solve+evaluate {stats(solve_only)[0]:.1f} us "
          f"(back-end call alone {stats(backend_only)[0]:.1f} us)")
    print(f"pink ({args.pink_solver}, FrameTask + PostureTask, 1 weighted level, limits): "
          f"median {p_med:7.1f} us  p99 {p_p99:7.1f} us  final tool error {err_pink:.2e} m")
    s_med, s_p99 = stats(small[10:])
    print(f"uvms-qp, Pink's content (tool position + posture, 1 level, same limits): "
          f"median {s_med:7.1f} us  p99 {s_p99:7.1f} us  final tool error {err_small:.2e} m")
    print(f"ratio ours/pink (median): 4-level stack {o_med / p_med:.2f}, "
          f"same content {s_med / p_med:.2f}")


if __name__ == "__main__":
    main()
