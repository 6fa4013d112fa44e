"""Scenario keys of the command as a signal: the damping thresholds (top level and per level)
and a task entering the stack through an activation event."""

from __future__ import annotations

import tomllib

import pytest

from tests.support.scenario_text import bluerov_scenario
from uvms_qp.errors import ConfigError
from uvms_qp.hqp.damping import DEFAULT_THRESHOLD
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import scenario_from_dict

POSTURE = """
[[levels]]
damping = 0.0
[[levels.tasks]]
type = "posture"
posture = [2.6, 1.3, 1.3, 2.6]
activation = 0.0
"""


def _load(header, tail=POSTURE):
    return scenario_from_dict(tomllib.loads(bluerov_scenario(header, tail)), name="keys")


def test_damping_thresholds_reach_the_controller():
    scenario = _load("duration = 0.5\ndamping = 0.1")
    controller = scenario.make_controller()
    assert scenario.damping == controller.damping == 0.1
    assert [level.damping for level in controller.stack.levels] == [None, 0.0]
    assert controller.assembler.damping == (0.1, 0.0)
    default = _load("duration = 0.5", POSTURE.replace("damping = 0.0\n", ""))
    assert default.damping is None and default.make_controller().damping == DEFAULT_THRESHOLD


@pytest.mark.parametrize(("header", "tail", "path"), [
    ("duration = 0.5\ndamping = -1.0", POSTURE, "damping"),
    ("duration = 0.5", POSTURE.replace("damping = 0.0", "damping = -0.5"), "levels[1].damping"),
])
def test_a_negative_damping_is_an_error_at_its_path(header, tail, path):
    with pytest.raises(ConfigError) as info:
        _load(header, tail)
    assert str(info.value).startswith(path)


def test_an_activation_event_ramps_a_task_into_the_stack():
    scenario = _load("duration = 2.0", POSTURE + """
[[events]]
time = 0.5
task = "posture"
update = { activation = 1.0, ramp = 0.5 }
""")
    result = simulate(scenario)
    statuses = result.status
    dt = scenario.dt
    assert statuses[round(0.6 / dt)] == "blended"  # half way through the ramp
    assert "blended" not in statuses[:round(0.5 / dt) + 1]
    assert "blended" not in statuses[round(1.1 / dt):]
    assert result.metrics()["status_counts"]["blended"] == round(0.5 / dt) - 1
