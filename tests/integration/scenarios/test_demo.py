"""The bundled demo, end to end through ``uvms-qp run``: its promises as numbers in results.json.

BlueROV2 Heavy + Reach Alpha 5, a tool path first inside the arm's workspace, then far beyond it,
a 20 N payload picked up at t = 15 s, a current at 0.2 rad, six mission tasks and all hard bounds
(the change of the command per period included).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from uvms_qp.cli import main
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario

FLOOR = 0.001  # manipulability floor of the demo [m^3]
MARGIN = 0.1  # joint margin of the demo [rad]
PAYLOAD_MAX = 0.6  # payload-moment bound of the demo [N m^2]
HEADING = 0.2  # current direction [rad]


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["run", "bluerov2_demo", "--out", str(out), "--quiet"]) == 0
    with (out / "results.json").open() as handle:
        return out, json.load(handle)


def test_results_schema_and_figures(demo):
    out, results = demo
    for key in ("scenario", "scheme", "solver", "dt", "steps", "metrics", "series"):
        assert key in results
    assert results["scenario"] == "bluerov2_demo"
    assert results["scheme"] == "hqp" and results["solver"] == "daqp"
    assert results["steps"] == 600 and results["dt"] == 0.05
    for key in ("ee_error_max", "ee_error_rms", "min_manipulability", "vehicle_displacement_max",
                "vehicle_yaw_error_final", "joint_limit_violation_max", "bound_violation_max",
                "payload_moment_max", "step_time_median_us", "step_time_p99_us", "nan_steps"):
        assert results["metrics"][key] is not None, key
    series = results["series"]
    assert len(series["time"]) == 601 and len(series["zeta"]) == 600
    assert np.asarray(series["q"]).shape == (601, 11)
    assert np.asarray(series["vehicle_pose"]).shape == (601, 6)
    assert np.asarray(series["ee_pose"]).shape == (601, 7)
    assert len(series["manipulability"]) == 601
    for name in ("tool_tracking", "vehicle_pose", "joints", "manipulability", "rates",
                 "residuals", "payload_moment"):
        assert (out / f"{name}.png").stat().st_size > 10_000


def test_metrics_agree_with_the_recorded_series(demo):
    _, results = demo
    series, metrics = results["series"], results["metrics"]
    ee = np.asarray(series["ee_pose"])[:, :3]
    target = np.asarray(series["target_position"])
    error = np.linalg.norm(ee - target, axis=1)
    assert metrics["ee_error_max"] == pytest.approx(error.max(), rel=1e-12)
    assert metrics["ee_error_rms"] == pytest.approx(np.sqrt(np.mean(error**2)), rel=1e-12)
    zeta = np.asarray(series["zeta"])
    lower = np.asarray([[-np.inf if v is None else v for v in row] for row in series["zeta_lower"]])
    upper = np.asarray([[np.inf if v is None else v for v in row] for row in series["zeta_upper"]])
    box = np.maximum(lower - zeta, 0.0) + np.maximum(zeta - upper, 0.0)
    assert box.max() <= metrics["bound_violation_max"] + 1e-15
    # every actuated DOF has a finite hard bound in the demo (all hard bounds in use)
    assert np.isfinite(lower).all() and np.isfinite(upper).all()
    pose = np.asarray(series["vehicle_pose"])
    displacement = np.linalg.norm(pose[:, :3] - pose[0, :3], axis=1)
    assert metrics["vehicle_displacement_max"] == pytest.approx(displacement.max(), rel=1e-9)
    assert metrics["min_manipulability"] == pytest.approx(min(series["manipulability"]))


def test_safe_every_step(demo):
    _, results = demo
    metrics = results["metrics"]
    assert metrics["nan_steps"] == 0
    assert metrics["bound_violation_max"] <= 1e-7
    assert metrics["joint_limit_violation_max"] == 0.0
    assert set(metrics["status_counts"]) <= {"optimal"}


def test_tool_tracks_the_path(demo):
    _, results = demo
    phases = results["phases"]
    assert phases["within_reach"]["ee_error_max"] < 1e-3  # [m]
    assert phases["after_pickup"]["ee_error_max"] < 1e-3
    # beyond reach the vehicle (rate-limited to 0.3 m/s) carries the arm: still within 5 mm
    assert results["metrics"]["ee_error_max"] < 5e-3
    assert results["metrics"]["ee_error_final"] < 1e-5


def test_vehicle_moves_only_when_the_arm_needs_it(demo):
    _, results = demo
    reach, beyond = results["phases"]["within_reach"], results["phases"]["beyond_reach"]
    # [m, m/s]: the arm follows the path; the vehicle only helps at the path's corners, where
    # the joints' acceleration bound binds
    assert reach["vehicle_displacement_max"] < 1e-3
    assert reach["vehicle_speed_max"] < 1e-2
    assert beyond["vehicle_displacement_max"] > 0.4  # [m]
    assert beyond["vehicle_speed_max"] == pytest.approx(0.3, abs=0.02)  # at its rate bound


def test_the_command_changes_no_faster_than_the_actuators_follow(demo):
    """The demo's command-rate bound: per period, each joint rate changes by at most
    1 rad/s^2 * dt, each vehicle rate by at most 0.6 (m/s^2 or rad/s^2) * dt, from rest, the
    payload pick-up at 15 s included."""
    _, results = demo
    zeta = np.asarray(results["series"]["zeta"])
    change = np.abs(np.diff(np.vstack([np.zeros(zeta.shape[1]), zeta]), axis=0)) / results["dt"]
    assert change[:, :6].max() <= 0.6 + 1e-9
    assert change[:, 6:].max() <= 1.0 + 1e-9


def test_beyond_reach_part_is_really_out_of_the_arms_reach():
    scenario = load_scenario("bluerov2_demo")
    model = scenario.model
    pin_model = model.pin_model
    # triangle inequality along the chain: from the vehicle origin, the tool is never farther
    # than the sum of the joint offsets and the tool offset
    bound = sum(
        np.linalg.norm(pin_model.jointPlacements[pin_model.getJointId(name)].translation)
        for name in model.joint_names
    )
    tool = pin_model.frames[pin_model.getFrameId("tool")]
    bound += np.linalg.norm(tool.placement.translation)
    vehicle = model.state(scenario.q0).position("vehicle")
    far = scenario.trajectories["tool_path"].sample(15.0).position
    assert np.linalg.norm(far - vehicle) > 1.5 * bound
    # and the within-reach part stays near the start (where the arm alone tracked it)
    near = [scenario.trajectories["tool_path"].sample(t).position for t in np.linspace(0, 10, 41)]
    assert max(np.linalg.norm(p - vehicle) for p in near) < bound


def test_margins_floor_payload_heading(demo):
    _, results = demo
    metrics, phases = results["metrics"], results["phases"]
    assert metrics["min_manipulability"] >= FLOOR * (1 - 1e-2)
    assert metrics["joint_margin_min"] >= MARGIN - 1e-3  # [rad]
    # no payload before the pick-up; the moment jumps at pick-up then falls to its bound
    assert phases["within_reach"]["payload_moment_max"] == 0.0
    after = phases["after_pickup"]
    assert after["payload_objective_start"] > 2.0 * PAYLOAD_MAX
    assert after["payload_objective_final"] <= PAYLOAD_MAX * 1.01
    assert after["payload_objective_final"] < 0.4 * after["payload_objective_start"]
    # the physical moment F |(x_E, y_E)| [N m] is the square root of objective * F: it drops too
    assert after["payload_moment_final"] < after["payload_moment_start"]
    assert results["events"] == [{"time": 15.0, "task": "payload", "update": {"force": 20.0}}]
    # the heading starts 0.2 rad away and converges to the current
    assert phases["within_reach"]["vehicle_yaw_error_max"] == pytest.approx(HEADING)
    assert metrics["vehicle_yaw_error_final"] < 1e-3  # [rad]


@pytest.mark.parametrize("solver", ["cascade:quadprog", "cascade:piqp"])
def test_demo_start_is_safe_with_cascades(solver):
    scenario = load_scenario("bluerov2_demo")
    result = simulate(scenario, scenario.make_controller(solver), duration=6.0)
    metrics = result.metrics()
    assert metrics["nan_steps"] == 0
    assert metrics["bound_violation_max"] <= 1e-7
    assert result.phase_metrics()["within_reach"]["ee_error_max"] < 1e-3
