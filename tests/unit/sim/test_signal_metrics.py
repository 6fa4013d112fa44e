"""The command as a signal: reversals per second, command change per step, settling times, and
where they appear (results.json, comparison table, command-rate window on rates.png)."""

from __future__ import annotations

import json
import tomllib
from types import SimpleNamespace

import numpy as np
import pytest

from tests.support.scenario_text import bluerov_scenario
from uvms_qp.cli.run import _summary
from uvms_qp.controller.history import command_reversals
from uvms_qp.sim.comparison import Comparison, SchemeRun
from uvms_qp.sim.metrics import axis_bounds, command_change_max, reversal_metrics, settling_time
from uvms_qp.sim.plots import run_figures
from uvms_qp.sim.results import write_results
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import scenario_from_dict


def test_a_command_banging_between_its_bounds_reverses_every_step():
    z = np.tile([[0.3], [-0.3]], (10, 1))
    assert command_reversals(z, np.array([0.3]))[0] == 19


def test_noise_below_one_percent_of_the_bound_is_not_a_reversal():
    rng = np.random.default_rng(1)
    z = np.concatenate([np.full(5, 0.2), rng.uniform(-0.0049, 0.0049, 40), np.full(5, 0.2)])
    assert command_reversals(z[:, None], np.array([0.5]))[0] == 0
    z[24:27] = [0.2, -0.2, 0.2]  # one real kick: there and back
    assert command_reversals(z[:, None], np.array([0.5]))[0] == 2


def test_a_change_of_direction_through_small_commands_is_not_a_reversal():
    smooth = np.array([0.3, 0.2, 0.001, -0.002, 0.0, -0.1, -0.3])[:, None]
    assert command_reversals(smooth, np.array([0.3]))[0] == 0
    abrupt = np.array([0.3, 0.2, -0.1, -0.3])[:, None]
    assert command_reversals(abrupt, np.array([0.3]))[0] == 1


def test_axis_bounds_use_the_finite_sides_or_the_signal():
    zeta = np.array([[0.1, 0.2], [0.05, -0.4], [0.0, 0.1]])
    lower = np.array([[-0.5, -np.inf], [-0.5, -np.inf], [-0.2, -np.inf]])
    upper = np.array([[np.inf, np.inf], [0.5, np.inf], [0.5, np.inf]])
    assert np.allclose(axis_bounds(zeta, lower, upper), [0.5, 0.4])


def test_command_change_is_per_unit_and_from_rest():
    result = SimpleNamespace(zeta=np.array([[0.1, 0.0, 0.2], [0.3, 0.5, 0.1]]), dt=0.1,
                             zeta_units=("m/s", "rad/s", "rad/s"))
    assert command_change_max(result) == pytest.approx({"m/s^2": 2.0, "rad/s^2": 5.0})


def test_the_worst_axis_is_none_when_no_entry_reverses():
    zeta = np.zeros((20, 2))
    zeta[:, 0] = 0.2
    result = SimpleNamespace(zeta=zeta, zeta_names=("u", "axis_e"), dt=0.1,
                             zeta_lower=np.full((20, 2), -0.5), zeta_upper=np.full((20, 2), 0.5))
    steps = np.ones(20, dtype=bool)
    quiet = reversal_metrics(result, steps)
    assert quiet["command_reversals_per_s_max"] == 0.0
    assert quiet["command_reversals_worst_axis"] is None
    zeta[10:, 1] = [0.3, -0.3] * 5  # the second entry bangs for 10 steps: 9 sign changes
    loud = reversal_metrics(result, steps)
    assert loud["command_reversals_worst_axis"] == "axis_e"
    assert loud["command_reversals_per_s_max"] == pytest.approx(9 / 2.0)
    assert "(" not in _summary(quiet) and "4.5 (axis_e) 1/s" in _summary(loud)

def test_settling_time():
    t = np.arange(6.0)
    assert settling_time(t, np.array([1.0, 0.5, 0.1, 0.015, 0.03, 0.01])) == 5.0
    assert settling_time(t, np.array([1.0, 0.5, 0.1, 0.015, 0.01, 0.0])) == 3.0
    assert settling_time(t, np.array([1.0, 0.5, 0.5, 0.5, 0.5, 0.5])) is None
    assert settling_time(t, np.zeros(6)) == 0.0
    assert settling_time(t, np.full(6, np.nan)) is None


@pytest.fixture(scope="module")
def accel_run():
    """The BlueROV2 tool reach at dt 0.1 s with command-rate bounds (2 s)."""
    text = bluerov_scenario("duration = 2.0", """
[[constraints]]
type = "command_rate_bounds"
joint = 1.0
linear = 0.5
angular = 0.5
""")
    return simulate(scenario_from_dict(tomllib.loads(text), name="accel"))


def test_run_metrics_match_the_series(accel_run, tmp_path):
    data = json.loads(write_results(accel_run, tmp_path).read_text())
    metrics, series = data["metrics"], data["series"]
    zeta = np.array(series["zeta"])
    change = np.abs(np.diff(zeta, axis=0, prepend=0.0)) / data["dt"]
    assert metrics["command_change_max"]["rad/s^2"] == pytest.approx(change[:, 3:].max())
    assert metrics["command_change_max"]["m/s^2"] == pytest.approx(change[:, :3].max())
    # the bounds held: from rest, at most a_max per entry (the position box never tightened)
    assert change[:, :3].max() <= 0.5 + 1e-9 and change[:, 6:].max() <= 1.0 + 1e-9
    assert series["command_rate_limit"] == [0.5] * 6 + [1.0] * 4
    rates = metrics["command_reversals_per_s"]
    assert set(rates) == set(series["zeta_names"])
    worst = metrics["command_reversals_worst_axis"]
    assert metrics["command_reversals_per_s_max"] == max(rates.values())
    assert worst is None if max(rates.values()) == 0.0 else rates[worst] == max(rates.values())
    errors = series["task_errors"]["tool"]
    assert len(errors) == data["steps"] + 1 and series["task_error_units"]["tool"] == "m"
    assert errors[0] == pytest.approx(np.linalg.norm(
        np.array(series["target_position"][0]) - series["ee_pose"][0][:3]), rel=1e-9)
    assert set(metrics["settling_time"]) == {"tool"}


def test_rates_figure_draws_the_command_rate_window(accel_run):
    fig = run_figures(accel_run)["rates.png"]
    ax = fig.axes[6]  # the first joint
    dotted = [line for line in ax.get_lines() if line.get_linestyle() == ":"]
    assert len(dotted) == 2
    previous = np.concatenate([[0.0], accel_run.zeta[:-1, 6]])
    assert np.allclose(dotted[1].get_ydata(), previous + 1.0 * accel_run.dt)
    assert "command-rate window" in fig.texts[0].get_text()


def test_comparison_table_expands_per_unit_and_per_task():
    runs = [SchemeRun(name, None, {}, metrics) for name, metrics in (  # type: ignore[arg-type]
        ("hqp", {"command_change_max": {"m/s^2": 1.0, "rad/s^2": 2.0},
                 "settling_time": {"tool": 3.0}, "command_reversals_per_s_max": 0.25}),
        ("other", {"command_change_max": {"rad/s^2": 4.0}, "settling_time": {"tool": None}}),
    )]
    rows = {(key, unit): values for key, unit, values in Comparison("s", "", runs).table()}
    assert rows[("command_change_max", "m/s^2")] == [1.0, None]
    assert rows[("command_change_max", "rad/s^2")] == [2.0, 4.0]
    assert rows[("settling_time (tool)", "s")] == [3.0, None]
    assert rows[("command_reversals_per_s_max", "1/s")] == [0.25, None]
