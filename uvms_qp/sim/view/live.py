"""A live 3-D view from Python: a matplotlib window redrawn at every step of your own loop.

::

    view = LiveView(model)
    for k in range(steps):
        zeta = controller.step(model.state(q), t).zeta
        q = model.integrate(q, zeta, dt)
        view.show(q, target=goal, t=t)

It draws what the HTML view draws (:mod:`uvms_qp.sim.view.scene`: the arm's skeleton, the body
box, the tool path, the target) with matplotlib's 3-D axes, in whatever back-end matplotlib uses
(a window with an interactive one; off-screen with ``Agg``, where :attr:`LiveView.figure` can be
saved). :func:`replay` plays a finished run.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np

from ..._validation import FloatArray
from .scene import BOX_EDGES, RobotScene, polyline

if TYPE_CHECKING:  # pragma: no cover
    from ..runner import SimulationResult

#: Matplotlib back-ends that draw off-screen (no window to show or refresh).
OFFSCREEN_BACKENDS = ("agg", "cairo", "pdf", "pgf", "ps", "svg", "template")


class LiveView:
    """A matplotlib 3-D view of a model, redrawn by :meth:`show`.

    Args:
        model: The UVMS model.
        body_size: Body box (length, width, height) [m]; default
            :func:`~uvms_qp.sim.view.scene.default_body_size`.
        pause: Time given to the window's event loop after each redraw [s].
        margin: Space around the first drawn configuration [m] (the axes keep these limits).
    """

    def __init__(self, model: Any, *, body_size: Any = None, pause: float = 0.001,
                 margin: float | None = None) -> None:
        import matplotlib.pyplot as plt

        self.scene = RobotScene(model, body_size)
        self.kind = str(model.vehicle_kind)
        self.pause = float(pause)
        self.margin = margin
        self.figure = plt.figure(figsize=(7, 6))
        self.axes: Any = self.figure.add_subplot(projection="3d")
        self._tool: list[FloatArray] = []
        self._arm = self.axes.plot([], [], [], "-o", color="tab:blue", linewidth=3,
                                   markersize=3, label="arm")[0]
        self._body = self.axes.plot([], [], [], "-", color="tab:orange", linewidth=1.5,
                                    label="body")[0]
        self._path = self.axes.plot([], [], [], "-", color="tab:green", linewidth=1,
                                    label="tool path")[0]
        self._target = self.axes.plot([], [], [], "D", color="tab:red", markersize=5,
                                      label="target")[0]
        self.axes.legend(loc="upper left", fontsize="small")
        names = ("x north [m]", "y east [m]", "z down [m]") if self.kind == "spatial" else (
            "x [m]", "y [m]", "z [m]")
        self.axes.set_xlabel(names[0])
        self.axes.set_ylabel(names[1])
        self.axes.set_zlabel(names[2])
        self._limits_set = False
        self.interactive = matplotlib.get_backend().lower() not in OFFSCREEN_BACKENDS
        if self.interactive:
            plt.show(block=False)

    def _set_limits(self, points: FloatArray) -> None:
        low, high = points.min(axis=0), points.max(axis=0)
        centre = 0.5 * (low + high)
        half = 0.5 * float(np.max(high - low))
        half += self.margin if self.margin is not None else max(half, 0.1)
        spans = [(c - half, c + half) for c in centre]
        if self.kind == "spatial":  # NED: y east and z down (a rotation, not a mirror)
            spans[1] = spans[1][::-1]
            spans[2] = spans[2][::-1]
        self.axes.set_xlim(*spans[0])
        self.axes.set_ylim(*spans[1])
        self.axes.set_zlim(*spans[2])
        self.axes.set_box_aspect((1, 1, 1))
        if self.kind == "planar":  # from above, x to the right and y up
            self.axes.view_init(elev=90, azim=-90)
        self._limits_set = True

    def show(self, q: Any, *, target: Any = None, t: float | None = None) -> None:
        """Draw configuration ``q`` (and the ``target`` position [m], world) and refresh."""
        positions, corners = self.scene.geometry(q)
        arm = polyline(self.scene.segments(positions))
        body = polyline(corners[np.array(BOX_EDGES)])
        tool = positions[self.scene.frames.index("tool")]
        self._tool.append(tool)
        path = np.array(self._tool)
        self._arm.set_data_3d(arm[:, 0], arm[:, 1], arm[:, 2])
        self._body.set_data_3d(body[:, 0], body[:, 1], body[:, 2])
        self._path.set_data_3d(path[:, 0], path[:, 1], path[:, 2])
        goal = np.full(3, np.nan) if target is None else np.asarray(target, dtype=np.float64)
        self._target.set_data_3d([goal[0]], [goal[1]], [goal[2]])
        if not self._limits_set:
            self._set_limits(np.vstack([positions, corners]))
        if t is not None:
            self.axes.set_title(f"t = {t:.2f} s")
        self.figure.canvas.draw_idle()
        if self.interactive:
            self.figure.canvas.start_event_loop(self.pause)

    def clear_path(self) -> None:
        """Forget the drawn tool path."""
        self._tool = []

    def close(self) -> None:
        """Close the window."""
        import matplotlib.pyplot as plt

        plt.close(self.figure)


def replay(model: Any, result: SimulationResult, *, speed: float = 1.0,
           view: LiveView | None = None) -> LiveView:
    """Play a finished run in a :class:`LiveView` at ``speed`` times real time."""
    view = view or LiveView(model)
    started = time.perf_counter()
    for k, q in enumerate(result.q):
        t = float(result.time_states[k])
        target = result.target_position[k]
        view.show(q, target=target if np.isfinite(target).all() else None, t=t)
        if view.interactive:
            wait = t / speed - (time.perf_counter() - started)
            if wait > 0:
                time.sleep(wait)
    return view
