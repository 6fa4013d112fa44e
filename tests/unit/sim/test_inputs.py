"""Inputs that used to be accepted silently or reported unhelpfully.

- A trajectory given with 2 coordinates (x, y) must not be taken at z = 0 on a spatial model:
  its points must all have the same number of coordinates, and a task bound to a non-planar model
  rejects a 2-coordinate trajectory as it rejects a 2-coordinate ``position``.
- A misspelt required scenario key is named as the unknown key, not reported as missing.
- Messages say how to fix the input (the ``heading`` string, rotation axes in position mode, the
  path of an event's update).
"""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest

from tests.unit.sim.test_scenario_errors import BASE
from uvms_qp.errors import ConfigError, InputError, ShapeError
from uvms_qp.model import load_model
from uvms_qp.sim.config import Table
from uvms_qp.sim.scenario import scenario_from_dict
from uvms_qp.sim.trajectories import (
    CircleTrajectory,
    FixedTarget,
    LineTrajectory,
    QuinticTrajectory,
    WaypointTrajectory,
)
from uvms_qp.tasks.end_effector import EndEffectorTask

SPATIAL_MESSAGE = "got 2 coordinates, but the model is spatial; give 3 (x, y, z)"
SPATIAL = re.escape(SPATIAL_MESSAGE)


@pytest.fixture(scope="module")
def spatial():
    return load_model("bluerov2_heavy_alpha5")


@pytest.fixture(scope="module")
def planar():
    return load_model("soylu_planar")


def load_text(text: str):
    return scenario_from_dict(tomllib.loads(text))


def replaced(old: str, new: str) -> str:
    assert old in BASE, old
    return BASE.replace(old, new)


# ------------------------------------------------------------------------- mixed point sizes
@pytest.mark.parametrize("cls", [QuinticTrajectory, LineTrajectory])
def test_segment_rejects_start_and_goal_of_different_lengths(cls):
    with pytest.raises(InputError, match=r"^goal: got 3 coordinates but start has 2"):
        cls(start=[1, 2], goal=[1, 2, 3], duration=1)
    with pytest.raises(InputError, match=r"^goal: got 2 coordinates but start has 3"):
        cls(start=[1, 2, 3], goal=[1, 2], duration=1)


def test_waypoints_reject_points_of_different_lengths():
    with pytest.raises(InputError, match=r"^points\[2\]: got 3 coordinates but points\[0\] has 2"):
        WaypointTrajectory([[0, 0], [1, 1], [1, 1, 1]], [0, 1, 2])


def test_same_length_points_keep_their_dimension():
    assert QuinticTrajectory([1, 2], [1, 3], 1).dimension == 2
    assert QuinticTrajectory([1, 2, 3], [1, 3, 3], 1).dimension == 3
    assert WaypointTrajectory([[0, 0], [1, 1]], [0, 1]).dimension == 2
    assert CircleTrajectory([0, 0], 1.0, 2.0).dimension == 2
    assert CircleTrajectory([0, 0, -1], 1.0, 2.0).dimension == 3
    assert FixedTarget([0, 0]).dimension == 2
    # planar samples are still 3-vectors with z = 0, halfway along the segment at t = T/2
    sample = QuinticTrajectory([1, 2], [1, 4], 2.0).sample(1.0)
    np.testing.assert_allclose(sample.position, [1.0, 3.0, 0.0])


# ----------------------------------------------------------------------- binding to a model
@pytest.mark.parametrize(
    "trajectory",
    [
        QuinticTrajectory([0.5, 0.1], [0.5, 0.2], 1.0),
        LineTrajectory([0.5, 0.1], [0.5, 0.2], 1.0),
        CircleTrajectory([0.5, 0.1], 0.1, 1.0),
        WaypointTrajectory([[0.5, 0.1], [0.5, 0.2]], [0.0, 1.0]),
        FixedTarget([0.5, 0.1]),
    ],
    ids=["quintic", "line", "circle", "waypoints", "fixed"],
)
def test_a_planar_trajectory_is_rejected_on_a_spatial_model(spatial, planar, trajectory):
    task = EndEffectorTask(trajectory=trajectory, name="tool")
    with pytest.raises(ShapeError, match=r"^tool\.trajectory: " + SPATIAL):
        task.bind(spatial)
    # tracking it after binding is rejected too, and the previous target is kept
    bound = EndEffectorTask(position=[0.5, 0.1, 0.2], name="tool").bind(spatial)
    with pytest.raises(ShapeError, match=SPATIAL):
        bound.track(trajectory)
    np.testing.assert_allclose(bound.target(0.0)[0], [0.5, 0.1, 0.2])
    # a planar model accepts it
    EndEffectorTask(trajectory=trajectory, name="tool").bind(planar)


def test_same_message_as_a_two_coordinate_position(spatial):
    with pytest.raises(ShapeError) as position_error:
        EndEffectorTask(position=[0.5, 0.1], name="tool").bind(spatial)
    with pytest.raises(ShapeError) as trajectory_error:
        EndEffectorTask(trajectory=FixedTarget([0.5, 0.1]), name="tool").bind(spatial)
    assert str(position_error.value).split(": ", 1)[1] == str(trajectory_error.value).split(
        ": ", 1)[1]


class _FlatTrajectory:
    """A trajectory that does not follow the contract: 2-vector positions and no dimension."""

    duration = 1.0

    def sample(self, t):
        class S:
            position = np.array([0.5, 0.1])
            velocity = np.zeros(2)
            rotation = None
            angular_velocity = None

        return S()


def test_a_duck_typed_trajectory_is_sampled_at_bind(spatial, planar):
    with pytest.raises(ShapeError, match=SPATIAL):
        EndEffectorTask(trajectory=_FlatTrajectory(), name="tool").bind(spatial)
    with pytest.raises(ShapeError, match=r"sample\(t\)\.position has 2 coordinates; expected 3"):
        EndEffectorTask(trajectory=_FlatTrajectory(), name="tool").bind(planar)


@pytest.mark.parametrize(
    ("start", "goal", "path"),
    [
        ("[0.4911, 0.0990]", "[0.45, 0.15, -0.14]", "trajectories.path.goal"),
        ("[0.4911, 0.0990]", "[0.45, 0.15]", "levels[0].tasks[0].trajectory"),
    ],
)
def test_scenario_with_a_two_coordinate_trajectory_is_rejected(start, goal, path):
    text = replaced("start = [0.49, 0.10, -0.17]\ngoal = [0.45, 0.15, -0.14]",
                    f"start = {start}\ngoal = {goal}")
    with pytest.raises(ConfigError) as info:
        load_text(text)
    assert info.value.path == path, str(info.value)
    assert str(info.value).startswith(path + ": ")


# ------------------------------------------------------------ unknown keys before missing ones
@pytest.mark.parametrize(
    ("old", "new", "path", "fragment"),
    [
        ("duration = 1.0\n\n[initial]", "durration = 1.0\n\n[initial]", "durration",
         "unknown key 'durration' (did you mean 'duration'?); known keys: constraints,"),
        ("duration = 1.0\n\n[initial]", "length = 1.0\n\n[initial]", "length",
         "unknown key 'length'; known keys:"),
        ('model = "bluerov2_heavy_alpha5"', 'modle = "bluerov2_heavy_alpha5"', "modle",
         "unknown key 'modle' (did you mean 'model'?)"),
        ("time = 0.5", "tiem = 0.5", "events[0].tiem",
         "unknown key 'tiem' (did you mean 'time'?); known keys: task, time, update"),
        ("direction = 0.2", "directon = 0.2", "current.directon",
         "unknown key 'directon' (did you mean 'direction'?)"),
        ('type = "end_effector"', 'tpye = "end_effector"', "levels[0].tasks[0].tpye",
         "unknown key 'tpye' (did you mean 'type'?)"),
        ("goal = [0.45, 0.15, -0.14]", "gaol = [0.45, 0.15, -0.14]", "trajectories.path.gaol",
         "unknown key 'gaol' for trajectory type 'quintic'"),
    ],
)
def test_a_misspelt_required_key_is_named_as_unknown(old, new, path, fragment):
    with pytest.raises(ConfigError) as info:
        load_text(replaced(old, new))
    assert info.value.path == path, str(info.value)
    assert fragment in str(info.value)


def test_a_truly_missing_key_is_still_reported_as_missing():
    with pytest.raises(ConfigError, match=r"^duration: missing required field 'duration'"):
        load_text(replaced("duration = 1.0\n\n[initial]", "\n[initial]"))
    # an unrelated unread key of an undeclared table is not mistaken for the missing one
    table = Table({"colour": 1}, "thing")
    with pytest.raises(ConfigError, match=r"^thing: missing required field 'size'"):
        table.take_number("size", required=True)
    declared = Table({"colour": 1}, "thing", keys=("size",))
    with pytest.raises(ConfigError, match=r"^thing\.colour: unknown key 'colour'; known keys: s"):
        declared.take_number("size", required=True)


# ------------------------------------------------------------------------- helpful messages
def test_heading_string_other_than_current_says_what_is_allowed():
    with pytest.raises(ConfigError) as info:
        load_text(replaced('heading = "current"', 'heading = "curent"'))
    assert info.value.path == "levels[1].tasks[2].heading"
    assert "expected a number [rad] or the string 'current'" in str(info.value)
    assert "got 'curent'" in str(info.value)


@pytest.mark.parametrize(
    ("mode", "axes", "needs"),
    [
        ("position", ["x", "rz"], "'rz' needs mode = \"orientation\" or \"pose\""),
        ("orientation", ["rz", "x"], "'x' needs mode = \"position\" or \"pose\""),
    ],
)
def test_axes_of_another_mode_name_the_mode_they_need(mode, axes, needs):
    with pytest.raises(InputError) as info:
        EndEffectorTask(mode=mode, axes=axes, name="tool")
    assert str(info.value).startswith("tool.axes: ")
    assert needs in str(info.value)
    EndEffectorTask(mode="pose", axes=axes, name="tool")  # both kinds are pose axes


def test_axes_typo_is_still_an_unknown_axis():
    with pytest.raises(InputError, match=r"unknown axis 'q'; known axes: x, y, z"):
        EndEffectorTask(axes=["x", "q"])


EVENT = '\n\n[[events]]\ntime = 0.5\ntask = "tool"\nupdate = {{ {} }}'


@pytest.mark.parametrize(
    ("update", "path"),
    [
        ("position = [0.5, 0.1]", "events[1].update.position"),
        ("trajectory = { type = 'line', start = [0.5, 0.1], goal = [0.5, 0.2], duration = 1.0 }",
         "events[1].update.trajectory"),
    ],
)
def test_event_update_needing_the_model_carries_the_event_path(update, path):
    text = replaced("update = { force = 10.0 }",
                    "update = { force = 10.0 }" + EVENT.format(update))
    with pytest.raises(ConfigError) as info:
        load_text(text)
    assert info.value.path == path, str(info.value)
    assert str(info.value).startswith(f"{path}: {SPATIAL_MESSAGE}")


def test_event_update_with_three_coordinates_loads():
    text = replaced("update = { force = 10.0 }",
                    "update = { force = 10.0 }" + EVENT.format("position = [0.5, 0.1, 0.2]"))
    scenario = load_text(text)
    assert scenario.events[1].update == {"position": [0.5, 0.1, 0.2]}
