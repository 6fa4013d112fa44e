"""A trajectory that starts away from the frame it moves is reported when the scenario loads."""

from __future__ import annotations

import tomllib
import warnings

import numpy as np
import pinocchio as pin
import pytest

from uvms_qp import ScenarioWarning, Stack, load_model
from uvms_qp.sim.scenario import Scenario, bundled_scenarios, load_scenario, scenario_from_dict
from uvms_qp.sim.trajectories import LineTrajectory
from uvms_qp.sim.trajectory_start import FAR_ANGLE, FAR_POSITION
from uvms_qp.tasks import EndEffectorTask

MODEL = "bluerov2_heavy_alpha5"


def _tool_at_home(model_name=MODEL):
    model = load_model(model_name)
    return model.frame_pose(model.home(), "tool")


def _scenario(start, task="", model=MODEL):
    """No [initial]: the run starts at the model's home."""
    start = ", ".join(repr(float(v)) for v in start)
    return tomllib.loads(f"""
model = "{model}"
dt = 0.1
duration = 1.0

[trajectories.reach]
type = "line"
start = [{start}]
goal = [0.3, 0.3, 0.3]
duration = 1.0

[[levels]]
[[levels.tasks]]
type = "end_effector"
trajectory = "reach"
{task}
""")


def _load(data):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scenario_from_dict(data)
    return [str(w.message) for w in caught if issubclass(w.category, ScenarioWarning)]


def test_a_trajectory_starting_away_from_the_tool_warns_with_the_distance_and_the_fix():
    tool = _tool_at_home()[:3, 3]
    start = tool + np.array([0.3, 0.0, -0.4])  # 0.5 m away
    [message] = _load(_scenario(start))
    assert message.startswith("task 'tool': its trajectory starts 0.5 m from the frame 'tool'")
    assert f"the frame at [{tool[0]:.4f}, {tool[1]:.4f}, {tool[2]:.4f}]" in message
    assert "tracking metrics" in message and f"uvms-qp models {MODEL}" in message


def test_a_trajectory_starting_at_the_tool_loads_quietly_within_the_tolerance():
    tool = _tool_at_home()[:3, 3]
    assert _load(_scenario(tool)) == []
    # the four decimals `uvms-qp models` prints are close enough; a step past the tolerance is not
    assert _load(_scenario(np.round(tool, 4))) == []
    assert _load(_scenario(tool + np.array([0.0, 0.0, 0.9 * FAR_POSITION]))) == []
    assert len(_load(_scenario(tool + np.array([0.0, 0.0, 1.1 * FAR_POSITION])))) == 1


def test_only_the_controlled_axes_count():
    tool = _tool_at_home()[:3, 3]
    away_in_z = tool + np.array([0.0, 0.0, 0.5])
    assert _load(_scenario(away_in_z, 'axes = ["x", "y"]')) == []
    assert len(_load(_scenario(away_in_z, 'axes = ["z"]'))) == 1


def test_a_pose_trajectory_turned_away_from_the_tool_warns_with_the_angle():
    T = _tool_at_home()
    turn = 3 * FAR_ANGLE
    rpy = pin.rpy.matrixToRpy(T[:3, :3] @ pin.rpy.rpyToMatrix(0.0, 0.0, turn))
    data = _scenario(T[:3, 3])
    data["trajectories"]["reach"]["start_rotation"] = [float(a) for a in rpy]
    data["trajectories"]["reach"]["goal_rotation"] = [float(a) for a in rpy]
    data["levels"][0]["tasks"][0]["mode"] = "pose"
    [message] = _load(data)
    assert f"turned {turn:.3g} rad from the frame 'tool'" in message and " m from" not in message
    # the same trajectory for a position task: its rotation is not controlled, so no warning
    data["levels"][0]["tasks"][0]["mode"] = "position"
    assert _load(data) == []


def test_a_scenario_built_in_code_warns_too():
    model = load_model(MODEL)
    tool = model.frame_pose(model.home(), "tool")[:3, 3]
    line = LineTrajectory(tool + np.array([0.2, 0.0, 0.0]), tool, duration=1.0)
    stack = Stack([[EndEffectorTask("tool", trajectory=line)]])
    with pytest.warns(ScenarioWarning, match=r"starts 0\.2 m from the frame 'tool'"):
        Scenario.build(model, stack, model.home(), dt=0.1, duration=1.0)


@pytest.mark.parametrize("name", bundled_scenarios())
def test_every_bundled_scenario_starts_its_trajectories_at_their_frames(name):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ScenarioWarning)
        load_scenario(name)
