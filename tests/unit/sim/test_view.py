"""The 3-D view: the drawn geometry, the self-contained HTML page in headless Chromium, the
live matplotlib view and ``uvms-qp run --view``."""

from __future__ import annotations

import io
import json
import os
import re
import time

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest

from tests.support.browser import chromium, load_page
from tests.support.short_scenarios import short_steps
from uvms_qp.cli import main
from uvms_qp.errors import InputError
from uvms_qp.model import bundled_models, load_model
from uvms_qp.sim import view as view_module
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario
from uvms_qp.sim.view import (
    LiveView,
    RobotScene,
    plotly_available,
    replay,
    view_figure,
    write_view,
)
from uvms_qp.sim.view.scene import BOX_CORNERS, BOX_EDGES, polyline

needs_plotly = pytest.mark.skipif(not plotly_available(), reason="plotly is not installed")


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    scenario = load_scenario(short_steps("bluerov2_demo", 40, tmp_path_factory.mktemp("demo")))
    return scenario.model, simulate(scenario)


# --- geometry -----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", bundled_models())
def test_skeleton_links_the_vehicle_to_the_tool(name):
    model = load_model(name)
    scene = RobotScene(model)
    parents = {child: parent for parent, child in scene.edges}
    chain, frame = ["tool"], "tool"
    while frame in parents:
        frame = parents[frame]
        chain.append(frame)
    assert chain[-2:] == ["arm_base", "vehicle"]
    assert set(scene.frames) <= set(model.frames)
    q = model.random_configuration(np.random.default_rng(3)) if hasattr(
        model, "random_configuration") else model.home()
    positions, _ = scene.geometry(q)
    state = model.state(q)
    for frame_name, position in zip(scene.frames, positions, strict=True):
        np.testing.assert_allclose(position, state.position(frame_name), atol=1e-12)
    segments = scene.segments(positions)
    tool_edge = segments[[child for _, child in scene.edges].index("tool")]
    np.testing.assert_allclose(tool_edge[1], state.position("tool"), atol=1e-12)


@pytest.mark.parametrize("name", ["bluerov2_heavy_alpha5", "wang_9dof", "soylu_planar"])
def test_body_box_moves_with_the_vehicle(name):
    model = load_model(name)
    scene = RobotScene(model)
    q = model.random_configuration(np.random.default_rng(7))
    _, corners = scene.geometry(q)
    pose = model.state(q).pose("vehicle")
    np.testing.assert_allclose(corners.mean(axis=0), pose[:3, 3], atol=1e-12)
    # corners 0 -> 4, 0 -> 2, 0 -> 1 step along the body x, y, z axes by length, width, height
    for corner, axis, size in zip((4, 2, 1), range(3), scene.body_size, strict=True):
        np.testing.assert_allclose(corners[corner] - corners[0], size * pose[:3, axis],
                                   atol=1e-12)
    assert len(BOX_EDGES) == 12 and BOX_CORNERS.shape == (8, 3)


def test_bluerov_body_has_the_vehicle_size_and_a_fixed_base_a_plate_under_the_arm():
    assert RobotScene(load_model("bluerov2_heavy_alpha5")).body_size == (0.457, 0.575, 0.254)
    model = load_model("nenchev_pa10_arm")
    scene = RobotScene(model)
    _, corners = scene.geometry(model.home())
    assert corners[:, 2].max() == pytest.approx(0.0)  # the plate's top is the arm base
    assert scene.body_size[2] < 0.1 * scene.body_size[0]


def test_bad_body_size_is_refused():
    with pytest.raises(InputError, match="body_size"):
        RobotScene(load_model("soylu_planar"), body_size=(1.0, -1.0, 1.0))


# --- HTML ---------------------------------------------------------------------------------------


@needs_plotly
def test_view_figure_animates_every_part_up_to_the_last_state(demo):
    model, result = demo
    fig = view_figure(model, result, max_frames=12)
    assert [trace.name for trace in fig.data] == list(view_module.html.TRACES)
    assert len(fig.frames) == 12
    scene = RobotScene(model)
    positions, corners = scene.geometry(result.q[-1])
    last = fig.frames[-1]
    arm = np.array([[p if p is not None else np.nan for p in axis]
                    for axis in (last.data[3].x, last.data[3].y, last.data[3].z)]).T
    np.testing.assert_allclose(arm, polyline(scene.segments(positions)), atol=1e-12)
    np.testing.assert_allclose(np.column_stack([last.data[1].x, last.data[1].y, last.data[1].z]),
                               corners, atol=1e-12)
    assert len(last.data[0].x) == result.q.shape[0]  # the whole tool path so far
    slider = fig.layout.sliders[0]
    assert len(slider.steps) == 12 and float(slider.steps[-1].label) == pytest.approx(
        result.time_states[-1], abs=0.005)


@needs_plotly
def test_view_title_says_which_plant_ran(demo, tmp_path):
    model, result = demo
    assert "on the kinematic plant" in view_figure(model, result, max_frames=2).layout.title.text
    scenario = load_scenario(short_steps("bluerov2_demo", 4, tmp_path)).with_plant("dynamic")
    dynamic = simulate(scenario)
    assert "on the dynamic plant" in view_figure(model, dynamic, max_frames=2).layout.title.text


@needs_plotly
def test_view_refuses_a_result_of_another_model(demo):
    _, result = demo
    with pytest.raises(InputError, match="soylu_planar"):
        view_figure(load_model("soylu_planar"), result)
    with pytest.raises(InputError, match="max_frames"):
        view_figure(demo[0], result, max_frames=1)


@needs_plotly
def test_view_page_is_self_contained_and_written_safely(demo, tmp_path):
    model, result = demo
    outside = tmp_path / "elsewhere.html"
    outside.write_text("keep me")
    link = tmp_path / "run.html"
    link.symlink_to(outside)
    path = write_view(model, result, link, max_frames=10)
    assert outside.read_text() == "keep me" and not path.is_symlink()
    html = path.read_text()
    assert re.search(r"<script[^>]*\bsrc=", html) is None
    assert re.search(r"<link[^>]*\bhref=", html) is None
    assert "Plotly.newPlot" in html and "uvms-qp-view" in html
    assert os.stat(path).st_mode & 0o777 == 0o644


def _classes(png: bytes) -> tuple[int, int]:
    """Pixels of the arm's blue and of the body's orange in a screenshot."""
    rgb = matplotlib.image.imread(io.BytesIO(png), format="png")[..., :3]
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    arm = int(np.count_nonzero((b - r > 0.4) & (b - g > 0.25)))
    body = int(np.count_nonzero((r - g > 0.1) & (g - b > 0.1)))
    return arm, body


@needs_plotly
@pytest.mark.skipif(chromium() is None and not os.environ.get("CI"),
                    reason="chromium is not installed (CI installs it and runs this test)")
def test_view_page_shows_the_robot_in_chromium_without_console_errors(demo, tmp_path):
    model, result = demo
    path = write_view(model, result, tmp_path / "run.html", max_frames=20)
    div = "document.getElementById('uvms-qp-view')"

    def click(button: int, wait_ms: int) -> str:
        return ("new Promise(done => { document.querySelectorAll('#uvms-qp-view "
                f".updatemenu-button')[{button}].dispatchEvent(new MouseEvent('click', "
                f"{{bubbles: true}})); setTimeout(() => done({div}._fullLayout.sliders[0]"
                f".active), {wait_ms}); }})")

    still = "{frame: {duration: 0, redraw: true}, mode: 'immediate'}"
    started = time.perf_counter()
    report = load_page(
        path,
        ready=f"{div} && {div}.querySelector('.gl-container canvas') !== null",
        settle=0.3,
        steps=(
            # the page's own buttons: pause, back to the start, play, pause while playing (an
            # interrupted animation must not leave an error in the console)
            click(1, 50),
            f"Plotly.animate({div}, ['0'], {still}).then(() => {div}._fullLayout.sliders[0]"
            ".active)",
            click(0, 600),
            click(1, 50),
            # the last frame without the legend (its swatches share the robot's colours): what
            # is left in those colours is the WebGL scene; then the same with body and arm hidden
            f"Plotly.animate({div}, ['19'], {still}).then(() => Plotly.relayout({div}, "
            "{showlegend: false})).then(() => null)",
            f"Plotly.restyle({div}, {{visible: false}}, [2, 3, 4]).then(() => null)",
        ),
    )
    elapsed = time.perf_counter() - started
    assert report.errors == [], report.errors
    _, start, _, paused = report.values[:4]
    assert start == 0 and 0 < paused < 19, report.values  # played, then stopped by pause
    arm, body = _classes(report.shots[4])
    assert arm > 150 and body > 1500, (arm, body)
    hidden = _classes(report.shots[5])
    assert hidden[0] < 0.02 * arm and hidden[1] < 0.02 * body, hidden
    assert elapsed < 60


def _ink(png: bytes) -> np.ndarray:
    """Pixels of a screenshot that are not the page's white background."""
    rgb = matplotlib.image.imread(io.BytesIO(png), format="png")[..., :3]
    return (rgb < 0.9).any(axis=2)


@needs_plotly
@pytest.mark.skipif(chromium() is None and not os.environ.get("CI"),
                    reason="chromium is not installed (CI installs it and runs this test)")
@pytest.mark.parametrize(("width", "height"), [(1000, 700), (1600, 1000)])
def test_view_page_shows_its_whole_scene_and_controls(demo, tmp_path, width, height):
    """Nothing of the 3-D scene (the axes' cube, its tick labels and titles, the robot) reaches
    the edge of the scene's area, where WebGL would cut it, and the slider's labels end above the
    bottom of the page."""
    model, result = demo
    path = write_view(model, result, tmp_path / "run.html", max_frames=20)
    div = "document.getElementById('uvms-qp-view')"
    still = "{frame: {duration: 0, redraw: true}, mode: 'immediate'}"
    report = load_page(
        path, width=width, height=height, settle=0.3,
        ready=f"{div} && {div}.querySelector('.gl-container canvas') !== null",
        steps=(
            # the legend lies over the scene's corner: hidden, what is left is the scene
            f"Plotly.animate({div}, ['19'], {still}).then(() => Plotly.relayout({div}, "
            f"{{showlegend: false}})).then(() => JSON.stringify({div}._fullLayout.scene._scene"
            ".container.getBoundingClientRect()))",
        ),
    )
    assert report.errors == [], report.errors
    box = json.loads(report.values[0])
    top, bottom = round(box["top"]), round(box["bottom"])
    left, right = round(box["left"]), round(box["right"])
    assert (left, right) == (0, width) and bottom - top > 0.75 * height  # the page's width
    ink = _ink(report.shots[0])
    scene = ink[top:bottom, left:right]
    rows = np.flatnonzero(scene.any(axis=1))
    columns = np.flatnonzero(scene.any(axis=0))
    margins = rows[0], bottom - top - 1 - rows[-1], columns[0], right - left - 1 - columns[-1]
    assert min(margins) >= 10, margins  # top, bottom, left, right [px]
    assert rows[-1] - rows[0] > 0.6 * (bottom - top)  # and the scene is not a speck
    below = np.flatnonzero(ink[bottom:].any(axis=1))
    assert below.size and bottom + below[-1] < height - 3  # the slider's labels are whole


# --- live view ----------------------------------------------------------------------------------


def test_live_view_draws_the_scene_and_the_tool_path(demo):
    model, result = demo
    view = LiveView(model)
    try:
        assert not view.interactive  # the tests draw off-screen (Agg)
        replay(model, result, view=view)
        scene = RobotScene(model)
        positions, corners = scene.geometry(result.q[-1])
        x, y, z = view._arm.get_data_3d()
        np.testing.assert_allclose(np.column_stack([x, y, z]),
                                   polyline(scene.segments(positions)), atol=1e-12)
        x, y, z = view._body.get_data_3d()
        np.testing.assert_allclose(np.column_stack([x, y, z]),
                                   polyline(corners[np.array(BOX_EDGES)]), atol=1e-12)
        x, y, z = view._path.get_data_3d()
        assert len(x) == result.q.shape[0]
        np.testing.assert_allclose([x[-1], y[-1], z[-1]], model.state(result.q[-1])
                                   .position("tool"), atol=1e-12)
        low, high = sorted(view.axes.get_zlim(), reverse=True)
        assert view.axes.get_zlim() == (low, high)  # NED: z down is drawn downwards
        view.figure.canvas.draw()
    finally:
        view.close()
    assert not plt.fignum_exists(view.figure.number)


# --- command line -------------------------------------------------------------------------------


@needs_plotly
def test_run_writes_the_view(tmp_path):
    scenario = short_steps("paper000_quintic", 20, tmp_path)
    out, page = tmp_path / "out", tmp_path / "views" / "run.html"
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--no-plots",
                 "--view", str(page)]) == 0
    assert page.stat().st_size > 1_000_000 and (out / "results.json").is_file()


def test_run_without_plotly_names_the_option_and_runs_nothing(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(view_module, "plotly_available", lambda: False)
    out = tmp_path / "out"
    code = main(["run", "paper000_quintic", "--out", str(out), "--view", str(tmp_path / "v.html")])
    assert code == 2
    err = capsys.readouterr().err
    assert "--view" in err and "uvms-qp[view]" in err and "Traceback" not in err
    assert not (out / "results.json").exists()
