"""Scenario keys ``strict`` and ``deadline``: checked with their path, given to the controller."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from tests.support.scenario_text import bluerov_scenario
from uvms_qp.errors import ConfigError, InputError, NoSolutionFound
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import Scenario, scenario_from_dict
from uvms_qp.testing.faults import Fault, inject

BASE = bluerov_scenario("duration = 0.5", """
[[levels]]
[[levels.tasks]]
type = "station_keeping"
""")


def load(head: str = "") -> Scenario:
    return scenario_from_dict(tomllib.loads(head + "\n" + BASE))


def test_defaults_leave_the_controller_lenient_and_unbounded():
    scenario = load()
    assert scenario.strict is False and scenario.deadline is None
    controller = scenario.make_controller()
    assert controller.strict is False
    assert controller.safe.deadline is None and controller.safe.strict is False


def test_keys_reach_the_controller_and_survive_overrides_and_fresh_stacks():
    scenario = load("strict = true\ndeadline = 0.02")
    assert scenario.strict is True and scenario.deadline == pytest.approx(0.02)
    for controller in (scenario.make_controller(),
                       scenario.make_controller("cascade:quadprog"),  # --solver override
                       scenario.make_controller(stack=scenario.build_stack())):
        assert controller.strict is True and controller.safe.strict is True
        assert controller.safe.deadline == pytest.approx(0.02)


def test_an_integer_deadline_is_seconds():
    assert load("deadline = 1").make_controller().safe.deadline == 1.0


@pytest.mark.parametrize(("line", "path", "words"), [
    ("deadline = -0.01", "deadline", "expected a positive number"),
    ("deadline = 0", "deadline", "expected a positive number"),
    ("deadline = nan", "deadline", "expected a finite number"),
    ("deadline = inf", "deadline", "expected a finite number"),
    ('deadline = "10ms"', "deadline", "expected a positive number, got a string"),
    ("deadline = true", "deadline", "expected a positive number, got a boolean"),
    ("strict = 1", "strict", "expected a boolean, got an integer"),
    ('strict = "yes"', "strict", "expected a boolean, got a string"),
])
def test_bad_values_name_their_field(line, path, words):
    with pytest.raises(ConfigError) as info:
        load(line)
    assert info.value.path == path
    assert str(info.value).startswith(f"{path}: {words}")


def test_scenario_build_validates_the_deadline():
    scenario = load()
    with pytest.raises(InputError, match="deadline: expected a positive number"):
        Scenario.build(scenario.model, scenario.build_stack(), scenario.q0, dt=0.1,
                       duration=0.5, deadline=-1.0)
    built = Scenario.build(scenario.model, scenario.build_stack(), scenario.q0, dt=0.1,
                           duration=0.5, strict=True, deadline=0.05)
    controller = built.make_controller()
    assert controller.strict is True and controller.safe.deadline == pytest.approx(0.05)


def faulty_controller(scenario: Scenario):
    """The scenario's controller with its primary and alternate back-ends failing on every call."""
    controller = scenario.make_controller()
    for solver in (controller.safe.primary, controller.safe.alternate):
        inject(solver, Fault.RAISE_OWN).armed = True
    return controller


def test_strict_from_the_file_raises_instead_of_degrading():
    scenario = load("strict = true")
    with pytest.raises(NoSolutionFound):
        simulate(scenario, faulty_controller(scenario))


def test_lenient_file_degrades_to_a_finite_command_instead():
    scenario = load()
    result = simulate(scenario, faulty_controller(scenario))
    assert result.nan_steps == 0 and np.all(np.isfinite(result.zeta))
    assert set(result.status) == {"backend_error"}
