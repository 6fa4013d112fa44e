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
    ('servo_rate = 15.0\ntype = "dynamic"', "plant.servo_rate", "must divide"),
    ('physics_step = 0.003\ntype = "dynamic"', "plant.physics_step", "must divide"),
    ('physics_step = 1e-7', "plant.physics_step", "0.0001"),
    ('supply_voltage = 14.8', "plant.supply_voltage", "14.8 V"),
    ('feedforward = "exact"', "plant.feedforward", "nominal"),
    ('[plant.payload]\ntime = 45.0\nmass = 1.0', "plant.payload.time", "0.5"),
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


@pytest.mark.parametrize(("name", "words"), [
    ("paper000_quintic", "'soylu_planar' has a planar vehicle"),
    ("paper002_line_paper_order", "'nenchev_pa10_arm' has a fixed vehicle"),
    ("paper003_case1_no_payload", "'wang_9dof' has no plant parameters"),
])
def test_a_model_without_dynamic_data_is_refused_naming_what_is_missing(name, words, tmp_path,
                                                                        capsys):
    sc = load_scenario(name)
    with pytest.raises(ConfigError, match=words):
        sc.with_plant("dynamic", "--plant")
    code = main(["run", name, "--plant", "dynamic", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and "--plant" in err and words in err
    if "no plant parameters" in words:  # what a plant needs, and how a scenario file gives it
        assert "mass, inertia" in err and "[plant] file" in err
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

    def settings(self, spec):
        return self.inner.settings(spec)


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
    captured = capsys.readouterr()
    err = captured.err
    assert "stopped at t = 0.23 s" in err and "diverged" in err
    # no summary of the steps that did run, nor a note on the duration, to mislead
    assert "ee_error_max" not in captured.out and "note:" not in captured.out
    record = json.loads((tmp_path / "out" / "results.json").read_text())
    assert record["stopped"]["step"] == 2 and record["steps"] == 2


def test_the_record_says_which_plant_and_sensors_ran(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(bluerov_scenario("duration = 0.2", '\n[plant]\ntype = "dynamic"\n'
                                     'servo_rate = 50.0\ncoordination = true\n'
                                     '[sensors]\nposition_noise = 0.01\nseed = 3\n'))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-plots",
                 "--quiet"]) == 0
    record = json.loads((tmp_path / "out" / "results.json").read_text())
    settings = record["plant_settings"]
    assert settings["type"] == "dynamic" and settings["coordination"] is True
    assert settings["parameters"] == "bluerov2_heavy_von_benzon_2022"
    assert settings["servo_rate"] == 50.0 and settings["feedforward"] == "model"
    assert record["sensors"]["position_noise"] == 0.01 and record["sensors"]["seed"] == 3
    assert record["kinematic_reference"]["metrics"]["nan_steps"] == 0


def test_the_record_gives_the_values_the_plant_ran_with_not_the_scenario_s_overrides(
        tmp_path, capsys):
    # no physics step, supply or gains in the scenario: the record has the plant's own
    path = tmp_path / "s.toml"
    path.write_text(bluerov_scenario("duration = 0.2", '\n[plant]\ntype = "dynamic"\n'))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    printed = capsys.readouterr().out
    settings = json.loads((tmp_path / "out" / "results.json").read_text())["plant_settings"]
    assert settings["physics_step"] == 0.005 and settings["supply_voltage"] == 16.0
    placed = settings["gains"]
    assert len(placed["proportional"]) == 6 and len(placed["integral"]) == 6
    assert min(placed["proportional"]) > 0.0 and min(placed["integral"]) > 0.0
    assert settings["defaults"] == ["physics_step", "supply_voltage", "gains.proportional",
                                    "gains.integral"]
    assert ("plant: dynamic, parameter set bluerov2_heavy_von_benzon_2022, feed-forward model, "
            "coordination off (physics 0.005 s, servos 100 Hz, thrusters at 16 V)") in printed
    # given values are recorded as given, and no longer listed as defaults
    path.write_text(bluerov_scenario("duration = 0.2", (
        '\n[plant]\ntype = "dynamic"\nphysics_step = 0.002\nsupply_voltage = 12.0\n'
        '[plant.gains]\nproportional = [145, 165, 224, 4, 2, 5]\n')))
    run = simulate(load_scenario(path))
    settings = run.plant_settings
    assert settings["physics_step"] == pytest.approx(0.002)
    assert settings["supply_voltage"] == 12.0
    assert settings["gains"]["proportional"] == [145.0, 165.0, 224.0, 4.0, 2.0, 5.0]
    assert len(settings["gains"]["integral"]) == 6
    assert settings["defaults"] == ["gains.integral"]


def test_the_payload_of_a_plant_table_is_attached_at_its_time():
    sc = scenario('\n[plant]\ntype = "dynamic"\nservo_rate = 50.0\n'
                  '[plant.payload]\ntime = 0.2\nmass = 1.0\nvolume = 0.0002\n')
    run = simulate(sc)
    assert run.dynamics.payload_time == pytest.approx(0.2)
    torque = np.abs(run.dynamics.joint_torque)
    t = run.dynamics.time
    assert torque[t > 0.35].max() > torque[t < 0.2].max()


@pytest.mark.parametrize("mass", [1.5, 2.5])
def test_a_payload_beyond_the_arm_s_rating_is_reported_not_refused(tmp_path, capsys, mass):
    # the bundled arm is rated 2 kg at full reach: 2.5 kg is flagged, 1.5 kg is not
    path = tmp_path / "s.toml"
    path.write_text(bluerov_scenario("duration = 0.2", '\n[plant]\ntype = "dynamic"\n'
                                     f'[plant.payload]\ntime = 0.1\nmass = {mass}\n'))
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    printed = capsys.readouterr()
    record = json.loads((tmp_path / "out" / "results.json").read_text())
    assert record["plant_settings"]["rated_payload"] == 2.0
    assert record["metrics"]["payload_mass"] == mass
    assert record["metrics"]["payload_rating_share"] == pytest.approx(mass / 2.0)
    assert record["steps"] == 2 and record.get("stopped") is None
    assert set(record["metrics"]["joint_torque_max"]) == {"axis_e", "axis_d", "axis_c", "axis_b"}
    assert "payload_rating_share" in printed.out
    flagged = "warning: the payload of 2.5 kg exceeds the arm's rated payload of 2 kg"
    if mass > 2.0:
        assert flagged in printed.err and record["warnings"] == [printed.err.split(
            "warning: ")[-1].strip()]
    else:
        assert "warning" not in printed.err and "warnings" not in record


def test_scenario_build_takes_a_plant_and_sensors():
    sc = scenario()
    spec = sc.plant.as_kind("dynamic", sc.model)
    built = Scenario.build(sc.model, sc.build_stack(), sc.q0, dt=0.1, duration=0.2, plant=spec)
    assert built.plant.kind == "dynamic" and simulate(built).plant == "dynamic"
    assert dataclasses.replace(built, sensors=None).sensors is None


def _own_plant(tmp_path, text: str) -> Scenario:
    (tmp_path / "mine.toml").write_text('name = "mine"\nbase = "bluerov2_heavy_von_benzon_2022"\n'
                                        + text)
    path = tmp_path / "s.toml"
    path.write_text(bluerov_scenario("duration = 0.2",
                                     '\n[plant]\ntype = "dynamic"\nfile = "mine.toml"\n'))
    return load_scenario(path)


FOUR = """
[thrusters]
actuated = ["u", "v", "w", "r"]
[[thrusters.thrusters]]
position = [-0.2, -0.15, 0.0]
axis = [1.0, 0.0, 0.0]
model = "T200"
[[thrusters.thrusters]]
position = [-0.2, 0.15, 0.0]
axis = [1.0, 0.0, 0.0]
model = "T200"
[[thrusters.thrusters]]
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
model = "T200"
[[thrusters.thrusters]]
position = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
model = "T200"
"""


def test_thrusters_that_leave_a_commanded_dof_passive_are_refused(tmp_path):
    # the model commands roll and pitch; four thrusters cannot give them
    with pytest.raises(ConfigError, match=r"^plant: .*leaves p, q passive"):
        _own_plant(tmp_path, FOUR)


def test_given_gains_replace_a_placement_that_does_not_suit_the_vehicle(tmp_path):
    # roll damping of 10 N m s/rad on 0.45 kg m^2: faster than the placement's 4 rad/s allows
    damped = "[vehicle]\nlinear_damping = [13.7, 0, 33, 10, 0.8, 0]\n"
    with pytest.raises(ConfigError, match=r"DOF p .*\[plant\.gains\]"):
        _own_plant(tmp_path, damped)
    path = tmp_path / "g.toml"
    path.write_text(bluerov_scenario("duration = 0.2", (
        '\n[plant]\ntype = "dynamic"\nfile = "mine.toml"\n[plant.gains]\n'
        "proportional = [145, 165, 224, 1, 2, 5]\nintegral = [318, 330, 515, 7, 6, 9]\n")))
    run = simulate(load_scenario(path))
    assert run.stopped is None and run.plant_settings["gains"]["proportional"][3] == 1.0


def test_the_run_starts_trimmed_on_what_the_loop_feeds_forward():
    # trimmed on the restoring wrench, the thrusters hold the vehicle from the first tick; with
    # nothing fed forward they start at zero and the vehicle sinks and pitches before the
    # integral catches up
    heave = {}
    for feedforward in ("model", "none"):
        sc = scenario(f'\n[plant]\ntype = "dynamic"\nfeedforward = "{feedforward}"\n',
                      header="duration = 0.3")
        run = simulate(sc)
        heave[feedforward] = np.abs(run.dynamics.body_velocity[:, 2]).max()
        if feedforward == "model":
            plant = sc.make_plant()
            plant.start(sc.q0)
            hold = plant.physics.restoring_wrench(sc.q0)
            np.testing.assert_allclose(plant.layout.matrix @ plant.thrusters.forces, hold,
                                       atol=1e-6)
    assert heave["none"] > 2.0 * heave["model"]


def test_a_slowly_varying_current_reaches_the_dynamic_plant():
    sc = scenario('\n[current]\ndirection = 0.5\nspeed = 0.2\noscillation = 0.1\nperiod = 20.0\n'
                  '[plant]\ntype = "dynamic"\n')
    water = sc.make_plant().physics.current
    assert not water.steady
    np.testing.assert_allclose(water.velocity(5.0), 0.3 * np.array([np.cos(0.5), np.sin(0.5),
                                                                    0.0]))
    assert sc.current.oscillation == 0.1


@pytest.mark.parametrize(("feedforward", "share"), [("model", (0.0, 0.1)),
                                                     ("nominal", (0.8, 1.2))])
def test_only_the_feed_forward_told_the_current_holds_its_drag(feedforward, share):
    # station in a 0.3 m/s head current: the vehicle's drag is (D_l + D_q |u_r|) u_r at the
    # relative surge u_r = 0.3 m/s; the model feed-forward is told the current and carries it,
    # the nominal one is not and its integral must
    sc = scenario(f'\n[current]\ndirection = 3.14159\nspeed = 0.3\n'
                  f'[plant]\ntype = "dynamic"\nfeedforward = "{feedforward}"\n')
    plant = sc.make_plant()
    plant.start(sc.q0)
    body = plant.spec.parameters.vehicle
    drag = body.linear_damping[0] * 0.3 + body.quadratic_damping[0] * 0.09
    t = 0.0
    for _ in range(60):  # 6 s holding station
        plant.advance(np.zeros(10), t)
        t += sc.dt
    assert abs(plant.body_velocity[0]) < 1e-3
    integral = (plant.loop.ki * plant.loop.integral)[0]
    assert share[0] * drag <= integral <= share[1] * drag
