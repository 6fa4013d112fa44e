"""A self-contained HTML animation of a run (plotly; every script inlined, no network needed).

The page shows the run in 3-D: the vehicle body (a box, :mod:`uvms_qp.sim.view.scene`), the arm's
skeleton, the tool path so far, the target path and the current target, with play / pause
buttons and a time slider (it plays once on load). The view can be turned with the mouse.

Axes: a spatial vehicle in NED (x north, y east, z down, drawn with down as down); a planar model
from above as in the papers' sketches (x to the right, y up); a fixed base in its base frame
(z up). Frames are evenly spaced states of the run, at most :data:`MAX_FRAMES`, played at the
run's own speed.

Plotly is an optional dependency (``pip install 'uvms-qp[view]'``): the page inlines plotly.js
(about 4.8 MB), so it opens offline in any browser with WebGL.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..._validation import FloatArray
from ...errors import InputError
from .._files import write_atomic
from .scene import BOX_EDGES, BOX_TRIANGLES, RobotScene

if TYPE_CHECKING:  # pragma: no cover
    from ..runner import SimulationResult

#: ``id`` of the page's plot element.
VIEW_ID = "uvms-qp-view"
#: Most animation frames written (the states shown are evenly spaced over the run).
MAX_FRAMES = 200
#: Shortest time a frame is shown when playing [ms].
MIN_FRAME_MS = 30
#: How to install the optional dependency of the view.
INSTALL_HINT = "pip install 'uvms-qp[view]' (or pip install plotly)"
#: Colours of the drawn parts (CSS).
COLORS = {
    "body": "rgb(240, 140, 0)",
    "body_edges": "rgb(150, 80, 0)",
    "arm": "rgb(20, 70, 220)",
    "tool_path": "rgb(40, 150, 70)",
    "target": "rgb(200, 0, 0)",
    "target_path": "rgb(120, 120, 120)",
}
#: Camera of a spatial or fixed-base view (plotly's normalised scene units): from ahead and to
#: the side, far enough that the whole cube, its tick labels and axis
#: titles stay inside the scene on a wide page (checked at 1000x700 and 1600x1000 in headless
#: Chromium), and aimed a little below the centre so the margins above and below are even.
SIDE_CAMERA = {"eye": {"x": 1.5, "y": -1.5, "z": 0.96}, "center": {"x": 0.0, "y": 0.0, "z": -0.15}}
#: Trace names, in the figure's order; the animated ones are updated by every frame.
TRACES = ("target path", "tool path", "body", "body edges", "arm", "tool", "target")
ANIMATED = (1, 2, 3, 4, 5, 6)


#: Script of the page: the play / pause buttons and the slider do not animate by themselves
#: (``execute: false``); these handlers do, and catch the promise that plotly rejects when an
#: animation is interrupted (plotly's own handlers leave it uncaught, an error in the console).
#: The run plays once on load.
_CONTROLS = """
var gd = document.getElementById('{plot_id}');
function animate(frames, options) {
  return Plotly.animate(gd, frames, options).catch(function () {});
}
gd.on('plotly_buttonclicked', function (event) {
  animate(event.button.args[0], event.button.args[1]);
});
gd.on('plotly_sliderchange', function (event) {
  if (event.interaction) { animate(event.step.args[0], event.step.args[1]); }
});
animate(null, %s);
"""


def _play_options(fig: Any) -> Any:
    return fig.layout.updatemenus[0].buttons[0].args[1]


def plotly_available() -> bool:
    """True when plotly (the optional dependency of the view) is installed."""
    return importlib.util.find_spec("plotly") is not None


def _graph_objects() -> Any:
    if not plotly_available():
        raise ModuleNotFoundError(f"the 3-D view needs plotly: {INSTALL_HINT}")
    import plotly.graph_objects as go

    return go


def frame_indices(n_states: int, max_frames: int = MAX_FRAMES) -> FloatArray:
    """Evenly spaced state indices, first and last included, at most ``max_frames`` of them."""
    if max_frames < 2:
        raise InputError(f"max_frames: expected at least 2, got {max_frames}")
    count = min(n_states, max_frames)
    return np.unique(np.linspace(0, n_states - 1, count).round().astype(int))


def _lines(pairs: FloatArray) -> tuple[list[Any], list[Any], list[Any]]:
    """x, y, z lists of (K, 2, 3) segments for one plotly line trace (None between segments)."""
    xs: list[Any] = []
    ys: list[Any] = []
    zs: list[Any] = []
    for a, b in pairs:
        xs += [a[0], b[0], None]
        ys += [a[1], b[1], None]
        zs += [a[2], b[2], None]
    return xs, ys, zs


def _check(model: Any, result: SimulationResult) -> None:
    q = np.asarray(result.q)
    if q.ndim != 2 or q.shape[1] != int(model.nq) or q.shape[0] < 1:
        raise InputError(f"result of scenario {result.scenario!r}: configurations of shape "
                         f"{q.shape} do not fit model {model.name!r} (nq = {model.nq})")


def _axes(kind: str, low: FloatArray, high: FloatArray) -> dict[str, Any]:
    """The scene layout: equal scales, fixed ranges (a cube around the run), axis directions."""
    centre = 0.5 * (low + high)
    half = 0.55 * float(np.max(high - low)) + 0.05
    titles = {"spatial": ("x north [m]", "y east [m]", "z down [m]"),
              "planar": ("x [m]", "y [m]", "z [m]"),
              "fixed": ("x [m]", "y [m]", "z [m]")}[kind]
    reversed_axes = (1, 2) if kind == "spatial" else ()  # NED: y east and z down, a rotation
    scene: dict[str, Any] = {"aspectmode": "cube"}
    for i, name in enumerate(("xaxis", "yaxis", "zaxis")):
        span = [centre[i] - half, centre[i] + half]
        scene[name] = {"title": {"text": titles[i]},
                       "range": span[::-1] if i in reversed_axes else span}
    if kind == "planar":  # from above, orthographic, like the papers' sketches
        scene["camera"] = {"eye": {"x": 0.0, "y": 0.0, "z": 2.0},
                           "up": {"x": 0.0, "y": 1.0, "z": 0.0},
                           "projection": {"type": "orthographic"}}
        scene["zaxis"]["visible"] = False
    else:  # from ahead and to the side of the vehicle (spatial) or the base (fixed)
        scene["camera"] = {key: dict(value) for key, value in SIDE_CAMERA.items()}
    return scene


def view_figure(model: Any, result: SimulationResult, *, max_frames: int = MAX_FRAMES,
                body_size: Any = None) -> Any:
    """The animation of ``result`` as a plotly figure (see the module docstring).

    Args:
        model: The model the run used (its kinematics place the drawn parts).
        result: The run.
        max_frames: Most animation frames.
        body_size: Body box (length, width, height) [m]; default
            :func:`~uvms_qp.sim.view.scene.default_body_size`.

    Raises:
        InputError: ``result`` does not fit ``model``, or a bad ``max_frames``/``body_size``.
        ModuleNotFoundError: plotly is not installed.
    """
    go = _graph_objects()
    _check(model, result)
    scene = RobotScene(model, body_size)
    picks = frame_indices(result.q.shape[0], max_frames)
    times = np.asarray(result.time_states)[picks]
    shots = [scene.geometry(result.q[k]) for k in picks]
    tool = np.asarray(result.ee_position, dtype=np.float64)
    target = np.asarray(result.target_position, dtype=np.float64)
    has_target = bool(np.isfinite(target).all(axis=1).any())

    points = [tool, *(p for shot in shots for p in shot)]
    if has_target:
        points.append(target[np.isfinite(target).all(axis=1)])
    cloud = np.vstack(points)
    kind = str(model.vehicle_kind)
    layout_scene = _axes(kind, cloud.min(axis=0), cloud.max(axis=0))

    def animated(j: int, k: int) -> list[Any]:
        positions, corners = shots[j]
        path = tool[: k + 1]
        ax, ay, az = _lines(scene.segments(positions))
        bx, by, bz = _lines(corners[np.array(BOX_EDGES)])
        current = target[k] if has_target and np.isfinite(target[k]).all() else [None] * 3
        return [
            go.Scatter3d(x=path[:, 0], y=path[:, 1], z=path[:, 2]),
            go.Mesh3d(x=corners[:, 0], y=corners[:, 1], z=corners[:, 2]),
            go.Scatter3d(x=bx, y=by, z=bz),
            go.Scatter3d(x=ax, y=ay, z=az),
            go.Scatter3d(x=[tool[k, 0]], y=[tool[k, 1]], z=[tool[k, 2]]),
            go.Scatter3d(x=[current[0]], y=[current[1]], z=[current[2]]),
        ]

    first = animated(0, int(picks[0]))
    i, jj, kk = np.array(BOX_TRIANGLES).T
    finite_target = np.where(np.isfinite(target), target, np.nan)
    traces = [
        go.Scatter3d(x=finite_target[:, 0], y=finite_target[:, 1], z=finite_target[:, 2],
                     mode="lines", name=TRACES[0], visible=has_target,
                     line={"color": COLORS["target_path"], "width": 3, "dash": "dot"}),
        first[0].update(mode="lines", name=TRACES[1],
                        line={"color": COLORS["tool_path"], "width": 4}),
        first[1].update(i=i, j=jj, k=kk, name=TRACES[2], color=COLORS["body"], opacity=0.4,
                        flatshading=True, showlegend=True, hoverinfo="skip"),
        first[2].update(mode="lines", name=TRACES[3], showlegend=False, hoverinfo="skip",
                        line={"color": COLORS["body_edges"], "width": 4}),
        first[3].update(mode="lines+markers", name=TRACES[4],
                        line={"color": COLORS["arm"], "width": 9},
                        marker={"color": COLORS["arm"], "size": 4}),
        first[4].update(mode="markers", name=TRACES[5],
                        marker={"color": COLORS["tool_path"], "size": 5}),
        first[5].update(mode="markers", name=TRACES[6], visible=has_target,
                        marker={"color": COLORS["target"], "size": 6, "symbol": "diamond"}),
    ]
    frames = [go.Frame(data=animated(j, int(k)), traces=list(ANIMATED), name=f"{j}")
              for j, k in enumerate(picks)]
    step_ms = (max(MIN_FRAME_MS, int(1000 * float(np.median(np.diff(times)))))
               if times.size > 1 else MIN_FRAME_MS)
    play = {"frame": {"duration": step_ms, "redraw": True}, "fromcurrent": True,
            "transition": {"duration": 0}, "mode": "immediate"}
    still = {"frame": {"duration": 0, "redraw": True}, "transition": {"duration": 0},
             "mode": "immediate"}
    fig = go.Figure(data=traces, frames=frames)
    fig.update_layout(
        title={"text": f"{result.scenario}: {model.name} on the {result.plant} plant, "
                       f"{result.scheme} ({result.solver}), {result.steps} steps of "
                       f"{result.dt:g} s"},
        scene=layout_scene,
        margin={"l": 0, "r": 0, "t": 40, "b": 0},
        legend={"x": 0.0, "y": 0.95},
        updatemenus=[{
            "type": "buttons", "direction": "left", "x": 0.0, "y": 0.0, "xanchor": "left",
            "yanchor": "top", "pad": {"t": 30},
            "buttons": [{"label": "play", "method": "animate", "args": [None, play],
                         "execute": False},
                        {"label": "pause", "method": "animate", "execute": False,
                         "args": [[None], {**still, "frame": {"duration": 0, "redraw": False}}]}],
        }],
        sliders=[{
            "x": 0.12, "y": 0.0, "len": 0.86, "pad": {"t": 20, "b": 12},  # its labels whole
            "currentvalue": {"prefix": "t = ", "suffix": " s"},
            "steps": [{"label": f"{t:.2f}", "method": "animate", "args": [[f"{j}"], still],
                       "execute": False} for j, t in enumerate(times)],
        }],
    )
    return fig


def write_view(model: Any, result: SimulationResult, path: str | Path, *,
               max_frames: int = MAX_FRAMES, body_size: Any = None) -> Path:
    """Write the animation of ``result`` as one self-contained HTML file (atomically).

    Args:
        model: The model the run used.
        result: The run.
        path: HTML file to write (its directory is created); a link there is replaced, not
            followed.
        max_frames: Most animation frames.
        body_size: Body box (length, width, height) [m].

    Returns:
        The written path.

    Raises:
        InputError: ``result`` does not fit ``model``, or a bad ``max_frames``/``body_size``.
        ModuleNotFoundError: plotly is not installed.
    """
    fig = view_figure(model, result, max_frames=max_frames, body_size=body_size)
    html = fig.to_html(include_plotlyjs=True, full_html=True, auto_play=False, div_id=VIEW_ID,
                       config={"displaylogo": False, "responsive": True},
                       post_script=_CONTROLS % json.dumps(_play_options(fig)))
    html = html.replace("<head>", "<head><style>body { margin: 0; }</style>", 1)
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    return write_atomic(target, html)
