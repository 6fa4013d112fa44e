"""Random models, states and stacks shared by the reliability tests (not a test module).

Models are random Denavit-Hartenberg arms (3-7 revolute joints, random link lengths and twists,
finite joint and rate limits) on a planar or a spatial vehicle, built once per seed and reused.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from uvms_qp.constraints import (
    JointPositionBounds,
    JointVelocityBounds,
    LinearInequality,
    VehicleRateBounds,
)
from uvms_qp.model import Model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import (
    CurrentAlignmentTask,
    EndEffectorTask,
    JointLimitTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
    VehicleAttitudeTask,
    VehicleMotionTask,
)

KINDS = ("planar", "spatial")
JOINTS = (3, 4, 5, 6, 7)


@cache
def random_model(kind: str, n_joints: int, seed: int = 0) -> Model:
    """A random DH arm with ``n_joints`` revolute joints on a ``kind`` vehicle (cached)."""
    rng = np.random.default_rng(1000 * n_joints + seed + (0 if kind == "planar" else 500))
    rows = []
    for _ in range(n_joints):
        half = rng.uniform(0.8, 2.8)
        mid = rng.uniform(-0.3, 0.3)
        rows.append({
            "a": float(rng.uniform(0.05, 0.4)),
            "alpha": 0.0 if kind == "planar" else float(rng.choice([0.0, math.pi / 2,
                                                                    -math.pi / 2])),
            "d": 0.0 if kind == "planar" else float(rng.uniform(0.0, 0.1)),
            "lower": mid - half, "upper": mid + half,
            "rate_limit": float(rng.uniform(0.3, 1.5)),
        })
    return Model.from_dh(rows, vehicle=kind, name=f"random_{kind}_{n_joints}_{seed}")


def random_state(model: Model, rng: np.random.Generator, where: str) -> np.ndarray:
    """A configuration with joints ``inside``, ``at`` or just ``outside`` their limits.

    Spatial vehicles get random attitudes (roll and pitch up to +/-1.3 rad).
    """
    q = model.random_configuration(rng, tilt=1.3)
    eta, joints = model.split(q)
    lo, hi = model.joint_lower, model.joint_upper
    if where != "inside":
        pick = rng.uniform(size=model.n_joints) < 0.5
        side = rng.uniform(size=model.n_joints) < 0.5
        off = 0.0 if where == "at" else rng.choice([1e-9, 1e-6, 1e-3, 1e-2], model.n_joints)
        edge = np.where(side, lo - off, hi + off)
        joints = np.where(pick, edge, joints)
    return model.configuration(eta, joints)


def random_stack(model: Model, rng: np.random.Generator, reachable: bool) -> Stack:
    """1-5 levels mixing equality and inequality tasks, weights in [1e-3, 1e3], all hard bounds."""
    state = model.state(random_state(model, rng, "inside"))
    names = iter(f"t{i}" for i in range(100))

    def weight() -> float:
        return float(10.0 ** rng.uniform(-3, 3))

    def tool_task() -> EndEffectorTask:
        if reachable:
            target = model.frame_pose(model.random_configuration(rng), "tool")
        else:
            target = state.pose("tool").copy()
            target[:3, 3] += rng.normal(size=3) * 5.0
        if model.vehicle_kind == "planar":
            target[2, 3] = state.position("tool")[2]
            return EndEffectorTask(mode="position", axes=["x", "y"], position=target[:3, 3],
                                   gain=float(rng.uniform(0.5, 5.0)), weight=weight(),
                                   name=next(names))
        mode = str(rng.choice(["position", "pose", "orientation"]))
        kwargs = {"position": target[:3, 3]} if mode != "orientation" else {}
        if mode != "position":
            kwargs["rotation"] = target[:3, :3]
        return EndEffectorTask(mode=mode, gain=float(rng.uniform(0.5, 5.0)), weight=weight(),
                               name=next(names), **kwargs)

    def other() -> object:
        choice = int(rng.integers(0, 8))
        if choice == 0:
            return PostureTask(gain=float(rng.uniform(0.1, 2.0)), weight=weight(),
                               name=next(names))
        if choice == 1:
            return StationKeepingTask(gain=float(rng.uniform(0.1, 2.0)), weight=weight(),
                                      name=next(names))
        if choice == 2:
            return ManipulabilityTask(mode="floor", minimum=float(10.0 ** rng.uniform(-4, -1)),
                                      gain=1.0, weight=weight(), name=next(names))
        if choice == 3:
            return JointLimitTask(mode="margin", margin=float(rng.uniform(0.01, 0.2)),
                                  weight=weight(), name=next(names))
        if choice == 4:
            return PayloadMomentTask(mode="bound", force=float(rng.uniform(0, 30)),
                                     maximum=float(rng.uniform(0.0, 1.0)), weight=weight(),
                                     name=next(names))
        if choice == 5:
            return CurrentAlignmentTask(heading=float(rng.uniform(-3, 3)), weight=weight(),
                                        name=next(names))
        if choice == 6 and model.vehicle_kind == "spatial":
            return VehicleAttitudeTask(weight=weight(), name=next(names))
        return VehicleMotionTask(beta=float(rng.uniform(0.2, 0.9)), weight=weight(),
                                 name=next(names))

    n_levels = int(rng.integers(1, 6))
    levels = [Level(tool_task())] if rng.uniform() < 0.8 else [Level(other())]
    for _ in range(n_levels - 1):
        levels.append(Level(*[other() for _ in range(int(rng.integers(1, 3)))]))
    constraints = [JointPositionBounds(gain=float(rng.uniform(0.2, 1.0))),
                   JointVelocityBounds(),
                   VehicleRateBounds(limits=list(rng.uniform(0.1, 0.6, model.n_vehicle)))]
    if rng.uniform() < 0.3:
        constraints.append(LinearInequality(A=[list(rng.normal(size=model.nv))],
                                            lower=[-0.2], upper=[0.3]))
    return Stack(levels=levels, constraints=constraints)
