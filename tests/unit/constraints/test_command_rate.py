"""Command-rate (acceleration) bounds: defaults from the model, the window around the previous
command, position safety first, the first step, and building them from a scenario file."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from tests.support.scenario_text import bluerov_scenario
from uvms_qp.constraints import (
    CommandRateBounds,
    JointPositionBounds,
    JointVelocityBounds,
    VehicleRateBounds,
    intersect_boxes,
)
from uvms_qp.errors import InputError, ShapeError
from uvms_qp.model import load_model
from uvms_qp.sim.scenario import scenario_from_dict

DT = 0.05


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


def _box(rov, constraints, state=None):
    lower, upper = np.full(rov.nv, -np.inf), np.full(rov.nv, np.inf)
    intersect_boxes(constraints, state or rov.state(rov.home()), DT, lower, upper)
    return lower, upper


def test_defaults_are_the_model_rate_limits_over_the_ramp(rov):
    c = CommandRateBounds().bind(rov)
    # the Reach Alpha 5's 0.5 rad/s and the BlueROV2 Heavy's 1.5 m/s surge, reached in 0.5 s;
    # the vehicle rates without a published figure stay free
    expected = np.array([3.0, np.inf, np.inf, np.inf, np.inf, np.inf, 1.0, 1.0, 1.0, 1.0])
    assert np.array_equal(c.limits, expected)
    slow = CommandRateBounds(ramp=2.0).bind(rov)
    assert np.allclose(slow.limits[6:], 0.25) and slow.limits[0] == pytest.approx(0.75)


def test_explicit_bounds_take_precedence(rov):
    c = CommandRateBounds(linear=2.0, angular=4.0, joint=[1, 2, 3, 4]).bind(rov)
    assert np.array_equal(c.limits, [2, 2, 2, 4, 4, 4, 1, 2, 3, 4])
    every = list(np.arange(1.0, 11.0))
    assert np.array_equal(CommandRateBounds(limits=every, joint=9.0).bind(rov).limits, every)


def test_first_step_from_rest_bounds_the_command_around_zero(rov):
    c = CommandRateBounds(linear=2.0, angular=4.0, joint=1.0).bind(rov)
    lower, upper = _box(rov, [c])
    step = np.array([2, 2, 2, 4, 4, 4, 1, 1, 1, 1]) * DT
    assert np.allclose(upper, step) and np.allclose(lower, -step)


def test_free_first_step_then_the_window_follows_the_command_sent(rov):
    c = CommandRateBounds(joint=1.0, linear=2.0, angular=2.0, initial="free").bind(rov)
    lower, upper = _box(rov, [c])
    assert np.all(np.isinf(lower)) and np.all(np.isinf(upper))
    sent = np.linspace(-0.3, 0.3, rov.nv)
    c.command_sent(sent)
    sent[:] = 99.0  # the constraint keeps its own copy
    lower, upper = _box(rov, [c])
    centre = np.linspace(-0.3, 0.3, rov.nv)
    half = np.array([2.0] * 6 + [1.0] * 4) * DT
    assert np.allclose(lower, centre - half) and np.allclose(upper, centre + half)
    c.reset()
    assert c.previous is None


def test_given_initial_command_and_reset(rov):
    start = [0.1] * 6 + [0.2] * 4
    c = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0, initial=start).bind(rov)
    c.command_sent(np.zeros(rov.nv))
    c.reset()
    assert np.allclose(c.previous, start)
    with pytest.raises(InputError, match="initial: expected 10 values"):
        CommandRateBounds(initial=[0.0, 0.0]).bind(rov)


def test_window_inside_the_box_is_the_intersection(rov):
    c = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0).bind(rov)
    c.command_sent(np.array([0.2] * 6 + [0.3] * 4))
    others = [JointVelocityBounds().bind(rov), VehicleRateBounds(linear=0.5, angular=0.3).bind(rov)]
    lower, upper = _box(rov, [others[0], c, others[1]])
    assert np.allclose(lower, [0.15] * 6 + [0.25] * 4)
    assert np.allclose(upper, [0.25] * 6 + [0.35] * 4)


def test_position_safety_wins_when_the_window_misses_the_box(rov):
    """A command at 0.5 rad/s whose rate bound drops to 0.2 rad/s: the box holds, the
    acceleration bound gives (the command goes to the box's nearest point)."""
    c = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0).bind(rov)
    c.command_sent(np.array([0.0] * 6 + [0.5, -0.5, 0.0, 0.0]))
    # listed first, the window still yields to the rate bound
    lower, upper = _box(rov, [c, JointVelocityBounds(scale=0.4).bind(rov)])
    assert lower[6] == upper[6] == pytest.approx(0.2)
    assert lower[7] == upper[7] == pytest.approx(-0.2)
    assert lower[8] == pytest.approx(-0.05) and upper[8] == pytest.approx(0.05)


def test_position_safety_near_a_joint_limit(rov):
    """Joint axis_c 0.01 rad below its upper limit while it moves at 0.5 rad/s toward it: the
    joint position bound (at most 0.2 rad/s this step) wins over the acceleration bound."""
    eta, arm = rov.split(rov.home())
    arm = np.array(arm)
    arm[2] = rov.joint_upper[2] - 0.01
    state = rov.state(rov.configuration(eta, arm))
    c = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0).bind(rov)
    c.command_sent(np.array([0.0] * 6 + [0.0, 0.0, 0.5, 0.0]))
    others = [JointPositionBounds().bind(rov), JointVelocityBounds().bind(rov)]
    lower, upper = _box(rov, [*others, c], state)
    assert upper[8] == pytest.approx(0.01 / DT) and lower[8] == upper[8]
    assert arm[2] + DT * upper[8] <= rov.joint_upper[2] + 1e-12


def test_an_empty_box_stays_empty(rov):
    c = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0).bind(rov)
    lower, upper = np.zeros(rov.nv), np.zeros(rov.nv)
    lower[6], upper[6] = 1.0, -1.0
    intersect_boxes([c], rov.state(rov.home()), DT, lower, upper)
    assert lower[6] > upper[6]


def test_update_changes_the_bounds(rov):
    c = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0).bind(rov)
    c.update(joint=np.inf, linear=5.0)
    assert np.array_equal(c.limits, [5, 5, 5, 1, 1, 1] + [np.inf] * 4)
    _, upper = _box(rov, [c])
    assert np.all(np.isinf(upper[6:])) and upper[0] == pytest.approx(5.0 * DT)
    with pytest.raises(InputError, match="unknown parameter 'ramp'"):
        c.update(ramp=1.0)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"joint": 0.0}, "joint: expected positive"),
    ({"linear": -1.0}, "linear: expected positive"),
    ({"ramp": 0.0}, "ramp"),
    ({"initial": "stopped"}, "initial: expected 'rest', 'free' or a command"),
])
def test_validation(kwargs, match):
    with pytest.raises(InputError, match=match):
        CommandRateBounds(**kwargs)


def test_sizes_are_checked_at_bind(rov):
    with pytest.raises(InputError, match="joint: expected one value or 4"):
        CommandRateBounds(joint=[1.0, 2.0]).bind(rov)
    with pytest.raises((InputError, ShapeError), match="limits: expected 10 values"):
        CommandRateBounds(limits=[1.0, 2.0]).bind(rov)


def test_scenario_file_builds_the_constraint():
    text = bluerov_scenario('duration = 0.5', """
[[constraints]]
type = "command_rate_bounds"
joint = 2.0
angular = 1.0
initial = "free"
""")
    scenario = scenario_from_dict(tomllib.loads(text), name="accel")
    stack = scenario.build_stack()
    (c,) = [c for c in stack.constraints if isinstance(c, CommandRateBounds)]
    assert c.previous is None
    assert np.allclose(c.limits[6:], 2.0) and np.allclose(c.limits[3:6], 1.0)
    assert c.limits[0] == pytest.approx(1.5 / 0.5)  # surge from the model, the default ramp
