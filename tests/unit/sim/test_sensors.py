"""Sensors: what the controller measures of the plant (noise, delay), and runs that use them."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest

from tests.support.scenario_text import bluerov_scenario
from uvms_qp import load_model
from uvms_qp.errors import ConfigError, InputError
from uvms_qp.sim.runner import _measured_state, simulate
from uvms_qp.sim.scenario import scenario_from_dict
from uvms_qp.sim.sensors import Sensors

MODEL = load_model("bluerov2_heavy_alpha5")
STILL = bluerov_scenario("duration = 1.0", "")


def configurations(count: int) -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    return [MODEL.random_configuration(rng) for _ in range(count)]


def test_exact_sensors_give_the_true_configuration_and_velocity_unchanged():
    channel = Sensors().channel(MODEL, 0.1)
    for q in configurations(3):
        assert channel.pose(q) is q
    nu = np.arange(6.0)
    assert channel.body_velocity(nu) is nu


def test_a_delay_gives_the_configuration_of_that_many_periods_ago():
    channel = Sensors(delay=0.3).channel(MODEL, 0.1)
    qs = configurations(8)
    seen = [channel.pose(q) for q in qs]
    for k, q in enumerate(seen):
        np.testing.assert_array_equal(q, qs[max(0, k - 3)])


def test_a_delay_gives_the_configuration_and_velocity_of_one_same_earlier_instant():
    channel = Sensors(delay=0.2).channel(MODEL, 0.1)
    qs = configurations(6)
    nus = [np.full(6, float(k)) for k in range(6)]
    for k, (q, nu) in enumerate(zip(qs, nus, strict=True)):
        seen_q, seen_nu = channel.state(q, nu)
        np.testing.assert_array_equal(seen_q, qs[max(0, k - 2)])
        np.testing.assert_array_equal(seen_nu, nus[max(0, k - 2)])


def test_the_controller_s_measured_state_is_delayed_whole_and_the_loop_s_rates_are_not():
    class Plant:  # what the runner reads of a dynamic plant: its true body velocity
        body_velocity = np.zeros(6)

    channel = Sensors(delay=0.1).channel(MODEL, 0.1)
    plant = Plant()
    qs = configurations(3)
    for k, q in enumerate(qs):
        plant.body_velocity = np.full(6, 0.1 * k)
        state = _measured_state(MODEL, plant, channel, MODEL.state(q))
        np.testing.assert_array_equal(state.q, qs[max(0, k - 1)])
        np.testing.assert_array_equal(state.velocity, np.full(6, 0.1 * max(0, k - 1)))
    # the velocity loop's reading: the current velocity (noise only)
    np.testing.assert_array_equal(channel.body_velocity(plant.body_velocity), np.full(6, 0.2))


def test_pose_noise_has_the_stated_standard_deviation_and_joints_stay_in_their_limits():
    sensors = Sensors(position_noise=0.02, attitude_noise=0.01, joint_noise=0.05, seed=7)
    channel = sensors.channel(MODEL, 0.1)
    q = MODEL.configuration([1.0, 2.0, 3.0, 0.1, -0.1, 0.5], [0.0, 1.0, 1.7, 3.1])
    eta0, _ = MODEL.split(q)
    draws = [MODEL.split(channel.pose(q)) for _ in range(4000)]
    eta = np.array([d[0] for d in draws]) - eta0
    joints = np.array([d[1] for d in draws])
    np.testing.assert_allclose(eta[:, :3].std(axis=0), 0.02, rtol=0.06)
    np.testing.assert_allclose(eta[:, 3:].std(axis=0), 0.01, rtol=0.06)
    assert np.all(joints >= MODEL.joint_lower) and np.all(joints <= MODEL.joint_upper)
    # a joint far from its limits shows the full spread; one at its lower limit is clipped
    assert joints[:, 2].std() == pytest.approx(0.05, rel=0.06)
    assert joints[:, 0].min() == MODEL.joint_lower[0]


def test_velocity_noise_per_axis_and_repeatability_from_the_seed():
    sensors = Sensors(linear_rate_noise=0.01, angular_rate_noise=0.002, seed=11)
    a = sensors.channel(MODEL, 0.1)
    b = sensors.channel(MODEL, 0.1)
    nu = np.zeros(6)
    first = np.array([a.body_velocity(nu) for _ in range(3000)])
    np.testing.assert_allclose(first.std(axis=0), [0.01] * 3 + [0.002] * 3, rtol=0.06)
    again = np.array([b.body_velocity(nu) for _ in range(3000)])
    np.testing.assert_array_equal(first, again)
    other = Sensors(linear_rate_noise=0.01, angular_rate_noise=0.002, seed=12).channel(MODEL, 0.1)
    assert not np.array_equal(first[0], other.body_velocity(nu))


@pytest.mark.parametrize(("kwargs", "culprit"), [
    ({"position_noise": -0.1}, "position_noise"),
    ({"delay": float("nan")}, "delay"),
    ({"seed": True}, "seed"),
    ({"seed": -1}, "seed"),
])
def test_bad_sensor_settings_are_refused_naming_the_field(kwargs, culprit):
    with pytest.raises(InputError, match=culprit):
        Sensors(**kwargs)


def test_a_sensors_table_with_a_bad_key_is_a_config_error_at_its_path():
    data = tomllib.loads(STILL + "\n[sensors]\nposition_noize = 0.1\n")
    with pytest.raises(ConfigError, match=r"^sensors\.position_noize: unknown key"):
        scenario_from_dict(data)
    data = tomllib.loads(STILL + "\n[sensors]\ndelay = -1.0\n")
    with pytest.raises(ConfigError, match=r"^sensors\.delay"):
        scenario_from_dict(data)


def test_exact_sensors_change_nothing_in_a_run():
    plain = scenario_from_dict(tomllib.loads(STILL))
    sensed = scenario_from_dict(tomllib.loads(STILL + "\n[sensors]\nseed = 4\n"))
    a, b = simulate(plain), simulate(sensed)
    np.testing.assert_array_equal(a.zeta, b.zeta)
    np.testing.assert_array_equal(a.q, b.q)


def test_a_delayed_controller_repeats_its_first_command_until_the_first_move_is_measured():
    # a fixed target and no command-rate bound: the command is a function of the measured state,
    # so with a delay of two periods the commands of steps 0, 1 and 2 are those of q0 alike
    base = scenario_from_dict(tomllib.loads(STILL))
    late = dataclasses.replace(base, sensors=Sensors(delay=0.2))
    run = simulate(late)
    np.testing.assert_array_equal(run.zeta[0], run.zeta[1])
    np.testing.assert_array_equal(run.zeta[0], run.zeta[2])
    assert not np.array_equal(run.zeta[2], run.zeta[3])
    exact = simulate(base)
    np.testing.assert_array_equal(exact.zeta[0], run.zeta[0])
    assert not np.array_equal(exact.zeta[1], run.zeta[1])
    # the recorded configuration is the true one: the first state and the plant's own motion
    np.testing.assert_array_equal(run.q[0], base.q0)
    np.testing.assert_allclose(run.q[1], base.model.integrate(base.q0, run.zeta[0], base.dt))
