"""Ready-made task stacks: the BlueROV2 demo stack and seeded random stacks.

* :func:`demo_stack`: the four-level stack of the tasks documentation and of
  ``benchmarks/bench_controller.py`` (tool; manipulability floor and joint-limit margin; payload
  moment, station keeping and current alignment; vehicle motion and posture) under joint
  position, joint rate and vehicle rate bounds.
* :func:`tool_posture_stack`: one weighted level, a tool frame task plus a light posture
  regularisation (the content of a Pink ``FrameTask`` + ``PostureTask`` problem).
* :func:`random_stack` and :func:`random_bounds`: the random mission stacks and hard bounds of
  the benchmark's ``random`` set (:func:`uvms_qp.bench.sets.random_uvms_problem`), also drawn by
  the controller property tests.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from .._validation import FloatArray
from ..constraints import (
    JointPositionBounds,
    JointVelocityBounds,
    LinearInequality,
    VehicleRateBounds,
)
from ..stack import Level, Stack
from ..tasks import (
    CurrentAlignmentTask,
    EndEffectorTask,
    JointLimitGradientTask,
    JointLimitMarginTask,
    ManipulabilityAscendTask,
    ManipulabilityFloorTask,
    PayloadMomentBoundTask,
    PayloadMomentReduceTask,
    PostureTask,
    StationKeepingTask,
    VehicleAttitudeTask,
    VehicleMotionTask,
)


def _standard_bounds() -> list[Any]:
    """Joint position (gain 0.5), joint rate (model limits) and vehicle rate bounds."""
    return [JointPositionBounds(gain=0.5), JointVelocityBounds(),
            VehicleRateBounds(linear=0.5, angular=0.3)]  # [m/s], [rad/s]


def demo_stack(*, trajectory: Any = None, position: list[float] | None = None) -> Stack:
    """The four-level demo stack for a vehicle-manipulator (e.g. ``bluerov2_heavy_alpha5``).

    Levels, highest first: the tool position (gain 2 [1/s]) following ``trajectory`` or held at
    ``position`` [m, world]; manipulability floor ``w >= 0.002`` and joint-limit margin 0.1 rad;
    payload moment (F = 10 N), station keeping and current alignment (heading 0.78 rad); vehicle
    motion (beta 0.8) and posture. Hard bounds: joint position (gain 0.5), joint rates (the
    model's limits), vehicle rates 0.5 m/s and 0.3 rad/s.

    Args:
        trajectory: Anything with ``sample(t)`` for the tool.
        position: Fixed tool target [m] (when no trajectory is given).

    Returns:
        A new :class:`~uvms_qp.stack.Stack` (fresh task objects on every call).
    """
    tool = (EndEffectorTask(trajectory=trajectory, gain=2.0) if trajectory is not None
            else EndEffectorTask(position=position, gain=2.0))
    return Stack(
        levels=[
            Level(tool),
            Level(ManipulabilityFloorTask(minimum=0.002, gain=2.0),
                  JointLimitMarginTask(margin=0.1, gain=2.0)),
            Level(PayloadMomentReduceTask(force=10.0, gain=0.5), StationKeepingTask(gain=1.0),
                  CurrentAlignmentTask(heading=0.78, gain=0.5)),
            Level(VehicleMotionTask(beta=0.8), PostureTask(gain=0.2)),
        ],
        constraints=_standard_bounds(),
    )


def tool_posture_stack(tool: Any, *, posture_gain: float = 0.1, posture_weight: float = 1e-3,
                       constraints: list[Any] | None = None) -> Stack:
    """One weighted level: the ``tool`` task plus a posture task of weight ``posture_weight``.

    Args:
        tool: The tool task (e.g. an :class:`~uvms_qp.tasks.EndEffectorTask`).
        posture_gain: Posture gain [1/s].
        posture_weight: Posture weight relative to the tool task.
        constraints: Hard constraints (default: those of :func:`demo_stack`).
    """
    return Stack(levels=[Level(tool, PostureTask(gain=posture_gain, weight=posture_weight))],
                 constraints=_standard_bounds() if constraints is None else constraints)


def random_target(state: Any, model: Any, rng: np.random.Generator, scale: float) -> FloatArray:
    """The tool position plus a normal draw of standard deviation ``scale`` [m] per axis.

    Planar models keep the tool's depth (their arm moves in the horizontal plane).
    """
    p = state.position("tool") + rng.normal(scale=scale, size=3)
    if model.vehicle_kind == "planar":
        p[2] = state.position("tool")[2]
    return p


def random_bounds(model: Any, rng: np.random.Generator) -> list[Any]:
    """Random hard bounds tight enough to be active.

    Joint rates 0.2-1 rad/s; joint positions with gain 0.3-1 (when every joint has finite
    limits); vehicle rates 0.05-0.5 m/s or rad/s (when there is a vehicle).
    """
    bounded = bool(np.isfinite(model.joint_lower).all() and np.isfinite(model.joint_upper).all())
    constraints: list[Any] = [
        JointVelocityBounds(limits=list(rng.uniform(0.2, 1.0, model.n_joints))),
    ]
    if bounded:
        constraints.append(JointPositionBounds(gain=float(rng.uniform(0.3, 1.0))))
    if model.vehicle_kind != "fixed":
        constraints.append(VehicleRateBounds(limits=list(rng.uniform(0.05, 0.5, model.n_vehicle))))
    return constraints


def random_stack(model: Any, state: Any, rng: np.random.Generator,
                 constraints: list[Any]) -> Stack:
    """A random mission stack: the tool task first in level 0, then 1-5 levels of mixed tasks.

    The tool task (position, or pose on spatial vehicles 40 % of the time) tracks a target about
    0.3 m from the tool. The other tasks, shuffled, fill the remaining levels one each, and the
    tasks left over join random levels (the first one included): a manipulability floor (around
    the current ``w``) or ascent; a joint-limit gradient (Wang et al. (2017),
    Eq. (15)-(16), saturated at the limits) or margin, when every joint has finite limits; a
    payload moment bound or reduction; with a vehicle, station keeping, current alignment (yaw
    actuated), vehicle attitude (roll and pitch actuated) and motion distribution; a posture
    task. A random general inequality over zeta joins ``constraints`` 40 % of the time.

    Args:
        model: The :class:`~uvms_qp.model.Model`.
        state: The model state the targets are drawn around.
        rng: Random generator (consumed).
        constraints: Hard constraints of the stack (e.g. :func:`random_bounds`); appended to.

    Returns:
        A new :class:`~uvms_qp.stack.Stack` of 2-6 levels.
    """
    bounded = bool(np.isfinite(model.joint_lower).all() and np.isfinite(model.joint_upper).all())
    vehicle = model.vehicle_kind != "fixed"
    ee_kwargs: dict[str, Any] = {"position": list(random_target(state, model, rng, 0.3))}
    mode: Literal["position", "pose"] = "position"
    if model.vehicle_kind == "spatial" and rng.uniform() < 0.4:
        mode = "pose"
        ee_kwargs["rotation"] = model.frame_pose(model.random_configuration(rng),
                                                 "tool")[:3, :3].tolist()
    pool: list[Any] = [EndEffectorTask(mode=mode, gain=float(rng.uniform(0.5, 3.0)),
                                       **ee_kwargs)]
    probe = ManipulabilityAscendTask()
    probe.bind(model)
    w0 = float(probe.compute_value(state)[0])
    if rng.uniform() < 0.5:
        pool.append(ManipulabilityFloorTask(minimum=w0 * float(rng.uniform(0.5, 1.5)),
                                            gain=float(rng.uniform(1.0, 10.0))))
    else:
        pool.append(ManipulabilityAscendTask(gain=float(rng.uniform(0.1, 1.0))))
    if bounded:
        gradient = rng.uniform() >= 0.6
        pool.append(JointLimitGradientTask(gain=2.0) if gradient
                    else JointLimitMarginTask(margin=0.05, gain=2.0))
    bound = rng.uniform() < 0.5
    force, maximum = float(rng.uniform(5.0, 30.0)), float(rng.uniform(0.0, 2.0))
    pool.append(PayloadMomentBoundTask(force=force, maximum=maximum, gain=1.0) if bound
                else PayloadMomentReduceTask(force=force, gain=1.0))
    if vehicle:
        pool.append(StationKeepingTask(gain=1.0, weight=float(rng.uniform(0.5, 2.0))))
        if "r" in model.actuated:
            pool.append(CurrentAlignmentTask(heading=float(rng.uniform(-3.0, 3.0))))
        if "p" in model.actuated and "q" in model.actuated:
            pool.append(VehicleAttitudeTask(gain=1.0))
        pool.append(VehicleMotionTask(beta=float(rng.uniform(0.2, 0.9))))
    pool.append(PostureTask(gain=0.5))
    n_levels = int(rng.integers(2, 7))
    rest = pool[1:]
    rng.shuffle(rest)
    n_levels = min(n_levels, 1 + len(rest))
    groups: list[list[Any]] = [[pool[0]]] + [[] for _ in range(n_levels - 1)]
    for i, task in enumerate(rest):
        k = 1 + i if i < n_levels - 1 else int(rng.integers(0, n_levels))
        groups[k].append(task)
    if rng.uniform() < 0.4:
        constraints.append(LinearInequality(A=[list(rng.normal(size=model.nv))],
                                            lower=[-0.2], upper=[0.3]))
    return Stack(levels=[Level(*g) for g in groups], constraints=constraints)
