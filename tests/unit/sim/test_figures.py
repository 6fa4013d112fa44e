"""Figures of a run and of a comparison: what each panel says, for every kind of model.

Read through the matplotlib objects (axis labels, lines, limits, text extents), not only the files.
"""

from __future__ import annotations

import os
from importlib import resources

import matplotlib.pyplot as plt
import numpy as np
import pytest

from tests.support.short_scenarios import bundled_scenarios, short_steps
from uvms_qp.cli import main
from uvms_qp.sim import _figures
from uvms_qp.sim._figures import PAYLOAD_LABEL, RATE_WINDOW_LABEL, event_label
from uvms_qp.sim.comparison import compare
from uvms_qp.sim.comparison_figures import comparison_figure_objects, comparison_figures
from uvms_qp.sim.dynamic_figures import dynamic_builders
from uvms_qp.sim.plots import POSITION_SPAN, plot_results, run_figures
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario


def _run(name, steps, directory):
    scenario = load_scenario(short_steps(name, steps, directory))
    return scenario, simulate(scenario)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    directory = tmp_path_factory.mktemp("scenarios")
    return {
        "spatial": _run("bluerov2_demo", 30, directory),
        "planar": _run("paper000_quintic", 60, directory),
        "held": _run("paper001_circle", 20, directory),
        "fixed": _run("paper002_line_self_motion", 40, directory),
    }


@pytest.fixture
def figures():
    opened = []

    def make(result):
        figs = run_figures(result)
        opened.extend(figs.values())
        return figs

    yield make
    for fig in opened:
        plt.close(fig)


def _visible(fig):
    return [ax for ax in fig.axes if ax.axison]


def _labels_inside(fig):
    """Every axis label and title lies inside the canvas (nothing is clipped)."""
    _figures.lay_out(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    texts = [t for ax in _visible(fig) for t in (ax.xaxis.label, ax.yaxis.label, ax.title)]
    texts += [t for t in fig.texts]
    for text in texts:
        if not text.get_text():
            continue
        extent = text.get_window_extent(renderer)
        assert extent.x0 >= box.x0 - 1 and extent.x1 <= box.x1 + 1, text.get_text()
        assert extent.y0 >= box.y0 - 1 and extent.y1 <= box.y1 + 1, text.get_text()


def test_fixed_base_run_writes_its_figures_without_a_vehicle(runs, tmp_path):
    _, result = runs["fixed"]
    paths = plot_results(result, tmp_path)
    assert sorted(p.name for p in paths) == ["joints.png", "manipulability.png", "rates.png",
                                             "residuals.png", "tool_tracking.png"]
    for path in paths:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_rates_give_each_axis_its_unit_and_the_time(runs, figures):
    scenario, result = runs["spatial"]
    fig = figures(result)["rates.png"]
    axes = _visible(fig)
    expected = [f"{n} [{'m/s' if n in 'uvw' else 'rad/s'}]" for n in scenario.model.zeta_names]
    assert [ax.get_ylabel() for ax in axes] == expected
    columns: dict[float, list] = {}
    for ax in axes:
        columns.setdefault(round(ax.get_position().x0, 3), []).append(ax)
    assert len(columns) == 2
    for column in columns.values():
        lowest = min(column, key=lambda ax: ax.get_position().y0)
        assert lowest.get_xlabel() == "t [s]"
        assert any(label.get_visible() and label.get_text()
                   for label in lowest.get_xticklabels())


def test_rates_draw_the_command_and_its_hard_box(runs, figures):
    _, result = runs["spatial"]
    ax = _visible(figures(result)["rates.png"])[0]
    command, lower, upper = ax.get_lines()[:3]
    np.testing.assert_array_equal(command.get_ydata(), result.zeta[:, 0])
    np.testing.assert_array_equal(lower.get_ydata(), result.zeta_lower[:, 0])
    np.testing.assert_array_equal(upper.get_ydata(), result.zeta_upper[:, 0])
    assert ax.collections, "the hard box is shaded"


def test_prismatic_joint_rates_are_in_metres_per_second(tmp_path):
    from uvms_qp.model import Model
    from uvms_qp.model.dh import DHRow
    from uvms_qp.model.vehicle import Vehicle
    from uvms_qp.sim.units import joint_units, zeta_units

    model = Model.from_dh([DHRow(a=1.0), DHRow(kind="prismatic", lower=0.0, upper=1.0)],
                          "standard", vehicle=Vehicle("planar"))
    assert zeta_units(model) == ("m/s", "m/s", "rad/s", "rad/s", "m/s")
    assert joint_units(model) == ("rad", "m")


def test_manipulability_has_its_unit_and_the_floor(runs, figures):
    scenario, result = runs["spatial"]
    ax = figures(result)["manipulability.png"].axes[0]
    assert ax.get_ylabel() == "manipulability w [m$^{3}$]"
    floors = [line for line in ax.get_lines() if line.get_label() == "floor"]
    assert len(floors) == 1
    minimum = next(t.minimum for t in scenario.build_stack().tasks
                   if t.type_name == "manipulability")
    np.testing.assert_allclose(floors[0].get_ydata(), minimum)
    assert ax.get_xlabel() == "t [s]"


def test_joints_title_mentions_limits_only_when_there_are_some(runs, figures):
    limited = figures(runs["spatial"][1])["joints.png"]
    free = figures(runs["fixed"][1])["joints.png"]
    assert "(dashed: limits)" in limited.texts[0].get_text()
    assert "limits" not in free.texts[0].get_text()
    assert all(len(ax.get_lines()) == 1 for ax in free.axes)  # no limit lines at +-inf


def test_planar_model_has_no_z_panel(runs, figures):
    figs = figures(runs["planar"][1])
    assert [ax.get_ylabel() for ax in figs["tool_tracking.png"].axes] == [
        "x [m]", "y [m]", "|error| [m]"]
    position = figs["vehicle_pose.png"].axes[0]
    assert [line.get_label() for line in position.get_lines()] == ["x", "y"]


def test_a_vehicle_held_in_place_is_drawn_flat_not_as_rounding_noise(runs, figures):
    _, result = runs["held"]
    moved = np.ptp(result.vehicle_position[:, :2], axis=0).max()
    assert moved < 1e-9  # the scheme holds the vehicle: what is left is rounding
    low, high = figures(result)["vehicle_pose.png"].axes[0].get_ylim()
    assert high - low >= POSITION_SPAN - 1e-12


def test_levels_are_numbered_from_0_as_in_summaries(runs, figures):
    scenario, result = runs["spatial"]
    ax = figures(result)["residuals.png"].axes[0]
    labels = [line.get_label() for line in ax.get_lines()]
    assert labels[0].startswith("level 0 (")
    levels = [int(label.split()[1]) for label in labels]
    assert levels == sorted(levels) and max(levels) < len(scenario.build_stack().levels)


@pytest.mark.parametrize("kind", ["spatial", "planar", "fixed"])
def test_run_figures_have_no_clipped_labels(runs, figures, kind):
    for fig in figures(runs[kind][1]).values():
        _labels_inside(fig)


def _legend_texts(fig):
    return {text.get_text() for ax in fig.axes if ax.get_legend() is not None
            for text in ax.get_legend().get_texts()}


@pytest.fixture(scope="module")
def pick_up_runs(tmp_path_factory):
    """The demo for 1 s with its payload picked up at 0.5 s: on the kinematic and the dynamic
    plant (command-rate bounds, an event, the payload's attachment)."""
    text = resources.files("uvms_qp.scenarios").joinpath("bluerov2_demo.toml").read_text()
    text = text.split("[[phases]]")[0].replace("duration = 30.0", "duration = 1.0")
    assert text.count("time = 15.0") == 2  # the event and the plant's payload
    path = tmp_path_factory.mktemp("pick_up") / "pick_up.toml"
    path.write_text(text.replace("time = 15.0", "time = 0.5"))
    scenario = load_scenario(path)
    return simulate(scenario), simulate(scenario.with_plant("dynamic"))


def test_event_lines_and_the_command_rate_window_are_named_in_every_figure_that_draws_them(
        pick_up_runs, figures):
    kinematic, dynamic = pick_up_runs
    [event] = kinematic.events
    assert event["task"] == "payload" and dynamic.dynamics.payload_time == pytest.approx(0.5)
    label = event_label(event)
    assert label == "event 0.5 s: payload force = 20"
    dynamic_names = {name for name, _ in dynamic_builders(dynamic)}
    assert dynamic_names == {"thrusters.png", "velocity_tracking.png",
                             "attitude_disturbance.png", "joint_torques.png"}
    for result in (kinematic, dynamic):
        for name, fig in figures(result).items():
            lines = [line for ax in fig.axes for line in ax.get_lines()]
            drawn = {line.get_label() for line in lines}
            named = _legend_texts(fig)
            assert label in drawn and label in named, name  # every figure marks the event
            if name in dynamic_names:
                assert PAYLOAD_LABEL in drawn and PAYLOAD_LABEL in named, name
            if name == "rates.png":
                assert RATE_WINDOW_LABEL in drawn and RATE_WINDOW_LABEL in named
            # no vertical dotted line without a name in the legend
            for line in lines:
                x = np.asarray(line.get_xdata(), dtype=float)
                if line.get_linestyle() == ":" and x.size == 2 and x[0] == x[1]:
                    assert line.get_label() in named, (name, line.get_label())


# --- writing ------------------------------------------------------------------------------------


def test_a_figure_path_that_is_a_link_is_replaced_not_followed(runs, tmp_path):
    outside = tmp_path / "precious.txt"
    outside.write_text("keep me")
    out = tmp_path / "out"
    out.mkdir()
    (out / "rates.png").symlink_to(outside)
    paths = plot_results(runs["fixed"][1], out)
    assert outside.read_text() == "keep me"
    assert not (out / "rates.png").is_symlink()
    assert (out / "rates.png").read_bytes()[:4] == b"\x89PNG"
    assert out / "rates.png" in paths
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in paths)  # no temp left


def test_cli_outputs_never_write_through_links_in_out(tmp_path):
    scenario = short_steps("paper001_circle", 10, tmp_path)
    outside = tmp_path / "outside.txt"
    outside.write_text("keep me")
    run_dir, cmp_dir = tmp_path / "run", tmp_path / "cmp"
    run_dir.mkdir()
    cmp_dir.mkdir()
    links = [run_dir / "tool_tracking.png", run_dir / "results.json", cmp_dir / "rates.png",
             cmp_dir / "comparison.md", cmp_dir / "comparison.json"]
    for link in links:
        link.symlink_to(outside)
    assert main(["run", str(scenario), "--out", str(run_dir), "--quiet"]) == 0
    assert main(["compare", str(scenario), "--out", str(cmp_dir), "--quiet",
                 "--schemes", "hqp"]) == 0
    assert outside.read_text() == "keep me"
    for link in links:
        assert link.is_file() and not link.is_symlink()


def test_figures_are_world_readable(runs, tmp_path):
    for path in plot_results(runs["fixed"][1], tmp_path):
        assert os.stat(path).st_mode & 0o777 == 0o644


def test_figure_progress_is_reported_once_writing_takes_long(runs, tmp_path, capsys,
                                                             monkeypatch):
    monkeypatch.setattr(_figures, "PROGRESS_AFTER", 0.0)
    paths = plot_results(runs["fixed"][1], tmp_path, progress=True)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == len(paths)
    assert err[0].startswith(f"paper002_line_self_motion figures: 1/{len(paths)} ")
    monkeypatch.setattr(_figures, "PROGRESS_AFTER", 1e9)
    plot_results(runs["fixed"][1], tmp_path, progress=True)
    assert capsys.readouterr().err == ""


# --- comparison ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def payload_comparison(tmp_path_factory):
    scenario = load_scenario(short_steps("paper003_case3_payload", 40,
                                         tmp_path_factory.mktemp("cmp")))
    comparison = compare(scenario)
    figs = comparison_figure_objects(comparison, scenario.model)
    yield scenario, comparison, figs
    for fig in figs.values():
        plt.close(fig)


def test_compare_overlays_tool_tracking_of_every_scheme_and_the_target(payload_comparison):
    _, comparison, figs = payload_comparison
    axes = figs["tool_tracking.png"].axes
    assert [ax.get_ylabel() for ax in axes] == ["x [m]", "y [m]", "z [m]", "|error| [m]"]
    names = [line.get_label() for line in axes[0].get_lines()]
    assert names == [run.name for run in comparison.runs] + ["target"]
    for run, line in zip(comparison.runs, axes[0].get_lines(), strict=False):
        np.testing.assert_array_equal(line.get_ydata(), run.result.ee_position[:, 0])


def test_compare_overlays_the_payload_moment(payload_comparison):
    _, comparison, figs = payload_comparison
    ax = figs["payload_moment.png"].axes[0]
    assert [line.get_label() for line in ax.get_lines()] == [r.name for r in comparison.runs]
    assert ax.get_ylabel() == "payload moment [N m]"


def test_compare_draws_the_command_of_every_scheme_with_its_box(payload_comparison):
    scenario, comparison, figs = payload_comparison
    axes = _visible(figs["rates.png"])
    assert [ax.get_ylabel().split()[0] for ax in axes] == list(scenario.model.zeta_names)
    assert axes[0].get_ylabel() == "u [m/s]" and axes[-1].get_ylabel().endswith("[rad/s]")
    labels = [line.get_label() for line in axes[0].get_lines()]
    assert labels[: len(comparison.runs)] == [run.name for run in comparison.runs]


def test_compare_figures_have_no_clipped_labels(payload_comparison):
    for fig in payload_comparison[2].values():
        _labels_inside(fig)


def test_planar_configurations_put_x_to_the_right_and_y_up(tmp_path):
    scenario = load_scenario(short_steps("paper000_quintic", 30, tmp_path))
    comparison = compare(scenario, ["hqp"])
    fig = dict(comparison_figures(comparison, scenario.model))["configurations.png"]()
    try:
        ax = fig.axes[0]
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [m]", "y [m]")
        assert not ax.xaxis_inverted() and not ax.yaxis_inverted()
        state = scenario.model.state(comparison.runs[0].result.q[-1])
        tool = state.position("tool")
        arm = ax.get_lines()[-3]  # the last snapshot: arm, mount, then the target path
        xs, ys = np.asarray(arm.get_xdata()), np.asarray(arm.get_ydata())
        assert np.nanmax(np.abs(xs - tool[0]) + np.abs(ys - tool[1])) > 0  # not a point
        assert np.any(np.isclose(xs, tool[0]) & np.isclose(ys, tool[1]))
        _labels_inside(fig)
    finally:
        plt.close(fig)


@pytest.mark.slow
@pytest.mark.parametrize("name", bundled_scenarios())
def test_every_bundled_scenario_runs_and_compares_with_figures(name, tmp_path, capsys):
    duration = str(25 * load_scenario(name).dt)  # the bundled file as shipped, 25 steps of it
    assert main(["run", name, "--out", str(tmp_path / "run"), "--duration", duration]) == 0
    assert main(["compare", name, "--out", str(tmp_path / "cmp"), "--duration", duration]) == 0
    assert "Traceback" not in capsys.readouterr().err
    assert (tmp_path / "run" / "rates.png").is_file()
    assert (tmp_path / "cmp" / "rates.png").is_file()
