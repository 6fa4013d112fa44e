"""Sweep files: every mistake is a ConfigError at the culprit's path, before any run."""

from __future__ import annotations

import pytest

from tests.support.sweeps import TINY, write_sweep
from uvms_qp.errors import ConfigError
from uvms_qp.sweep import bundled_sweeps, load_sweep
from uvms_qp.sweep.distributions import Choice, Normal, Uniform


def _error(tmp_path, old: str, new: str) -> ConfigError:
    text = TINY.replace(old, new)
    assert text != TINY, old
    with pytest.raises(ConfigError) as info:
        load_sweep(write_sweep(tmp_path, text=text))
    return info.value


@pytest.mark.parametrize(("old", "new", "path", "words"), [
    ("runs = {runs}", "runs = {runs}\nrnus = 3", "rnus", "unknown key 'rnus'"),
    ("speed = 0.2", "sped = 0.2", "current.sped", "unknown key 'sped'"),
    ("runs = {runs}", "runs = 0", "runs", "number of runs in [1,"),
    ("seed = 11", "seed = -1", "seed", "non-negative integer"),
    ("[payload]\nmass = {{ uniform = [0.0, 3.0] }}",
     "[payload]\nmass = {{ uniform = [-1.0, 3.0] }}", "payload.mass",
     "a payload mass [kg] must be >= 0, but the spread U(-1, 3) reaches -1"),
    ("[payload]\nmass = {{ uniform = [0.0, 3.0] }}",
     "[payload]\nmass = {{ uniform = [0.0, 3.0] }}\nvolume = 0.001", "payload.volume",
     "lighter than the water"),
    ("[payload]\nmass = {{ uniform = [0.0, 3.0] }}",
     "[payload]\nmass = {{ uniform = [0.0, 3.0] }}\nvolume = {{ uniform = [-0.1, 0.0] }}",
     "payload.volume", "must be >= 0"),
    ("delay = {{ choice = [0.0, 0.05] }}", "delay = {{ normal = [0.05, 0.01] }}", "sensors.delay",
     "is unbounded (add within = [low, high])"),
    ("delay = {{ choice = [0.0, 0.05] }}", "linear_rate_noise = 0.01",
     "sensors.linear_rate_noise", "set plant = \"dynamic\""),
    ("[current]", "[plant_parameters]\n\"vehicle.added_mass\" = 0.1\n[current]",
     "plant_parameters", "set plant = \"dynamic\""),
    ("drift = {{ uniform = [0.0, 0.5] }}", "drift = {{ uniforn = [0.0, 0.5] }}",
     "current.drift.uniforn", "unknown key 'uniforn'"),
    ("drift = {{ uniform = [0.0, 0.5] }}", "drift = {{ uniform = [0.5, 0.0] }}",
     "current.drift.uniform", "low <= high"),
    ("drift = {{ uniform = [0.0, 0.5] }}", "drift = {{ uniform = [0.0, 1.5] }}",
     "current.drift", "must be >= 0 and <= 1"),
    ("drift = {{ uniform = [0.0, 0.5] }}", "drift = {{ uniform = [0.0, 0.5], normal = [0, 1] }}",
     "current.drift", "exactly one of uniform, normal, choice"),
    ("ee_error_max = {{ max = 0.01 }}", "ee_eror_max = {{ max = 0.01 }}",
     "success.ee_eror_max", "did you mean 'ee_error_max'?"),
    ("ee_error_max = {{ max = 0.01 }}", "ee_error_max = {{ below = 0.01 }}",
     "success.ee_error_max.below", "unknown key"),
    ('scenario = "bluerov2_demo"', 'scenario = "bluerov2_dem"', "scenario",
     "unknown scenario 'bluerov2_dem'"),
    ("duration = 0.25", "duration = -1.0", "duration", "positive number"),
])
def test_a_bad_sweep_file_names_its_culprit(tmp_path, old, new, path, words):
    error = _error(tmp_path, old, new)
    assert error.path == path, str(error)
    assert words in str(error)


@pytest.mark.parametrize(("key", "law", "words"), [
    ("vehicle.mass", "{{ uniform = [-1.2, 0.0] }}",
     "the vehicle's mass [kg] is scaled by 1 + x, which must stay positive, but the spread "
     "U(-1.2, 0) reaches a factor 1 + (-1.2) = -0.2"),
    ("links.volume", "{{ normal = [0.0, 0.3] }}", "is unbounded (add within = [low, high])"),
    ("vehicle.volume", "-1.0", "reaches a factor 1 + (-1) = 0"),
    ("vehicle.masss", "0.1", "unknown plant parameter 'vehicle.masss'"),
])
def test_a_plant_parameter_spread_keeps_every_magnitude_positive(tmp_path, key, law, words):
    error = _error(tmp_path, "[current]",
                   f'plant = "dynamic"\n[plant_parameters]\n"{key}" = {law}\n[current]')
    assert error.path == f"plant_parameters.{key}"
    assert words in str(error)


def test_the_base_scenario_errors_carry_their_own_path(tmp_path):
    scenario = tmp_path / "base.toml"
    scenario.write_text('model = "bluerov2_heavy_alpha5"\ndt = 0.05\nduration = 1.0\n'
                        '[[levels]]\n[[levels.tasks]]\ntype = "posture"\ngian = 1.0\n')
    error = _error(tmp_path, 'scenario = "bluerov2_demo"', 'scenario = "base.toml"')
    assert error.path == "scenario"
    assert "levels[0].tasks[0].gian: unknown key" in str(error)


def test_a_payload_needs_a_pick_up_in_the_scenario(tmp_path):
    error = _error(tmp_path, 'scenario = "bluerov2_demo"', 'scenario = "paper000_quintic"')
    assert error.path == "payload"
    assert "'paper000_quintic' picks up no payload" in str(error)


def test_runs_override_is_checked_and_keeps_the_fingerprint(tiny):
    assert tiny.with_runs(50).digest() == tiny.digest()
    with pytest.raises(ConfigError, match=r"^--runs: expected a number of runs"):
        tiny.with_runs(0)
    with pytest.raises(ConfigError, match=r"^--runs: expected a positive integer"):
        tiny.with_runs(2.5)


def test_the_file_is_read_into_laws(tiny):
    laws = {v.name: v.dist for v in tiny.variables}
    assert laws["current.direction"] == Uniform(low=-0.5, high=0.5)
    assert laws["initial.joints"] == Normal(mean=0.0, std=0.02, low=-0.05, high=0.05)
    assert laws["sensors.delay"] == Choice(options=(0.0, 0.05))
    assert not laws["current.speed"].varies
    assert tiny.variable("initial.joints").count == 4  # the Alpha 5's joints
    assert [c.describe() for c in tiny.criteria] == ["ee_error_max <= 0.01",
                                                     "level_met_share.0 >= 0.99"]


def test_the_bundled_sweep_loads():
    assert "bluerov2_demo_sweep" in bundled_sweeps()
    spec = load_sweep("bluerov2_demo_sweep")
    assert spec.scenario == "bluerov2_demo"
    assert spec.varied and spec.criteria
