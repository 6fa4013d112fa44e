"""A 3-D view of a run: a self-contained HTML animation, and a live view from Python.

- :func:`write_view` writes one HTML file that plays the run (vehicle body, arm, tool path,
  target) offline in any browser; it needs the optional dependency plotly
  (``pip install 'uvms-qp[view]'``). ``uvms-qp run SCENARIO --out DIR --view run.html`` does
  the same from the command line.
- :class:`LiveView` draws a model in a matplotlib window at every step of your own loop;
  :func:`replay` plays a finished run in it.
- :class:`RobotScene` is what both draw: the model's skeleton and its body box, from its
  kinematics (the bundled models have no meshes).
"""

from __future__ import annotations

from .html import INSTALL_HINT, MAX_FRAMES, plotly_available, view_figure, write_view
from .live import LiveView, replay
from .scene import BODY_SIZES, RobotScene, default_body_size, skeleton_edges

__all__ = [
    "BODY_SIZES",
    "INSTALL_HINT",
    "MAX_FRAMES",
    "LiveView",
    "RobotScene",
    "default_body_size",
    "plotly_available",
    "replay",
    "skeleton_edges",
    "view_figure",
    "write_view",
]
