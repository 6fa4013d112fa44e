"""Every bundled scenario loads, resolves by name, and runs its first steps safely."""

from __future__ import annotations

import pytest

from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import bundled_scenarios, load_scenario, resolve_scenario

NAMES = bundled_scenarios()


def test_demo_is_bundled():
    assert "bluerov2_demo" in NAMES
    assert resolve_scenario("bluerov2_demo").name == "bluerov2_demo.toml"


@pytest.mark.parametrize("name", NAMES)
def test_bundled_scenario_loads_and_starts(name):
    scenario = load_scenario(name)
    assert scenario.steps > 0
    assert scenario.schemes[0] == "hqp"
    result = simulate(scenario, duration=5 * scenario.dt)
    metrics = result.metrics()
    assert metrics["nan_steps"] == 0
    assert metrics["bound_violation_max"] <= 1e-7
