"""A stack is a description: controllers built on one stack keep their own run-time memory."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.constraints import (
    CommandRateBounds,
    JointPositionBounds,
    JointVelocityBounds,
    VehicleRateBounds,
)
from uvms_qp.controller import Controller
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import (
    EndEffectorTask,
    ManipulabilityTask,
    PostureTask,
    StationKeepingTask,
)

DT = 0.05
# The controllers run without a wall-clock deadline: the tests compare runs bit for bit, and a
# deadline met on a loaded machine (stages skipped) would make the runs differ by the load.
JOINT_ACCELERATION = 1.0  # [rad/s^2]


def _stack(model):
    """Every kind of run-time memory: a command-rate window, held poses (tool and vehicle), a
    shaping task's rate estimate read by a blended task, a task ramped in mid-run."""
    goal = model.frame_pose(model.home(), "tool")[:3, 3] + [0.3, 0.1, 0.0]
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds(),
                               VehicleRateBounds(linear=0.5, angular=0.3),
                               CommandRateBounds(joint=JOINT_ACCELERATION)],
                  levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0)),
                          Level(EndEffectorTask("tool", mode="orientation", hold="activation",
                                                name="tool_attitude", gain=1.0)),
                          Level(StationKeepingTask(gain=1.0, blend="dexterity"),
                                ManipulabilityTask(mode="shaping", threshold=0.002, gain=1.0,
                                                   name="dexterity")),
                          Level(PostureTask(gain=0.5))])
    stack.set_activation("posture", 0.0)
    return stack


def _run(model, controllers, stacks, steps=40):
    """Step the controllers in turn, each from home on its own state; the commands of each."""
    q = {name: model.home() for name in controllers}
    commands: dict[str, list[np.ndarray]] = {name: [] for name in controllers}
    for k in range(steps):
        if k == 10:
            for stack in stacks:
                stack.set_activation("posture", 1.0, ramp=0.5)
        for name, ctrl in controllers.items():
            zeta = ctrl.step(model.state(q[name]), k * DT).zeta
            commands[name].append(zeta)
            q[name] = model.integrate(q[name], zeta, DT)
    return {name: np.array(c) for name, c in commands.items()}


@pytest.mark.parametrize("other", ["daqp", "cascade:quadprog"])
def test_two_controllers_on_one_stack_answer_as_on_two_stacks(rov, other):
    shared = _stack(rov)
    on_one = {"daqp": Controller(rov, shared, deadline=None),
              other + "'": Controller(rov, shared, solver=other, deadline=None)}
    apart = _stack(rov), _stack(rov)
    on_two = {"daqp": Controller(rov, apart[0], deadline=None),
              other + "'": Controller(rov, apart[1], solver=other, deadline=None)}
    one = _run(rov, on_one, [shared])
    two = _run(rov, on_two, apart)
    for name in one:
        np.testing.assert_array_equal(one[name], two[name])
    change = np.abs(np.diff(one["daqp"], axis=0, prepend=0.0))[:, rov.n_vehicle:] / DT
    assert change.max() <= JOINT_ACCELERATION * (1.0 + 1e-6)  # each its own command window
    assert change.max() > 0.5 * JOINT_ACCELERATION  # the bound was reached, not idle


def test_a_controller_built_later_leaves_the_first_ones_memory_alone(rov):
    """A second controller on the stack, stepped from elsewhere, changes nothing of the first:
    its held poses, its command window, its ramps."""
    stack = _stack(rov)
    alone = Controller(rov, _stack(rov), deadline=None)
    first = Controller(rov, stack, deadline=None)
    q = q_alone = rov.home()
    for k in range(5):
        zeta = first.step(rov.state(q), k * DT).zeta
        np.testing.assert_array_equal(zeta, alone.step(rov.state(q_alone), k * DT).zeta)
        q = q_alone = rov.integrate(q, zeta, DT)
    second = Controller(rov, stack, solver="cascade:quadprog", deadline=None)
    elsewhere = rov.random_configuration(np.random.default_rng(3))
    second.step(rov.state(elsewhere), 0.0)
    second.reset()
    for k in range(5, 10):
        zeta = first.step(rov.state(q), k * DT).zeta
        np.testing.assert_array_equal(zeta, alone.step(rov.state(q_alone), k * DT).zeta)
        q = q_alone = rov.integrate(q, zeta, DT)
    assert first.slot("tool_attitude").held is not second.slot("tool_attitude").held


def test_a_task_update_reaches_every_controller_on_the_stack(rov):
    stack = _stack(rov)
    controllers = (Controller(rov, stack, deadline=None),
                   Controller(rov, stack, solver="cascade:quadprog", deadline=None))
    state = rov.state(rov.home())
    stack.task("tool").set_target(position=[0.2, 0.0, 0.3])
    for ctrl in controllers:
        ctrl.step(state, 0.0)
        np.testing.assert_allclose(ctrl.slot("tool").last_error,
                                   [0.2, 0.0, 0.3] - state.position("tool"))


def test_a_copy_is_independent_and_answers_the_same(rov):
    stack = _stack(rov)
    twin = stack.copy()
    assert twin.model is stack.model
    assert not set(map(id, twin.tasks)) & set(map(id, stack.tasks))
    assert not set(map(id, twin.constraints)) & set(map(id, stack.constraints))
    twin.task("tool").update(gain=1.0)
    twin.set_activation("posture", 1.0)
    assert stack.task("tool").gain == 2.0 and stack.activation("posture") == 0.0
    state = rov.state(rov.home())
    ours, theirs = (Controller(rov, stack, deadline=None),
                    Controller(rov, stack.copy(), deadline=None))
    np.testing.assert_array_equal(ours.step(state, 0.0).zeta, theirs.step(state, 0.0).zeta)
