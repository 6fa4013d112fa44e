"""Task activation ramps and the period check of set-based rows."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.errors import InputError
from uvms_qp.model import load_model
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


def _fill(task, state, t):
    A = np.empty((task.dim, task.model.nv))
    task.fill(state, t, A, np.empty((2, task.dim)))


def test_activation_ramps_with_a_smoothstep(rov):
    task = PostureTask(gain=1.0, activation=0.0).bind(rov)
    task.update(activation=1.0, ramp=2.0)
    state = rov.state(rov.home())
    values = []
    for t in (5.0, 5.5, 6.0, 6.5, 7.0, 7.5):
        _fill(task, state, t)
        values.append(task.activation)
    s = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.0])
    assert np.allclose(values, 3 * s**2 - 2 * s**3)  # starts at the first tick, no step
    assert task.advance_activation(100.0) == 1.0


def test_a_partial_ramp_takes_its_fraction_of_the_ramp_time(rov):
    task = PostureTask(activation=1.0).bind(rov)  # default ramp 1 s
    state = rov.state(rov.home())
    task.update(activation=0.5)
    _fill(task, state, 2.0)
    _fill(task, state, 2.25)
    assert task.activation == pytest.approx(1.0 - 0.5 * 0.5)  # half way through 0.5 s
    _fill(task, state, 2.5)
    assert task.activation == 0.5


def test_a_step_with_zero_ramp_and_reset(rov):
    task = EndEffectorTask(position=[1.0, 0.0, 0.0], activation=0.3).bind(rov)
    task.update(ramp=0.0, activation=1.0)  # order of the keys does not matter
    _fill(task, rov.state(rov.home()), 0.0)
    assert task.activation == 1.0
    task.reset()
    assert task.activation == 0.3


def test_entering_the_stack_takes_the_activation_pose_then(rov):
    """A station-keeping task ramped in from 0 holds the pose where its ramp started."""
    task = StationKeepingTask(activation=0.0).bind(rov)
    eta0, joints = rov.split(rov.home())
    _fill(task, rov.state(rov.home()), 0.0)  # evaluated while out of the stack
    assert np.allclose(task.held_pose, np.asarray(eta0))
    moved = np.array(eta0, dtype=float)
    moved[:3] += [1.0, -2.0, 0.5]
    task.update(activation=1.0)
    _fill(task, rov.state(rov.configuration(moved, joints)), 3.0)
    assert np.allclose(task.held_pose, moved)


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_activation_is_validated(value):
    with pytest.raises(InputError, match="activation"):
        PostureTask(activation=value)
    with pytest.raises(InputError, match="activation"):
        PostureTask().update(activation=value)


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


def test_the_period_check_leaves_other_modes_alone(rov):
    ManipulabilityTask(mode="ascend", gain=100.0).bind(rov).check_period(0.05)
    JointLimitTask(mode="gradient", gain=100.0).bind(rov).check_period(0.05)

