"""Figures of a scheme comparison, with every scheme overlaid (matplotlib, Agg back-end).

They mirror the papers' plots: vehicle pose histories (Soylu et al. (2007), Fig. 2/5 left;
dos Santos et al. (2006), Fig. 9/12), joint histories with limits (Soylu et al., Fig. 2/5 right;
dos Santos et al., Fig. 10/13; Wang et al. (2017), Fig. 3/5/7 c-d), the command with its hard box
(the vehicle body rates of dos Santos et al., Fig. 11/14, and the joint rates), manipulability
(Soylu et al., Fig. 7; Wang et al., Fig. 3g), tool tracking, the payload moment (Wang et al.,
Eq. (20)), the schemes' own diagnostics (shaping function, fuzzy weights, SC path rate) and
configuration snapshots (Soylu et al., Fig. 3/6 for planar models, drawn like the paper's
sketches with x to the right and y up).

:func:`comparison_figures` lists the figures that the runs have something to show in, as
``(file name, builder)`` pairs (a builder draws and returns a matplotlib figure), followed by the
paper figures of a bundled paper model (:mod:`uvms_qp.sim.paper_figures`).
"""

from __future__ import annotations

from collections.abc import Iterator
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._figures import (
    Builder,
    built,
    min_span,
    output_dir,
    pyplot,
    time_axis,
    unit_label,
    write_figures,
)
from .paper_figures import paper_figures
from .plots import ANGLE_SPAN, LOG_FLOOR, POSITION_SPAN, RATE_SPAN, is_planar
from .view.scene import RobotScene, polyline

if TYPE_CHECKING:  # pragma: no cover
    from .comparison import Comparison

#: Number of configuration snapshots drawn per scheme.
SNAPSHOTS = 7


def _pose_labels(model: Any) -> list[tuple[str, float]]:
    """``(axis label, smallest vertical span)`` of each entry of eta."""
    if model.vehicle_kind == "planar":
        names = [("x [m]", POSITION_SPAN), ("y [m]", POSITION_SPAN), ("psi [rad]", ANGLE_SPAN)]
    elif model.vehicle_kind == "spatial":
        names = [(f"{a} [m]", POSITION_SPAN) for a in "xyz"]
        names += [(f"{a} [rad]", ANGLE_SPAN) for a in ("phi", "theta", "psi")]
    else:
        names = []
    return names


def _vehicle_pose(comparison: Comparison, model: Any) -> Any:
    labels = _pose_labels(model)
    plt = pyplot()
    fig, axes = plt.subplots(len(labels), 1, figsize=(7, 1.8 * len(labels) + 0.6), sharex=True,
                             squeeze=False)
    for i, (label, span) in enumerate(labels):
        ax = axes[i, 0]
        for run in comparison.runs:
            ax.plot(run.result.time_states, run.result.eta[:, i], label=run.name)
        ax.set_ylabel(label)
        min_span(ax, np.concatenate([run.result.eta[:, i] for run in comparison.runs]), span)
    axes[0, 0].set_title(f"{comparison.scenario}: vehicle pose")
    axes[0, 0].legend(fontsize=7)
    time_axis(axes[-1, 0])
    return fig


def _rates(comparison: Comparison, model: Any) -> Any:
    """The command of every scheme per axis of zeta, over the hard box (the same for all)."""
    runs = comparison.runs
    first = runs[0].result
    nv = first.zeta.shape[1]
    plt = pyplot()
    units = first.zeta_units if len(first.zeta_units) == nv else ("",) * nv
    cols = 2 if nv > 1 else 1
    rows = (nv + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 1.8 * rows + 1.2), sharex=True,
                             squeeze=False)
    for i in range(nv):
        ax = axes[i // cols, i % cols]
        for run in runs:
            ax.plot(run.result.time, run.result.zeta[:, i], linewidth=1.0, label=run.name)
        lower = np.where(np.isfinite(first.zeta_lower[:, i]), first.zeta_lower[:, i], np.nan)
        upper = np.where(np.isfinite(first.zeta_upper[:, i]), first.zeta_upper[:, i], np.nan)
        for bound in (lower, upper):
            if np.isfinite(bound).any():
                ax.plot(first.time, bound, "k--", linewidth=0.8)
        ax.fill_between(first.time, lower, upper, color="0.5", alpha=0.1, linewidth=0)
        name = first.zeta_names[i]
        ax.set_ylabel(f"{name} [{units[i]}]" if units[i] else name)
        min_span(ax, np.concatenate([run.result.zeta[:, i] for run in runs]), RATE_SPAN)
    for i in range(nv, rows * cols):
        axes[i // cols, i % cols].axis("off")
    for col in range(cols):
        time_axis(axes[max(i for i in range(nv) if i % cols == col) // cols, col])
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"{comparison.scenario}: command zeta and its hard box (dashed, shaded)")
    return fig


def _joints(comparison: Comparison, model: Any) -> Any:
    n = int(model.n_joints)
    plt = pyplot()
    first = comparison.runs[0].result
    units = first.joint_units if len(first.joint_units) == n else ("rad",) * n
    fig, axes = plt.subplots(n, 1, figsize=(7, 1.6 * n + 0.6), sharex=True, squeeze=False)
    lower = np.asarray(model.joint_lower, dtype=np.float64)
    upper = np.asarray(model.joint_upper, dtype=np.float64)
    limited = False
    for i in range(n):
        ax = axes[i, 0]
        for run in comparison.runs:
            ax.plot(run.result.time_states, run.result.joints[:, i], label=run.name)
        for bound in (lower[i], upper[i]):
            if np.isfinite(bound):
                ax.axhline(bound, color="k", linestyle="--", linewidth=0.8)
                limited = True
        ax.set_ylabel(f"{model.joint_names[i]} [{units[i]}]")
    axes[0, 0].set_title(f"{comparison.scenario}: joints" + (" (dashed: limits)" if limited
                                                             else ""))
    axes[0, 0].legend(fontsize=7)
    time_axis(axes[-1, 0])
    return fig


def _manipulability_tracking(comparison: Comparison, model: Any) -> Any:
    plt = pyplot()
    first = comparison.runs[0].result
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for run in comparison.runs:
        r = run.result
        ax1.plot(r.time_states, r.manipulability, label=run.name)
        err = np.linalg.norm(r.ee_position - r.target_position, axis=1)
        ax2.plot(r.time_states, err, label=run.name)
    floor = first.manipulability_floor
    if floor is not None and np.isfinite(floor).any():
        ax1.plot(first.time_states, floor, "k--", linewidth=0.8, label="floor (hqp)")
    unit = first.manipulability_unit
    ax1.set_ylabel(f"manipulability [{unit_label(unit)}]" if unit else "manipulability")
    ax1.set_title(f"{comparison.scenario}: manipulability and tool error")
    ax1.legend(fontsize=7)
    ax2.set_ylabel("tool error [m]")
    ax2.set_yscale("symlog", linthresh=1e-4)
    time_axis(ax2)
    return fig


def _tool_tracking(comparison: Comparison, model: Any) -> Any:
    """Tool position of every scheme per world axis, the target dashed, and the error."""
    plt = pyplot()
    first = comparison.runs[0].result
    names = "xy" if is_planar(first) else "xyz"
    fig, axes = plt.subplots(len(names) + 1, 1, figsize=(7, 1.9 * len(names) + 2.2), sharex=True)
    for i, axis in enumerate(names):
        ax = axes[i]
        for run in comparison.runs:
            ax.plot(run.result.time_states, run.result.ee_position[:, i], label=run.name)
        if np.isfinite(first.target_position[:, i]).any():
            ax.plot(first.time_states, first.target_position[:, i], "k--", linewidth=0.9,
                    label="target")
        ax.set_ylabel(f"{axis} [m]")
        min_span(ax, np.concatenate([run.result.ee_position[:, i] for run in comparison.runs]),
                 POSITION_SPAN)
    for run in comparison.runs:
        r = run.result
        error = np.linalg.norm(r.ee_position - r.target_position, axis=1)
        if np.isfinite(error).any():
            axes[-1].semilogy(r.time_states, np.maximum(error, LOG_FLOOR), label=run.name)
    axes[-1].set_ylabel("|error| [m]")
    axes[0].set_title(f"{comparison.scenario}: tool tracking (world frame)")
    axes[0].legend(fontsize=7)
    time_axis(axes[-1])
    return fig


def _payload_moment(comparison: Comparison, model: Any) -> Any:
    runs = [run for run in comparison.runs if run.result.payload_moment is not None]
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for run in runs:
        ax.plot(run.result.time_states, run.result.payload_moment, label=run.name)
    ax.set_ylabel("payload moment [N m]")
    ax.set_title(f"{comparison.scenario}: payload moment F |(x_E, y_E)|")
    ax.legend(fontsize=7)
    time_axis(ax)
    return fig


def _diagnostics(comparison: Comparison, model: Any) -> Any:
    runs = comparison.runs
    keys = sorted({key for run in runs for key in run.info if key != "manipulability"})
    plt = pyplot()
    fig, axes = plt.subplots(len(keys), 1, figsize=(7, 1.5 * len(keys) + 0.6), sharex=True,
                             squeeze=False)
    for ax, key in zip(axes[:, 0], keys, strict=True):
        for run in runs:
            if key in run.info:
                ax.plot(run.result.time, run.info[key], label=run.name)
        ax.set_ylabel(key, fontsize=7)
    axes[0, 0].set_title(f"{comparison.scenario}: scheme diagnostics")
    axes[0, 0].legend(fontsize=7)
    time_axis(axes[-1, 0])
    return fig


def _snapshots(comparison: Comparison, model: Any) -> Any:
    """Configurations at evenly spaced times, one panel per scheme.

    The robot is the skeleton of :class:`~uvms_qp.sim.view.scene.RobotScene` (the mount red, the
    arm blue). Planar models are drawn as the papers' sketches (Soylu et al. (2007), Fig. 3/6):
    x to the right, y up. Spatial ones from the side, in the world x-z plane with z down (Wang
    et al. (2017), Fig. 2/4/6); a fixed base from the side too, z up (its base frame).
    """
    plt = pyplot()
    runs = comparison.runs
    scene = RobotScene(model)
    mount = np.array([edge == ("vehicle", "arm_base") for edge in scene.edges])
    planar = model.vehicle_kind == "planar"
    h, v = (0, 1) if planar else (0, 2)
    ned = model.vehicle_kind == "spatial"
    xlabel, ylabel = ("x [m]", "y [m]") if planar else ("x [m]", "z (down) [m]" if ned else "z [m]")
    fig, axes = plt.subplots(1, len(runs), figsize=(max(4.2 * len(runs), 6.0), 4.6),
                             squeeze=False, layout="constrained")
    for ax, run in zip(axes[0], runs, strict=True):
        r = run.result
        picks = np.linspace(0, r.q.shape[0] - 1, SNAPSHOTS).round().astype(int)
        shades = np.linspace(0.25, 1.0, picks.size)
        for shade, k in zip(shades, picks, strict=True):
            segments = scene.segments(scene.geometry(r.q[k])[0])
            arm = polyline(segments[~mount])
            ax.plot(arm[:, h], arm[:, v], "-o", color=(0.1, 0.3, 0.8, shade), markersize=2.5)
            if mount.any():
                body = polyline(segments[mount])
                ax.plot(body[:, h], body[:, v], "-", color=(0.8, 0.3, 0.1, shade), linewidth=3)
        target = r.target_position
        ax.plot(target[:, h], target[:, v], "k:", linewidth=0.8)
        ax.set_title(run.name, fontsize=9)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if ned:
            ax.invert_yaxis()
        ax.set_aspect("equal", adjustable="datalim")
    parts = "vehicle red, arm blue" if mount.any() and model.vehicle_kind != "fixed" else "arm blue"
    fig.suptitle(f"{comparison.scenario}: configurations ({parts}, later darker)")
    return fig


def comparison_figures(comparison: Comparison, model: Any) -> Iterator[tuple[str, Builder]]:
    """The comparison's figures that have something to show, as ``(file name, builder)``.

    The paper figures of a bundled paper model come last.
    """
    runs = comparison.runs
    draws: list[tuple[str, Any]] = []
    if model.vehicle_kind != "fixed":
        draws.append(("vehicle_pose.png", _vehicle_pose))
    if model.nv:
        draws.append(("rates.png", _rates))
    if model.n_joints:
        draws.append(("joints.png", _joints))
    draws += [("tool_tracking.png", _tool_tracking),
              ("manipulability_tracking.png", _manipulability_tracking)]
    if any(run.result.payload_moment is not None for run in runs):
        draws.append(("payload_moment.png", _payload_moment))
    if any(key != "manipulability" for run in runs for key in run.info):
        draws.append(("scheme_diagnostics.png", _diagnostics))
    draws.append(("configurations.png", _snapshots))
    for name, draw in draws:
        yield name, partial(draw, comparison, model)
    yield from paper_figures(comparison, model)


def comparison_figure_objects(comparison: Comparison, model: Any) -> dict[str, Any]:
    """The comparison's figures as matplotlib figures, by file name (close them when done)."""
    return dict(built(comparison_figures(comparison, model)))


def plot_comparison(comparison: Comparison, model: Any, out_dir: str | Path, *,
                    progress: bool = False) -> list[Path]:
    """Write the comparison figures as PNG files into ``out_dir`` and return their paths.

    Args:
        comparison: The runs to overlay.
        model: The scenario's model (for labels, frames and joint limits).
        out_dir: Output directory (created if needed). A figure path there that is a symbolic
            link is replaced by the figure, never followed.
        progress: Report the figures as they are written (on standard error).
    """
    return write_figures(comparison_figures(comparison, model), output_dir(out_dir),
                         label=f"{comparison.scenario} figures", progress=progress)
