"""Activation ramps of a stack's tasks in one controller, and the period check of set-based rows."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.constraints import JointVelocityBounds
from uvms_qp.controller import Controller
from uvms_qp.errors import InputError
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import (
    EndEffectorTask,
    JointLimitTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
)


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


def _controller(rov, task, activation=None):
    stack = Stack(levels=[Level(EndEffectorTask(position=[0.5, 0.0, 0.0], name="tool")),
                          Level(task)], constraints=[JointVelocityBounds()])
    if activation is not None:
        stack.set_activation(task.name, activation)
    return stack, Controller(rov, stack, dt=0.05)


def test_activation_ramps_with_a_smoothstep(rov):
    stack, ctrl = _controller(rov, PostureTask(gain=1.0), activation=0.0)
    stack.set_activation("posture", 1.0, ramp=2.0)
    state = rov.state(rov.home())
    values = []
    for t in (5.0, 5.5, 6.0, 6.5, 7.0, 7.5):
        ctrl.assembler.fill(state, t)
        values.append(ctrl.slot("posture").activation)
    s = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.0])
    assert np.allclose(values, 3 * s**2 - 2 * s**3)  # starts at the first tick, no step
    assert stack.activation("posture") == 1.0


def test_a_partial_ramp_takes_its_fraction_of_the_ramp_time(rov):
    stack, ctrl = _controller(rov, PostureTask())  # default ramp 1 s
    state = rov.state(rov.home())
    stack.set_activation("posture", 0.5)
    ctrl.assembler.fill(state, 2.0)
    ctrl.assembler.fill(state, 2.25)
    assert ctrl.slot("posture").activation == pytest.approx(1.0 - 0.5 * 0.5)  # half of 0.5 s
    ctrl.assembler.fill(state, 2.5)
    assert ctrl.slot("posture").activation == 0.5


def test_a_step_with_zero_ramp_and_a_reset_to_the_request(rov):
    stack, ctrl = _controller(rov, PostureTask(), activation=0.3)
    assert ctrl.slot("posture").activation == 0.3  # a controller starts at the request
    stack.set_activation("posture", ramp=0.0)
    stack.set_activation("posture", 1.0)
    ctrl.assembler.fill(rov.state(rov.home()), 0.0)
    assert ctrl.slot("posture").activation == 1.0
    stack.set_activation("posture", 0.0, ramp=1.0)
    ctrl.reset()  # back to what the stack requests now, without a ramp
    assert ctrl.slot("posture").activation == 0.0
    ctrl.assembler.fill(rov.state(rov.home()), 1.0)
    assert ctrl.slot("posture").activation == 0.0


def test_entering_the_stack_takes_the_activation_pose_then(rov):
    """A station-keeping task ramped in from 0 holds the pose where its ramp started."""
    stack, ctrl = _controller(rov, StationKeepingTask(), activation=0.0)
    eta0, joints = rov.split(rov.home())
    ctrl.assembler.fill(rov.state(rov.home()), 0.0)  # evaluated while out of the stack
    assert np.allclose(ctrl.slot("station_keeping").held, np.asarray(eta0))
    moved = np.array(eta0, dtype=float)
    moved[:3] += [1.0, -2.0, 0.5]
    stack.set_activation("station_keeping", 1.0)
    ctrl.assembler.fill(rov.state(rov.configuration(moved, joints)), 3.0)
    assert np.allclose(ctrl.slot("station_keeping").held, moved)


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_activation_is_validated_and_belongs_to_the_stack(value):
    stack = Stack(levels=[Level(PostureTask())])
    with pytest.raises(InputError, match="activation"):
        stack.set_activation("posture", value)
    assert stack.activation("posture") == 1.0  # unchanged
    with pytest.raises(InputError, match=r"stack entry.*set_activation"):
        PostureTask().update(activation=0.5)
    with pytest.raises(InputError, match=r"unknown keyword 'activation'.*set_activation"):
        PostureTask(activation=0.5)


def test_an_activation_for_an_unknown_task_names_the_known_ones():
    stack = Stack(levels=[Level(PostureTask())])
    with pytest.raises(InputError, match="unknown task 'postur'; known tasks: posture"):
        stack.set_activation("postur", 0.0)


@pytest.mark.parametrize(("task", "row"), [
    (ManipulabilityTask(mode="floor", minimum=0.001, gain=25.0), "floor row"),
    (JointLimitTask(mode="margin", margin=0.1, gain=25.0), "margin rows"),
    (PayloadMomentTask(mode="bound", force=10.0, maximum=1.0, gain=25.0), "bound row"),
])
def test_set_based_rows_that_overshoot_are_refused(rov, task, row):
    task.bind(rov)
    task.check_period(0.04)  # gain * dt = 1: reaches the bound in one step, no overshoot
    with pytest.raises(InputError, match=rf"gain \* dt = 25 \* 0.05 = 1.25 > 1: the {row}"):
        task.check_period(0.05)


def test_the_period_check_leaves_other_kinds_of_rows_alone(rov):
    ManipulabilityTask(mode="ascend", gain=100.0).bind(rov).check_period(0.05)
    JointLimitTask(mode="gradient", gain=100.0).bind(rov).check_period(0.05)
