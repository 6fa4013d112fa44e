"""Closed loop: the command is a signal a vehicle and an arm can follow.

The README's stack and two arms with a goal just beyond their reach (a DH-built and a URDF arm,
whose elbows end at the stretched-arm singularity) are run in closed loop with the library's
default options; without damping the first bangs its pitch rate and two joints between their
bounds every tick, the others their elbow and shoulder.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import uvms_qp
from uvms_qp import Controller, Level, Model, Stack
from uvms_qp.constraints import (
    JointPositionBounds,
    JointVelocityBounds,
    VehicleRateBounds,
)
from uvms_qp.controller.history import command_reversals
from uvms_qp.model import DHRow, Vehicle
from uvms_qp.tasks import EndEffectorTask, ManipulabilityTask, StationKeepingTask

DT = 0.05
URDF = "tests/data/three_joint_arm.urdf"


def _run(model, stack, q, steps, **options):
    controller = Controller(model, stack, solver="daqp", dt=DT, **options)
    commands, results = [], []
    for k in range(steps):
        result = controller.step(model.state(q), t=k * DT)
        commands.append(result.zeta.copy())
        results.append(result)
        q = model.integrate(q, result.zeta, DT)
    return np.array(commands), results, q


def _readme_stack(goal, station=None):
    """The README's stack as it stood before the command became a signal (unchanged)."""
    return Stack(
        constraints=[JointPositionBounds(), JointVelocityBounds(),
                     VehicleRateBounds(linear=0.5, angular=0.3)],
        levels=[
            Level(EndEffectorTask("tool", position=goal, gain=2.0)),
            Level(ManipulabilityTask(mode="floor", minimum=0.001)),
            Level(station or StationKeepingTask(gain=1.0)),
        ],
    )


@pytest.fixture(scope="module")
def readme_run():
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    q = model.home()
    goal = model.frame_pose(q, "tool")[:3, 3] + [0.3, 0.1, 0.0]
    commands, results, q = _run(model, _readme_stack(goal), q, 200)
    return model, goal, commands, results, q


def test_the_readme_stack_settles_without_chatter(readme_run):
    model, goal, commands, _, q = readme_run
    bounds = np.array([0.5] * 3 + [0.3] * 3 + [0.5] * 4)
    reversals = command_reversals(commands[50:], bounds)
    assert reversals.max() <= 10, dict(zip(model.zeta_names, reversals.tolist(), strict=True))
    state = model.state(q)
    assert np.linalg.norm(state.position("tool") - goal) < 1e-3
    roll, pitch = state.eta[3:5]
    assert abs(roll) < 0.05 and abs(pitch) < 0.05
    # once settled, the command changes by a small fraction of the bang-bang figure 2 bound / dt
    change = np.abs(np.diff(commands[20:], axis=0)) / DT
    assert np.all(change.max(axis=0) < 0.1 * 2 * bounds / DT)


def test_a_station_keeping_level_in_conflict_with_the_tool_does_not_chatter():
    """The README's stack holding only x, y, z and yaw: the station-keeping level, unmet and
    nearly singular in the freedom the tool level leaves, is damped instead of banging the
    vehicle's angular rates and two joints between their bounds."""
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    q = model.home()
    goal = model.frame_pose(q, "tool")[:3, 3] + [0.3, 0.1, 0.0]
    station = StationKeepingTask(axes=["x", "y", "z", "psi"], gain=1.0)
    commands, results, q = _run(model, _readme_stack(goal, station), q, 200)
    bounds = np.array([0.5] * 3 + [0.3] * 3 + [0.5] * 4)
    assert command_reversals(commands[50:], bounds).max() <= 10
    assert np.linalg.norm(model.state(q).position("tool") - goal) < 1e-3
    assert any(r.damped_levels for r in results[50:])


def test_the_step_result_reports_the_controllers_reversals(readme_run):
    results = readme_run[3]
    last = results[-1]
    assert last.reversals_per_s == pytest.approx(0.0)
    assert "reversals" in last.summary()


def _dh_arm():
    return Model.from_dh(
        [DHRow(a=0.0, alpha=math.pi / 2, d=0.1, lower=-2.0, upper=2.0, rate_limit=1.0),
         DHRow(a=0.3, lower=-1.5, upper=1.5, rate_limit=1.0),
         DHRow(a=0.25, lower=-2.0, upper=2.0, rate_limit=1.0)],
        vehicle=Vehicle("fixed"), mount={"xyz": [0.3, 0.0, 0.2]}, tool={"xyz": [0.05, 0.0, 0.0]},
        home=[0.3, 0.6, -1.0], name="dh_arm")


def _urdf_arm():
    return Model.from_urdf(URDF, tool="gripper", vehicle=Vehicle("fixed"),
                           mount={"xyz": [0.3, 0.0, 0.2]}, home=[0.3, 0.6, 1.2], name="urdf_arm")


def _beyond_reach(model, shoulder, factor=1.02):
    """A goal 2 % beyond the arm's reach from its shoulder, off the arm's current direction."""
    state = model.state(model.home())
    stretched = np.array(state.joints)
    stretched[-1] = 0.0
    extended = model.state(model.configuration(state.eta, stretched))
    reach = np.linalg.norm(extended.position("tool") - extended.position(shoulder))
    direction = np.array([1.0, 0.3, -0.4]) / np.linalg.norm([1.0, 0.3, -0.4])
    return state.position(shoulder) + factor * reach * direction, reach


@pytest.mark.parametrize(("make", "shoulder"), [(_dh_arm, "link1"), (_urdf_arm, "upper_arm")])
def test_an_arm_at_its_singularity_does_not_bang_between_its_bounds(make, shoulder):
    model = make()
    goal, reach = _beyond_reach(model, shoulder)
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds()],
                  levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0))])
    commands, _, q = _run(model, stack, model.home(), 200)
    rates = np.asarray(model.joint_rate_limit)
    assert np.all(np.abs(commands) <= rates + 1e-9)
    late = commands[round(1.0 / DT):]
    per_second = command_reversals(late, rates) / (late.shape[0] * DT)
    assert per_second.max() <= 0.5
    # the largest change per step [rad/s^2]: never a jump across the box (the bang-bang figure
    # 2 bound / dt), and once the arm has stretched (last 5 s) a small fraction of it
    bang = 2 * rates / DT
    change = np.abs(np.diff(late, axis=0)) / DT
    assert np.all(change.max(axis=0) < 0.25 * bang)
    assert np.all(change[-100:].max(axis=0) < 0.01 * bang)
    state = model.state(q)  # the arm ends stretched toward the goal, as close as it can be
    assert np.linalg.norm(state.position("tool") - goal) == pytest.approx(0.02 * reach, rel=0.02)
