"""Plants of a run: the ``[plant]`` table, the kinematic plant, the dynamic one under a scenario,
and a run that stops early because its plant diverged."""

from __future__ import annotations

import dataclasses
import json
import tomllib

import numpy as np
import pytest

from tests.support.scenario_text import bluerov_scenario
from uvms_qp.cli import main
from uvms_qp.errors import ConfigError, SimulationDiverged
from uvms_qp.sim.plant_config import PlantSpec
from uvms_qp.sim.plants import KinematicPlant
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import Scenario, load_scenario, scenario_from_dict

REACH = bluerov_scenario("duration = 0.5", "")


def scenario(extra: str = "", header: str = "duration = 0.5") -> Scenario:
    return scenario_from_dict(tomllib.loads(bluerov_scenario(header, extra)))


def test_without_a_plant_table_a_run_is_kinematic_and_equals_integrating_the_commands():
    sc = scenario()
    assert sc.plant == PlantSpec() and sc.plant.kind == "kinematic"
    run = simulate(sc)
    assert run.plant == "kinematic" and run.dynamics is None
    q = sc.q0
    for k in range(run.steps):
        q = sc.integrator.step(q, run.zeta[k], sc.dt)
        np.testing.assert_array_equal(run.q[k + 1], q)
    plant = sc.make_plant()
    assert isinstance(plant, KinematicPlant) and plant.body_velocity is None


def test_a_dynamic_plant_table_runs_the_floating_vehicle():
    sc = scenario('\n[plant]\ntype = "dynamic"\nservo_rate = 50.0\n')
    assert sc.plant.kind == "dynamic"
    assert sc.plant.parameters.name == "bluerov2_heavy_von_benzon_2022"
    run = simulate(sc)
    assert run.plant == "dynamic"
    assert run.dynamics.thrust.shape == (run.steps * 5, 8)  # 50 Hz servos, 0.1 s periods
    assert run.metrics()["bound_violation_max"] == 0.0
    # the controller's state carried the measured body velocity: the vehicle moved
    assert np.abs(run.dynamics.body_velocity).max() > 0.0


def test_kinematic_scenarios_keep_their_dynamic_settings_for_the_command_line_override():
    sc = scenario('\n[plant]\nparameters = "bluerov2_wu_2018"\nservo_rate = 50.0\n')
    assert sc.plant.kind == "kinematic"
    dynamic = sc.with_plant("dynamic")
    assert dynamic.plant.parameters.name == "bluerov2_wu_2018"
    assert dynamic.plant.servo_rate == 50.0
    assert dynamic.with_plant("kinematic").make_plant().kind == "kinematic"


@pytest.mark.parametrize(("table", "path", "words"), [
    ('type = "floating"', "plant.type", "expected one of"),
    ('parameters = "bluerov3"', "plant.parameters", "bluerov2_heavy_von_benzon_2022"),
    ('parameters = "bluerov2_wu_2018"\nfile = "x.toml"', "plant.file", "not both"),
    ('file = "no_such_plant.toml"', "plant.file", "no_such_plant.toml"),
    ('servo_rate = 15.0\ntype = "dynamic"', "plant", "servo_rate"),
    ('physics_step = 0.003\ntype = "dynamic"', "plant", "physics_step"),
    ('supply_voltage = 14.0\ntype = "dynamic"', "plant", "14"),
    ('coordinate = true', "plant.coordinate", "coordination"),
    ('[plant.payload]\ntime = 0.2\nmass = -1.0', "plant.payload.mass", "positive"),
    ('[plant.gains]\nproportional = [1, 2, 3]', "plant.gains.proportional", "6"),
])
def test_bad_plant_tables_are_config_errors_at_their_path(table, path, words):
    text = "[plant]\n" + table
    with pytest.raises(ConfigError) as info:
        scenario("\n" + text + "\n")
    assert str(info.value).startswith(path), str(info.value)
    assert words in str(info.value)


def test_a_model_without_dynamic_data_is_refused_naming_what_is_missing(tmp_path, capsys):
    sc = load_scenario("paper000_quintic")
    with pytest.raises(ConfigError, match=r"soylu_planar.*no plant parameters"):
        sc.with_plant("dynamic", "--plant")
    code = main(["run", "paper000_quintic", "--plant", "dynamic", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and "--plant" in err and "mass, inertia" in err
    assert "Traceback" not in err and not (tmp_path / "results.json").exists()


class _Diverging:
    """A plant that fails on its third period, as an unstable physics step would."""

    kind = "dynamic"

    def __init__(self, inner) -> None:
        self.inner = inner
        self.periods = 0

    def start(self, q0):
        self.inner.start(q0)

    @property
    def q(self):
        return self.inner.q

    @property
    def body_velocity(self):
        return np.zeros(6)

    def advance(self, zeta, t, rates):
        self.periods += 1
        if self.periods == 3:
            raise SimulationDiverged("physics step diverged: velocity u = 1e9", t=t + 0.03,
                                     q=self.inner.q, v=np.zeros(10), reason="u")
        return self.inner.advance(zeta, t, rates)

    def series(self, steps):
        return None


def test_a_diverging_plant_ends_the_run_keeping_the_steps_before_it(monkeypatch, tmp_path,
                                                                    capsys):
    sc = scenario()
    monkeypatch.setattr(Scenario, "make_plant",
                        lambda self, sensors=None: _Diverging(KinematicPlant(self.integrator,
                                                                             self.dt)))
    run = simulate(sc)
    assert run.stopped == {"time": pytest.approx(0.23), "step": 2,
                           "error": "physics step diverged: velocity u = 1e9"}
    assert run.steps == 2 and run.zeta.shape[0] == 2 and run.q.shape[0] == 3
    assert len(run.status) == 2 and run.time_states.shape == (3,)
    assert run.ee_position.shape[0] == 3 and np.isfinite(run.q).all()
    metrics = run.metrics()
    assert metrics["nan_steps"] == 0
    # the command line writes what was recorded and says why it stopped, with status 1
    path = tmp_path / "s.toml"
    path.write_text(bluerov_scenario("duration = 0.5", ""))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-plots"]) == 1
    err = capsys.readouterr().err
    assert "stopped at t = 0.23 s" in err and "diverged" in err
    record = json.loads((tmp_path / "out" / "results.json").read_text())
    assert record["stopped"]["step"] == 2 and record["steps"] == 2


def test_the_payload_of_a_plant_table_is_attached_at_its_time():
    sc = scenario('\n[plant]\ntype = "dynamic"\nservo_rate = 50.0\n'
                  '[plant.payload]\ntime = 0.2\nmass = 1.0\nvolume = 0.0002\n')
    run = simulate(sc)
    assert run.dynamics.payload_time == pytest.approx(0.2)
    torque = np.abs(run.dynamics.joint_torque)
    t = run.dynamics.time
    assert torque[t > 0.35].max() > torque[t < 0.2].max()


def test_scenario_build_takes_a_plant_and_sensors():
    sc = scenario()
    spec = sc.plant.as_kind("dynamic", sc.model)
    built = Scenario.build(sc.model, sc.build_stack(), sc.q0, dt=0.1, duration=0.2, plant=spec)
    assert built.plant.kind == "dynamic" and simulate(built).plant == "dynamic"
    assert dataclasses.replace(built, sensors=None).sensors is None
