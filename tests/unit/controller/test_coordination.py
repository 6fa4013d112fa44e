"""Arm-vehicle coordination: the joints re-solved with the vehicle at its measured velocity.

Checked against an independent solve of the same levels (``solve_hierarchy`` on the controller's
rows, the vehicle's box entries fixed at the measured rates), not against the controller itself.
"""

from __future__ import annotations

import numpy as np
import pytest

import uvms_qp
from uvms_qp import Controller, Level, Stack
from uvms_qp.constraints import JointVelocityBounds, VehicleRateBounds
from uvms_qp.errors import InputError, ShapeError
from uvms_qp.tasks import EndEffectorTask, StationKeepingTask

MODEL = uvms_qp.load_model("bluerov2_heavy_alpha5")
METRIC = [10.0] * 6 + [1.0] * 4


def stack() -> Stack:
    q = MODEL.home()
    goal = MODEL.frame_pose(q, "tool")[:3, 3] + [0.05, 0.03, -0.02]
    return Stack(
        constraints=[JointVelocityBounds(), VehicleRateBounds(linear=0.3, angular=0.3)],
        levels=[Level(EndEffectorTask("tool", position=goal, gain=1.0)),
                Level(StationKeepingTask(gain=0.5))])


def controllers(**kwargs):
    plain = Controller(MODEL, stack(), metric=METRIC, deadline=None, **kwargs)
    coordinated = Controller(MODEL, stack(), metric=METRIC, deadline=None, coordination=True,
                             **kwargs)
    return plain, coordinated


MEASURED = np.array([0.05, -0.02, 0.01, 0.02, -0.01, 0.03])  # [m/s, rad/s], body FRD


def test_the_joints_answer_the_stack_with_the_vehicle_fixed_at_its_measured_rates():
    plain, coordinated = controllers()
    q = MODEL.home()
    reference = plain.step(MODEL.state(q), 0.0)
    result = coordinated.step(MODEL.state(q, MEASURED), 0.0)
    assert result.status == "coordinated"
    # the vehicle keeps the whole stack's answer
    np.testing.assert_allclose(result.zeta[:6], reference.zeta[:6], atol=1e-9)
    # the joints: the same levels and box, the vehicle's entries fixed, solved apart
    rows = plain.level_rows(MODEL.state(q), 0.0)
    lower, upper = plain.bounds(MODEL.state(q))
    lower[:6] = upper[:6] = MEASURED
    levels = [[(r.A, r.lower, r.upper)] for r in rows]
    independent = uvms_qp.solve_hierarchy(levels, lower, upper, weights=METRIC)
    np.testing.assert_allclose(result.zeta[6:], independent.x[6:], atol=1e-7)
    # and they differ from the plain answer: the arm makes up for the vehicle's motion
    assert np.abs(result.zeta[6:] - reference.zeta[6:]).max() > 1e-3


def test_the_coordinated_tool_velocity_is_the_one_the_plain_command_asked_for():
    # the top level is met in both problems, so the tool moves as the task asks with the vehicle
    # at its measured rates: J [nu_measured; qd_coordinated] = J zeta_plain
    plain, coordinated = controllers()
    state = MODEL.state(MODEL.home(), MEASURED)
    zeta_plain = plain.step(MODEL.state(MODEL.home()), 0.0).zeta
    zeta = coordinated.step(state, 0.0).zeta
    J = state.jacobian("tool", "position")
    realised = J @ np.concatenate([MEASURED, zeta[6:]])
    np.testing.assert_allclose(realised, J @ zeta_plain, atol=1e-8)


def test_a_state_without_a_velocity_is_solved_as_usual():
    plain, coordinated = controllers()
    q = MODEL.home()
    a = plain.step(MODEL.state(q), 0.0)
    b = coordinated.step(MODEL.state(q), 0.0)
    np.testing.assert_array_equal(a.zeta, b.zeta)
    assert b.status != "coordinated"


def test_a_measured_velocity_outside_the_rate_box_still_gives_joints_within_theirs():
    _, coordinated = controllers()
    fast = np.array([0.9, 0.0, 0.0, 0.0, 0.0, 0.8])  # beyond the 0.3 m/s and 0.3 rad/s box
    result = coordinated.step(MODEL.state(MODEL.home(), fast), 0.0)
    lower, upper = coordinated.bounds(MODEL.state(MODEL.home()))
    assert np.all(result.zeta >= lower - 1e-9) and np.all(result.zeta <= upper + 1e-9)


def test_bad_coordination_settings_and_velocities_are_refused():
    with pytest.raises(InputError, match="coordination"):
        Controller(MODEL, stack(), coordination="yes")
    with pytest.raises(InputError, match="nullspace"):
        Controller(MODEL, Stack(levels=[Level(StationKeepingTask())]), scheme="nullspace",
                   coordination=True)
    with pytest.raises(ShapeError, match="velocity"):
        MODEL.state(MODEL.home(), [0.0, 0.1])
    planar = uvms_qp.load_model("soylu_planar")
    with pytest.raises(InputError, match="spatial"):
        planar.state(planar.home(), np.zeros(6))
