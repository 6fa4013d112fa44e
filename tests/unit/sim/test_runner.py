"""Closed-loop runner, metrics and results.json: checked against independent computations."""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass

import numpy as np
import pytest

import uvms_qp
from tests.support.scenario_text import bluerov_scenario
from uvms_qp import Level, Stack
from uvms_qp.constraints import JointVelocityBounds, VehicleRateBounds
from uvms_qp.errors import InputError, UnknownNameError
from uvms_qp.sim import runner as runner_module
from uvms_qp.sim.results import results_dict, write_results
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import Event, Phase, Scenario, scenario_from_dict
from uvms_qp.tasks import EndEffectorTask, PayloadMomentTask, StationKeepingTask

SMALL = bluerov_scenario("duration = 1.0\ntracking = \"tool\"", """
[[levels]]
[[levels.tasks]]
type = "payload_moment"
name = "payload"
mode = "bound"
maximum = 10.0

[[levels]]
[[levels.tasks]]
type = "station_keeping"

[[events]]
time = 0.3
task = "payload"
update = { force = 5.0 }

[[phases]]
name = "late"
start = 0.5
end = 1.0
""")


@pytest.fixture
def small():
    return scenario_from_dict(tomllib.loads(SMALL))


def test_events_fire_at_their_step_and_series_follow(small):
    result = simulate(small)
    assert result.steps == 10
    assert result.events == [{"time": pytest.approx(0.3), "task": "payload",
                              "update": {"force": 5.0}}]
    moment = result.payload_moment
    assert np.all(moment[:3] == 0.0) and np.all(moment[3:] > 0.0)
    # independent values from the tool in the arm-base frame: the Eq. (20) objective
    # (x^2 + y^2) F [N m^2] and the physical moment F sqrt(x^2 + y^2) [N m]
    state = small.model.state(result.q[5])
    p = state.pose_in("tool", "arm_base")[:3, 3]
    assert result.payload_objective[5] == pytest.approx((p[0] ** 2 + p[1] ** 2) * 5.0, rel=1e-12)
    assert moment[5] == pytest.approx(5.0 * np.hypot(p[0], p[1]), rel=1e-12)
    # the tool holds its initial position (rounded to 0.1 mm in the file)
    assert result.metrics()["ee_error_max"] < 1e-4
    assert result.metrics()["vehicle_displacement_max"] < 1e-9
    assert set(result.phase_metrics()) == {"late"}


def test_each_run_builds_fresh_tasks(small):
    stack = small.build_stack()
    first = simulate(small, stack=stack)
    assert stack.task("payload").force == 5.0  # the event fired on this run's task
    fresh = small.build_stack()
    assert fresh.task("payload").force == 0.0
    assert fresh.task("payload") is not stack.task("payload")
    second = simulate(small)  # starts again without the event applied
    np.testing.assert_array_equal(second.payload_moment, first.payload_moment)


@dataclass
class _Step:
    zeta: np.ndarray
    status: str = "custom"
    step_time: float = 1e-5


class _ConstantScheme:
    """A scheme returning a fixed command (to check the runner's own accounting)."""

    def __init__(self, zeta):
        self.zeta = np.asarray(zeta, dtype=float)
        self.resets = 0

    def reset(self):
        self.resets += 1

    def step(self, state, t):
        return _Step(self.zeta.copy())


def test_bound_violation_is_measured_independently(small):
    # vehicle rate bound 0.2 m/s, joint rate limit 0.5 rad/s: command 0.5 m/s and 0.8 rad/s
    zeta = np.zeros(10)
    zeta[0] = 0.5
    zeta[7] = 0.8
    scheme = _ConstantScheme(zeta)
    result = simulate(small, scheme, scheme_name="constant")
    assert scheme.resets == 1
    assert result.metrics()["bound_violation_max"] == pytest.approx(0.3)
    np.testing.assert_allclose(result.zeta_upper[0, :6], 0.2)
    np.testing.assert_allclose(result.zeta_upper[0, 6:], small.model.joint_rate_limit)
    # the vehicle moved at 0.5 m/s along body x for 1 s (heading 0): 0.5 m
    assert result.metrics()["vehicle_displacement_max"] == pytest.approx(0.5, rel=1e-9)
    assert result.vehicle_speed.max() == pytest.approx(0.5)


def test_non_finite_commands_are_counted_and_replaced_by_zero(small):
    zeta = np.full(10, np.nan)
    result = simulate(small, _ConstantScheme(zeta), scheme_name="broken")
    assert result.nan_steps == 10
    assert result.metrics()["nan_steps"] == 10
    np.testing.assert_array_equal(result.zeta, 0.0)
    np.testing.assert_array_equal(result.q[-1], result.q[0])


def test_duration_override_and_validation(small):
    assert simulate(small, duration=0.25).steps == 2  # round(0.25 / 0.1)
    with pytest.raises(InputError, match="duration"):
        simulate(small, duration=-1.0)


def test_progress_bar_path_runs(small, monkeypatch):
    monkeypatch.setattr(runner_module, "PROGRESS_AFTER", 0.0)
    result = simulate(small, progress=True, duration=2.0)
    assert result.steps == 20


def test_results_json_is_strict_and_atomic(small, tmp_path):
    # no tracking task: the target series is NaN and must be written as null
    data = tomllib.loads(SMALL)
    del data["tracking"]
    data["levels"] = data["levels"][1:]
    scenario = scenario_from_dict(data)
    assert scenario.tracking is None
    result = simulate(scenario)
    path = write_results(result, tmp_path / "out")
    text = path.read_text()

    def reject(constant):
        raise AssertionError(f"non-strict JSON constant {constant}")

    loaded = json.loads(text, parse_constant=reject)
    assert loaded["series"]["target_position"][0] == [None, None, None]
    assert loaded["metrics"]["ee_error_max"] is None
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["results.json"]
    assert results_dict(result, series=False).keys() >= {"scenario", "metrics", "phases"}


def test_ee_pose_quaternion_matches_rotation(small):
    result = simulate(small)
    pose = np.asarray(results_dict(result)["series"]["ee_pose"])
    x, y, z, w = pose[4, 3:]
    R = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    np.testing.assert_allclose(R, result.ee_rotation[4], atol=1e-12)


def test_scenario_built_in_code_runs_and_validates():
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    q0 = model.configuration(np.zeros(6), [math.pi, 1.2, 1.7, math.pi])
    goal = model.frame_pose(q0, "tool")[:3, 3] + np.array([0.02, 0.0, 0.0])

    def stack():
        return Stack(
            constraints=[JointVelocityBounds(), VehicleRateBounds(linear=0.2, angular=0.2)],
            levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0)),
                    Level(PayloadMomentTask(name="payload", mode="bound", maximum=1.0)),
                    Level(StationKeepingTask())],
        )

    scenario = Scenario.build(model, stack(), q0, dt=0.05, duration=3.0,
                              events=[Event(1.0, "payload", {"force": 2.0})],
                              phases=[Phase("end", 2.0, 3.0)])
    assert scenario.tracking == "tool"  # named after its frame
    result = simulate(scenario)
    assert result.phase_metrics()["end"]["ee_error_max"] < 1e-3  # exp(-2 t) convergence
    assert result.payload_moment[0] == 0.0 and result.payload_moment[-1] > 0.0
    again = simulate(scenario)  # the stack given is a template: each run has its own copy
    np.testing.assert_array_equal(again.payload_moment, result.payload_moment)
    with pytest.raises(UnknownNameError, match="unknown task 'cargo'"):
        Scenario.build(model, stack(), q0, dt=0.05, duration=1.0,
                       events=[Event(0.5, "cargo", {"force": 1.0})])
    with pytest.raises(InputError, match="dt"):
        Scenario.build(model, stack(), q0, dt=0.0, duration=1.0)


def test_rk4_closed_loop_tracks_better_than_euler():
    data = tomllib.loads(SMALL.replace('position = [0.4911, 0.0990, -0.1675]', 'trajectory = "p"')
                         + """
[trajectories.p]
type = "quintic"
start = [0.4911, 0.0990, -0.1675]
goal = [0.4611, 0.1290, -0.1475]
duration = 0.8
""")
    euler = simulate(scenario_from_dict(data)).metrics()["ee_error_max"]
    data["integrator"] = "rk4"
    rk4 = simulate(scenario_from_dict(data)).metrics()["ee_error_max"]
    assert rk4 < 0.5 * euler
