"""Sweeps on the floating vehicle: each drawn value reaches the run's plant, sensors and payload."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sweeps import DYNAMIC, write_sweep
from uvms_qp import dynamics
from uvms_qp.errors import ConfigError
from uvms_qp.sweep import draw, load_sweep, run_seed, run_sweep, simulate_run
from uvms_qp.sweep.outcome import run_outcome
from uvms_qp.sweep.realise import realise
from uvms_qp.sweep.sampling import sensor_seed
from uvms_qp.sweep.spec import GRAVITY, WATER_DENSITY


@pytest.fixture
def spec(tmp_path):
    return load_sweep(write_sweep(tmp_path, runs=2, text=DYNAMIC))


def test_each_run_gets_its_parameter_set_scaled_by_its_factors(spec):
    for index in range(4):
        seed = run_seed(spec.seed, index)
        drawn = draw(spec.variables, seed)
        scenario = realise(spec, drawn, seed)
        assert scenario.plant.kind == "dynamic"
        expected = dynamics.plant_parameters(drawn["plant_parameters.set"])
        factor = 1.0 + drawn["plant_parameters.vehicle.added_mass"]
        got = scenario.plant.parameters
        assert np.allclose(got.vehicle.added_mass, factor * expected.vehicle.added_mass,
                           rtol=1e-12, atol=0.0)
        assert np.array_equal(got.vehicle.linear_damping, expected.vehicle.linear_damping)
        link = 1.0 + drawn["plant_parameters.links.mass"]
        for joint, body in got.links.items():
            assert body.mass == pytest.approx(link * expected.links[joint].mass, rel=1e-12)


def test_each_run_gets_its_sensors_and_payload(spec):
    seed = run_seed(spec.seed, 1)
    drawn = draw(spec.variables, seed)
    scenario = realise(spec, drawn, seed)
    sensors = scenario.sensors
    assert sensors.position_noise == 0.01
    assert sensors.linear_rate_noise == drawn["sensors.linear_rate_noise"]
    assert sensors.seed == sensor_seed(seed)
    mass, volume = drawn["payload.mass"], drawn["payload.volume"]
    assert (scenario.plant.payload.mass, scenario.plant.payload.volume) == (mass, volume)
    pickup = next(e for e in scenario.events if "force" in e.update)
    assert pickup.update["force"] == pytest.approx((mass - WATER_DENSITY * volume) * GRAVITY)


def test_a_dynamic_run_replays_from_its_seed(spec, tmp_path):
    outcome = run_sweep(spec, tmp_path, workers=1)
    assert [r["status"] for r in outcome.records] == ["ok", "ok"]
    record = outcome.records[1]
    assert record["metrics"]["energy"] > 0.0  # a metric only the dynamic plant reports
    _, result = simulate_run(spec, record["seed"])
    assert run_outcome(result)["metrics"] == record["metrics"]


@pytest.mark.parametrize(("old", "new", "path", "words"), [
    ('"bluerov2_wu_2018"', '"bluerov2_wu_2019"', "plant_parameters.set",
     "unknown parameter set 'bluerov2_wu_2019'"),
    ('"links.mass" = {{ uniform = [-0.2, 0.2] }}', '"links.mass" = {{ uniform = [-1.0, 0.2] }}',
     "plant_parameters.links.mass", "reaches a factor 1 + (-1) = 0"),
    ('plant = "dynamic"', 'plant = "kinematic"', "plant_parameters",
     'set plant = "dynamic"'),
])
def test_a_bad_dynamic_sweep_names_its_culprit(tmp_path, old, new, path, words):
    text = DYNAMIC.replace(old, new)
    assert text != DYNAMIC
    with pytest.raises(ConfigError) as info:
        load_sweep(write_sweep(tmp_path, text=text))
    assert info.value.path == path, str(info.value)
    assert words in str(info.value)


def test_the_sweeps_plant_decides_whatever_the_scenarios(tmp_path):
    from uvms_qp.sim.scenario import resolve_scenario

    text = resolve_scenario("bluerov2_demo").read_text()
    assert 'type = "kinematic"' in text
    (tmp_path / "floating.toml").write_text(text.replace('type = "kinematic"', 'type = "dynamic"'))
    sweep = DYNAMIC.replace('scenario = "bluerov2_demo"', 'scenario = "floating.toml"')
    sweep = sweep.replace('plant = "dynamic"', 'plant = "kinematic"')
    sweep = sweep.split("[plant_parameters]")[0] + "[success]" + sweep.split("[success]")[1]
    spec = load_sweep(write_sweep(tmp_path, runs=1, text=sweep))
    seed = run_seed(spec.seed, 0)
    assert realise(spec, draw(spec.variables, seed), seed).plant.kind == "kinematic"
