"""Ready-made stacks of :mod:`uvms_qp.bench.stacks` (demo, tool + posture, random)."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.bench.stacks import demo_stack, random_bounds, random_stack, tool_posture_stack
from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.controller import Controller
from uvms_qp.model import load_model
from uvms_qp.tasks import EndEffectorTask


def test_demo_stack_levels_and_bounds_hold_on_the_bluerov(rov):
    q = rov.home()
    target = rov.frame_pose(q, "tool")[:3, 3] + [0.05, 0.0, 0.0]
    stack = demo_stack(position=list(target))
    assert [[t.type_name for t in level.tasks] for level in stack.levels] == [
        ["end_effector"], ["manipulability", "joint_limit"],
        ["payload_moment", "station_keeping", "current_alignment"],
        ["vehicle_motion", "posture"]]
    assert [type(c) for c in stack.constraints] == [JointPositionBounds, JointVelocityBounds,
                                                    VehicleRateBounds]
    result = Controller(rov, stack, dt=0.05).step(rov.state(q), 0.0)
    assert result.ok and result.bound_violation <= 1e-9
    # vehicle rates within 0.5 m/s and 0.3 rad/s
    assert np.all(np.abs(result.zeta[:3]) <= 0.5 + 1e-9)
    assert np.all(np.abs(result.zeta[3:6]) <= 0.3 + 1e-9)
    assert demo_stack(position=list(target)).levels[0].tasks[0] is not stack.levels[0].tasks[0]


def test_tool_posture_stack_is_one_weighted_level():
    stack = tool_posture_stack(EndEffectorTask(position=[0.5, 0.0, 0.0]), posture_weight=1e-2)
    (level,) = stack.levels
    tool, posture = level.tasks
    assert tool.type_name == "end_effector" and posture.type_name == "posture"
    assert posture.weight == pytest.approx(1e-2)
    assert len(stack.constraints) == 3
    assert tool_posture_stack(EndEffectorTask(position=[0.5, 0.0, 0.0]),
                              constraints=[]).constraints == ()


@pytest.mark.parametrize("name", ["bluerov2_heavy_alpha5", "soylu_planar"])
def test_random_stack_is_seeded_and_keeps_the_tool_first(name):
    model = load_model(name)

    def draw(seed):
        rng = np.random.default_rng(seed)
        state = model.state(model.random_configuration(rng))
        return random_stack(model, state, rng, random_bounds(model, rng))

    for seed in range(5):
        a, b = draw(seed), draw(seed)
        shape = [[(t.type_name, getattr(t, "mode", None)) for t in lv.tasks] for lv in a.levels]
        assert shape == [[(t.type_name, getattr(t, "mode", None)) for t in lv.tasks]
                         for lv in b.levels]
        assert 2 <= len(a.levels) <= 6
        assert a.levels[0].tasks[0].type_name == "end_effector"
        assert all(level.tasks for level in a.levels)
