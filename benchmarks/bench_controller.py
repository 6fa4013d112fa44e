"""Full control step of uvms-qp vs Pink on the BlueROV2 Heavy + Reach Alpha 5, same run.

Ours: state update (``model.state(q)``) + all task rows + hard bounds + HQP solve + StepResult,
for a 4-level stack with joint position, joint velocity and vehicle rate bounds.
Pink: ``Configuration(model, data, q)`` (forward kinematics) + ``solve_ik`` with a FrameTask and a
PostureTask in one weighted level, its ConfigurationLimit and VelocityLimit, through qpsolvers.
Both follow the same moving target (a circle around the start tool position) and integrate
their own zeta, so warm-start conditions are realistic. Prints medians, p99 and the ratio, first
with the three loops interleaved tick by tick (same machine load for all), then with each loop
alone in alternating blocks of 100 ticks (no other loop evicting caches between ticks, as in a
control process).

    python benchmarks/bench_controller.py [--steps 2000] [--solver daqp] [--breakdown 2000]
        [--scenario bluerov2_demo]

``--scenario NAME`` adds the per-task breakdown and the full-step median (fresh state every
tick, target time advancing) of a bundled scenario's controller.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from uvms_qp.bench.stacks import demo_stack, tool_posture_stack
from uvms_qp.controller import Controller
from uvms_qp.model import load_model
from uvms_qp.tasks import EndEffectorTask

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
    return tool_posture_stack(EndEffectorTask(trajectory=traj, gain=2.0))


def ours_stepper(model, q0, traj, solver, stack=None, deadline="period"):
    """One-tick closure for our controller (state update + step), integrating its own q.

    ``deadline``: the controller's (default: its period); ``bench_instructions.py`` passes None,
    since under valgrind a step runs some 50 times slower and would meet a wall-clock deadline
    that skips stages, so the count would measure the machine's load instead of the work.
    """
    stack = stack or demo_stack(trajectory=traj)
    ctrl = Controller(model, stack, solver=solver, dt=DT, deadline=deadline)
    box = {"q": q0.copy(), "statuses": {}, "c_times": []}

    def tick(k):
        start = time.perf_counter()
        result = ctrl.step(model.state(box["q"]), k * DT)
        elapsed = time.perf_counter() - start
        statuses = box["statuses"]  # keyed by the Status (a str): no enum property per tick
        statuses[result.status] = statuses.get(result.status, 0) + 1
        c_time = result.hierarchy.info.get("daqp_solve_time")  # DAQP's own C solve time [s]
        if c_time is not None:
            box["c_times"].append(c_time)
        box["q"] = model.integrate(box["q"], result.zeta, DT)
        return elapsed

    def error(t):
        return float(np.linalg.norm(model.frame_pose(box["q"], "tool")[:3, 3]
                                    - traj.sample(t).position))

    return tick, error, box, ctrl


def pink_stepper(model, q0, traj, solver):
    """One-tick closure for Pink: Configuration (kinematics) + solve_ik, same limits."""
    import pink
    import pinocchio as pin
    from pink.limits import ConfigurationLimit, VelocityLimit
    from pink.tasks import FrameTask
    from pink.tasks import PostureTask as PinkPosture

    pm = model.pin_model
    data = pm.createData()
    frame = FrameTask("tool", position_cost=1.0, orientation_cost=0.0, gain=1.0)
    posture = PinkPosture(cost=1e-3)
    posture.set_target(q0)
    vlim = np.minimum(np.r_[np.full(3, 0.5), np.full(3, 0.3), model.joint_rate_limit], 1e3)
    limits = [ConfigurationLimit(pm, config_limit_gain=0.5), VelocityLimit(pm, vlim)]
    tasks = [frame, posture]
    box = {"q": q0.copy()}

    def tick(k):
        start = time.perf_counter()
        conf = pink.Configuration(pm, data, box["q"], copy_data=False)
        frame.set_target(pin.SE3(np.eye(3), traj.sample(k * DT).position))
        v = pink.solve_ik(conf, tasks, DT, solver=solver, limits=limits, safety_break=False)
        elapsed = time.perf_counter() - start
        box["q"] = pin.integrate(pm, box["q"], v * DT)
        return elapsed

    def error(t):
        return float(np.linalg.norm(model.frame_pose(box["q"], "tool")[:3, 3]
                                    - traj.sample(t).position))

    return tick, error


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--solver", default="daqp", help="our back-end (default daqp)")
    parser.add_argument("--pink-solver", default="daqp", help="qpsolvers name used by Pink")
    parser.add_argument("--breakdown", type=int, default=2000, metavar="N",
                        help="ticks of the per-task breakdown with fresh states (0: skip)")
    parser.add_argument("--scenario", default="", metavar="NAME",
                        help="also break down this bundled scenario's controller (e.g. "
                             "bluerov2_demo)")
    args = parser.parse_args()

    model = load_model("bluerov2_heavy_alpha5")
    q0 = model.home()
    traj = Circle(model.frame_pose(q0, "tool")[:3, 3])
    ours, ours_err, ours_box, ctrl = ours_stepper(model, q0, traj, args.solver)
    small, small_err, _, _ = ours_stepper(model, q0, traj, args.solver, small_stack(traj))
    pink, pink_err = pink_stepper(model, q0, traj, args.pink_solver)
    # interleaved: the three loops see the same machine load
    t_ours, t_small, t_pink = [], [], []
    for k in range(args.steps):
        t_ours.append(ours(k))
        t_small.append(small(k))
        t_pink.append(pink(k))
    # then each loop in blocks of 100 ticks, the blocks alternating (continuing each motion):
    # within a block no other loop evicts its code and data between ticks, as in a control
    # process, while the alternation still spreads the machine's load over the three
    alone: dict[str, list[float]] = {"ours": [], "small": [], "pink": []}
    loops = {"ours": ours, "small": small, "pink": pink}
    for b in range(0, args.steps, 100):
        for name, loop in loops.items():
            alone[name].extend(loop(args.steps + k) for k in range(b, min(b + 100, args.steps)))
    t_end = 2 * args.steps * DT
    o_med, o_p99 = stats(t_ours[10:])
    s_med, s_p99 = stats(t_small[10:])
    p_med, p_p99 = stats(t_pink[10:])
    # split of our step at a fixed state: state update, rows + bounds, ladder (DAQP, measurement,
    # hierarchy result), step result
    state = model.state(q0)
    parts: dict[str, list[float]] = {"state": [], "rows+bounds+checks": [], "ladder": [],
                                     "step result": []}
    assembler, safe = ctrl.assembler, ctrl.safe
    for _ in range(500):
        start = time.perf_counter()
        model.state(q0)
        parts["state"].append(time.perf_counter() - start)
        start = time.perf_counter()
        assembler.fill(state, 0.0)
        parts["rows+bounds+checks"].append(time.perf_counter() - start)
        start = time.perf_counter()
        out = safe.solve(assembler.problem)
        parts["ladder"].append(time.perf_counter() - start)
        start = time.perf_counter()
        assembler.step_result(out, 0.0, 0.0, "hqp", ctrl.solver_name)
        parts["step result"].append(time.perf_counter() - start)
    parts = {k: v for k, v in parts.items() if v}
    print(f"model {model.name}, nv {model.nv}, {args.steps} interleaved steps, dt {DT} s")
    print(f"uvms-qp ({args.solver}, 4 levels, {sum(t.dim for t in ctrl.tasks)} task rows, "
          f"3 bound sets): median {o_med:7.1f} us  p99 {o_p99:7.1f} us  "
          f"statuses { {str(k): v for k, v in ours_box['statuses'].items()} }  "
          f"final tool error {ours_err(t_end):.2e} m")
    print("  split at a fixed state (medians): " + ", ".join(
        f"{k} {stats(v)[0]:.1f} us" for k, v in parts.items()))
    if ours_box["c_times"]:
        c_med = stats(ours_box["c_times"])[0]
        print(f"  DAQP's reported C solve time in the loop (excludes its update): median "
              f"{c_med:.1f} us, {c_med / o_med:.0%} of our median step")
    print(f"uvms-qp, Pink's content (tool position + posture, 1 level, same limits): "
          f"median {s_med:7.1f} us  p99 {s_p99:7.1f} us  final tool error {small_err(t_end):.2e} m")
    print(f"pink ({args.pink_solver}, FrameTask + PostureTask, 1 weighted level, limits): "
          f"median {p_med:7.1f} us  p99 {p_p99:7.1f} us  final tool error {pink_err(t_end):.2e} m")
    print(f"ratio ours/pink (median): 4-level stack {o_med / p_med:.2f}, "
          f"same content {s_med / p_med:.2f}")
    (ao, ao99), (as_, as99), (ap, ap99) = (stats(alone[k][10:]) for k in ("ours", "small", "pink"))
    print(f"each loop alone (blocks of 100 ticks), median / p99: "
          f"uvms-qp 4-level {ao:.1f} / {ao99:.1f} us, "
          f"same content {as_:.1f} / {as99:.1f} us, pink {ap:.1f} / {ap99:.1f} us; "
          f"ratio 4-level {ao / ap:.2f}, same content {as_ / ap:.2f}")
    if args.breakdown:
        print_breakdown(model, ctrl, q0, args.breakdown)
    if args.scenario:
        from uvms_qp.sim import load_scenario

        sc_ctrl = load_scenario(args.scenario).make_controller()
        print(f"scenario {args.scenario}: {sc_ctrl.model.name}, "
              f"{sum(t.dim for t in sc_ctrl.tasks)} task rows")
        print_breakdown(sc_ctrl.model, sc_ctrl, None, args.breakdown or 2000, step=True)


def print_breakdown(model, ctrl, q0, reps, step=False):
    """Per-tick cost of the rows and bounds with a fresh state every tick (no warm caches).

    Each task is timed alone as ``model.state(q) + task.fill`` minus ``model.state(q)``, so it
    includes the kinematic getters it triggers (shared getters count in every task using them;
    the sum exceeds the whole). Configurations cycle through a random set. With ``step`` the
    whole ``ctrl.step(model.state(q), t)`` is timed too (``q0`` is unused).
    """
    rng = np.random.default_rng(0)
    qs = [model.random_configuration(rng) for _ in range(32)]
    assembler = ctrl.assembler
    slots = list(assembler._slots)
    dt = ctrl.dt
    box_cons = list(assembler._dynamic_box)
    lower, upper = np.empty(model.nv), np.empty(model.nv)
    samples = {"state": [], "state+rows+bounds": []}
    samples.update({f"task {t.name} ({type(t).__name__})": [] for t, *_ in slots})
    samples.update({f"box {c.name}": [] for c in box_cons})
    clock = time.perf_counter
    for r in range(reps):
        q = qs[r % len(qs)]
        start = clock()
        model.state(q)
        samples["state"].append(clock() - start)
        start = clock()
        state = model.state(q)
        assembler.fill(state, 0.0)
        samples["state+rows+bounds"].append(clock() - start)
        for task, A, sides in slots:
            start = clock()
            state = model.state(q)
            task.fill(state, 0.0, A, sides)
            samples[f"task {task.name} ({type(task).__name__})"].append(clock() - start)
        for c in box_cons:
            lower.fill(-np.inf)
            upper.fill(np.inf)
            start = clock()
            state = model.state(q)
            c.fill_box(state, dt, lower, upper)
            samples[f"box {c.name}"].append(clock() - start)
        start = clock()
        model.state(q).vehicle_pose_jacobian()
        samples.setdefault("state+vehicle_pose_jacobian", []).append(clock() - start)
        if step:
            start = clock()
            ctrl.step(model.state(q), r * dt)
            samples.setdefault("full step (state + step)", []).append(clock() - start)
    base = stats(samples["state"])[0]
    print(f"breakdown, fresh state every tick ({reps} ticks, medians; rows below 'state' exclude "
          f"the state update of {base:.1f} us)")
    for label, values in samples.items():
        med = stats(values)[0]
        own = label == "state" or label.startswith("full step")
        print(f"  {label:<48}{med if own else med - base:8.1f} us")


if __name__ == "__main__":
    main()
