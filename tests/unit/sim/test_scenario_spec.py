"""A scenario is a frozen specification: checked once, and every run builds its own objects."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest

import uvms_qp
from tests.support.scenario_text import bluerov_scenario
from uvms_qp import Level, Stack
from uvms_qp.constraints import JointVelocityBounds
from uvms_qp.errors import ConfigError
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import Event, Scenario, scenario_from_dict
from uvms_qp.tasks import TASK_TYPES, EndEffectorTask, PayloadMomentTask, PostureTask

SMALL = bluerov_scenario("duration = 0.6", """
[[levels]]
[[levels.tasks]]
type = "payload_moment"
name = "payload"
mode = "bound"
maximum = 10.0

[[levels]]
[[levels.tasks]]
type = "counted_posture"
name = "posture"

[[events]]
time = 0.3
task = "payload"
update = { force = 5.0 }
""")


class CountedPosture(PostureTask):
    """A posture task that counts its constructions."""

    type_name = "counted_posture"
    built = 0

    def __init__(self, *, name: str | None = None, gain: float = 1.0) -> None:
        type(self).built += 1
        super().__init__(name=name, gain=gain)


@pytest.fixture
def small():
    CountedPosture.built = 0
    return scenario_from_dict(tomllib.loads(SMALL),
                              task_types={**TASK_TYPES, "counted_posture": CountedPosture})


def test_loading_builds_each_task_once_and_each_run_once_more(small):
    assert CountedPosture.built == 1  # checked on one stack: no scratch copies
    simulate(small)
    assert CountedPosture.built == 2
    simulate(small)
    assert CountedPosture.built == 3


def test_the_specification_cannot_be_changed(small):
    with pytest.raises(dataclasses.FrozenInstanceError):
        small.dt = 0.2
    with pytest.raises(ValueError, match="read-only"):
        small.q0[0] = 1.0
    with pytest.raises(TypeError):
        small.events[0].update["force"] = 1.0
    with pytest.raises(TypeError):
        small.trajectories["x"] = None


def test_each_stack_is_new_bound_and_unchanged_by_runs(small):
    first, second = small.build_stack(), small.build_stack()
    assert first.task("payload") is not second.task("payload")
    assert first.model is small.model and first.task("payload").model is not None
    simulate(small, stack=first)
    assert first.task("payload").force == 5.0  # the event fired on this run's task
    assert small.build_stack().task("payload").force == 0.0


def test_events_reach_the_tasks_of_a_controller_given_to_the_run(small):
    controller = small.make_controller("cascade:quadprog")
    result = simulate(small, controller)
    assert controller.stack.task("payload").force == 5.0
    assert result.payload_moment[0] == 0.0 and result.payload_moment[-1] > 0.0


def test_duration_override_keeps_the_step_cap(small):
    assert small.with_duration(0.25).steps == 2  # round(0.25 / 0.1)
    assert small.duration == 0.6  # the original is unchanged
    with pytest.raises(ConfigError, match=r"^--duration: .*steps; at most 2000000"):
        small.with_duration(3e5, "--duration")  # 3e6 steps
    with pytest.raises(ConfigError, match=r"^duration: 0.01 s is shorter than one control"):
        small.with_duration(0.01)


def _model_and_q0():
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    return model, model.configuration(np.zeros(6), [math.pi, 1.2, 1.7, math.pi])


def _stack(goal):
    return Stack(constraints=[JointVelocityBounds()],
                 levels=[Level(EndEffectorTask("tool", position=goal)),
                         Level(PayloadMomentTask(name="payload", mode="bound", maximum=1.0))])


def test_code_built_event_updates_are_checked_when_built():
    model, q0 = _model_and_q0()
    goal = model.frame_pose(q0, "tool")[:3, 3]
    with pytest.raises(ConfigError, match=r"^events\[0\]\.update\.force: expected a non-negative"):
        Scenario.build(model, _stack(goal), q0, dt=0.1, duration=1.0,
                       events=[Event(0.5, "payload", {"force": -2.0})])


def test_code_built_stack_is_a_template_or_a_factory():
    model, q0 = _model_and_q0()
    goal = model.frame_pose(q0, "tool")[:3, 3]
    given = _stack(goal)
    scenario = Scenario.build(model, given, q0, dt=0.1, duration=0.5,
                              events=[Event(0.2, "payload", {"force": 3.0})])
    stack = scenario.build_stack()
    assert stack.task("payload") is not given.task("payload")
    simulate(scenario, stack=stack)
    assert stack.task("payload").force == 3.0 and given.task("payload").force == 0.0
    made = Scenario.build(model, lambda: _stack(goal), q0, dt=0.1, duration=0.5)
    assert made.task_names == (("tool",), ("payload",))
    with pytest.raises(uvms_qp.InputError, match="stack: expected a Stack"):
        Scenario.build(model, 3, q0, dt=0.1, duration=0.5)
