"""Controller properties on random (model, state, target, stack) draws.

For the DAQP hierarchical back-end and two qpsolvers cascades: zeta is finite, the hard box and
rows hold to 1e-7, and a lower level never changes what a higher level achieves (solve again
with the lower levels removed: each remaining level's violation vector is unique at the
lexicographic optimum, so its norm must not move).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_qp.constraints import (
    JointPositionBounds,
    JointVelocityBounds,
    LinearInequality,
    VehicleRateBounds,
)
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

MODELS = {name: load_model(name) for name in
          ("bluerov2_heavy_alpha5", "wang_9dof", "soylu_planar")}
SOLVERS = ["daqp", "cascade:quadprog", "cascade:piqp"]


def random_problem(model, rng):
    """A random state and a random 3-4 level stack with all hard bounds."""
    q = model.random_configuration(rng)
    state = model.state(q)
    p_tool = state.position("tool")
    target = p_tool + rng.normal(scale=0.3, size=3)
    if model.vehicle_kind == "planar":
        target[2] = p_tool[2]
    mode = "position"
    ee_kwargs = {"position": target}
    if model.vehicle_kind == "spatial" and rng.uniform() < 0.5:
        mode = "pose"
        ee_kwargs["rotation"] = model.frame_pose(model.random_configuration(rng), "tool")[:3, :3]
    levels = [Level(EndEffectorTask(mode=mode, gain=float(rng.uniform(0.5, 3)), **ee_kwargs))]
    w0 = ManipulabilityTask(mode="ascend").bind(model).compute_value(state)[0]
    second = [ManipulabilityTask(mode="floor", minimum=float(w0 * rng.uniform(0.5, 1.5)),
                                 gain=float(rng.uniform(1, 10)))]
    if np.isfinite(model.joint_lower).all():
        second.append(JointLimitTask(mode="margin", margin=0.05, gain=2.0))
    if rng.uniform() < 0.5:
        second.append(PayloadMomentTask(mode="bound", force=20.0,
                                        maximum=float(rng.uniform(0.0, 2.0)), gain=2.0))
    levels.append(Level(*second))
    third = [PayloadMomentTask(force=float(rng.uniform(0, 30)), gain=0.2, name="payload_reduce")]
    if model.vehicle_kind != "fixed":
        third += [StationKeepingTask(gain=1.0, weight=float(rng.uniform(0.5, 2))),
                  CurrentAlignmentTask(heading=float(rng.uniform(-3, 3)))]
    levels.append(Level(*third))
    if rng.uniform() < 0.7:
        levels.append(Level(VehicleMotionTask(beta=float(rng.uniform(0.2, 0.9))),
                            PostureTask(gain=0.5)))
    constraints = [JointPositionBounds(gain=float(rng.uniform(0.2, 1.0))),
                   JointVelocityBounds(limits=list(rng.uniform(0.3, 1.0, model.n_joints))),
                   VehicleRateBounds(limits=list(rng.uniform(0.1, 0.6, model.n_vehicle)))]
    if rng.uniform() < 0.5:
        constraints.append(LinearInequality(A=[list(rng.normal(size=model.nv))],
                                            lower=[-0.2], upper=[0.3]))
    return state, Stack(levels=levels, constraints=constraints)


def check_draw(model, seed, solver):
    rng = np.random.default_rng(seed)
    state, stack = random_problem(model, rng)
    full = Controller(model, stack, solver=solver, dt=0.05).step(state, 0.0)
    assert np.all(np.isfinite(full.zeta))
    assert full.ok, full.summary()
    assert full.bound_violation <= 1e-7, full.summary()
    for k in range(len(stack.levels) - 1):
        partial = Stack(levels=list(stack.levels[: k + 1]), constraints=list(stack.constraints))
        sub = Controller(model, partial, solver=solver, dt=0.05).step(state, 0.0)
        assert sub.ok
        for j in range(k + 1):
            a, b = full.level_violations[j], sub.level_violations[j]
            assert abs(a - b) <= 1e-5 * (1.0 + b), (
                f"{model.name} seed {seed} {solver}: level {j} violation {a:.3e} with levels "
                f"below, {b:.3e} without\n{full.summary()}\n{sub.summary()}")


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("name", list(MODELS))
@settings(max_examples=25)
@given(seed=st.integers(0, 2**31 - 1))
def test_random_stacks_finite_bounded_and_prioritised(name, solver, seed):
    check_draw(MODELS[name], seed, solver)
