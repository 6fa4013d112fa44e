"""Figures of a run (PNG, headless matplotlib "Agg" back-end).

One file per topic, each drawn only when the run has something to show:

- ``tool_tracking.png``: tool and target per world axis (no ``z`` panel for a planar model) and
  the tracking error;
- ``vehicle_pose.png``: vehicle position and attitude (not for a fixed base);
- ``joints.png``: joint positions, with their limits dashed when the joints have limits;
- ``manipulability.png``: the measure in its unit, with the manipulability task's floor;
- ``rates.png``: the command, every entry of zeta in its unit, with its hard box shaded (the
  intersection of every constraint's bounds at each step) and, with command-rate bounds, the
  window ``zeta_(k-1) +/- a_max dt`` they allowed at each step (green dotted, in the legend);
- ``residuals.png``: per-level residual norms (log scale), levels numbered from 0 as in
  the ``summary()`` of a solve and of a control step;
- ``payload_moment.png``: with a payload task;
- on a dynamic plant, the figures of :mod:`uvms_qp.sim.dynamic_figures` (thrusters, velocity
  tracking, attitude disturbance, joint torques).

Dotted vertical lines mark the scenario's events (the payload's pick-up of the demo is one), each
named in the figure's legend. :func:`run_figures` gives the figures as
matplotlib objects (to inspect or restyle); :func:`plot_results` writes them.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._figures import (
    RATE_WINDOW_LABEL,
    Builder,
    built,
    legend,
    mark_events,
    min_span,
    output_dir,
    pyplot,
    time_axis,
    unit_label,
    write_figures,
)
from .dynamic_figures import dynamic_builders
from .units import LINEAR_RATES

if TYPE_CHECKING:  # pragma: no cover
    from .runner import SimulationResult

#: Smallest vertical range of a position panel [m] and of an angle panel [rad].
POSITION_SPAN = 0.02
ANGLE_SPAN = 0.02
#: Smallest vertical range of a command panel [m/s or rad/s].
RATE_SPAN = 1e-6
#: Residuals and errors below this are drawn at this value on log axes.
LOG_FLOOR = 1e-12


def _events(ax: Any, result: SimulationResult) -> None:
    mark_events(ax, result.events)


def is_planar(result: SimulationResult) -> bool:
    """True for a planar vehicle (pose ``[x, y, psi]``): its world ``z`` is identically 0."""
    return bool(result.eta.shape[1] == 3)


def _zeta_units(result: SimulationResult) -> tuple[str, ...]:
    if len(result.zeta_units) == len(result.zeta_names):
        return tuple(result.zeta_units)
    n_joints = len(result.joint_names)
    vehicle = result.zeta_names[: len(result.zeta_names) - n_joints]
    return (tuple("m/s" if n in LINEAR_RATES else "rad/s" for n in vehicle)
            + ("rad/s",) * n_joints)


def _joint_units(result: SimulationResult) -> tuple[str, ...]:
    if len(result.joint_units) == len(result.joint_names):
        return tuple(result.joint_units)
    return ("rad",) * len(result.joint_names)


def _tool_tracking(result: SimulationResult) -> Any:
    plt = pyplot()
    t = result.time_states
    axes_names = "xy" if is_planar(result) else "xyz"
    fig, axes = plt.subplots(len(axes_names) + 1, 1, figsize=(8, 2.2 * len(axes_names) + 2.4),
                             sharex=True)
    has_target = bool(np.isfinite(result.target_position).any())
    for i, label in enumerate(axes_names):
        axes[i].plot(t, result.ee_position[:, i], label="tool")
        if has_target:
            axes[i].plot(t, result.target_position[:, i], "--", label="target")
        axes[i].set_ylabel(f"{label} [m]")
        min_span(axes[i], result.ee_position[:, i], POSITION_SPAN)
        _events(axes[i], result)
    legend(axes[0], loc="best", fontsize="small")
    if has_target:
        error = np.linalg.norm(result.ee_position - result.target_position, axis=1)
        axes[-1].semilogy(t, np.maximum(error, LOG_FLOOR))
    axes[-1].set_ylabel("|error| [m]")
    _events(axes[-1], result)
    time_axis(axes[-1])
    fig.suptitle(f"{result.scenario}: tool tracking (world frame)")
    return fig


def _vehicle_pose(result: SimulationResult) -> Any:
    size = result.eta.shape[1]
    plt = pyplot()
    t = result.time_states
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    position_names = "xy" if is_planar(result) else "xyz"
    for i, label in enumerate(position_names):
        axes[0].plot(t, result.vehicle_position[:, i], label=label)
    axes[0].set_ylabel("position [m]")
    min_span(axes[0], result.vehicle_position[:, : len(position_names)], POSITION_SPAN)
    angle_names = ("psi",) if size == 3 else ("phi", "theta", "psi")
    angles = result.eta[:, size - len(angle_names):]
    for j, name in enumerate(angle_names):
        axes[1].plot(t, angles[:, j], label=name)
    if result.heading is not None:
        axes[1].axhline(result.heading, color="k", linestyle="--", label="current heading")
    axes[1].set_ylabel("attitude [rad]")
    min_span(axes[1], angles, ANGLE_SPAN)
    time_axis(axes[1])
    for ax in axes:
        _events(ax, result)
    legend(axes[0], [axes[0]], loc="best", fontsize="small")
    legend(axes[1], [axes[1]], loc="best", fontsize="small")
    fig.suptitle(f"{result.scenario}: vehicle pose")
    return fig


def _joints(result: SimulationResult) -> Any:
    n = result.joints.shape[1]
    plt = pyplot()
    t = result.time_states
    units = _joint_units(result)
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.8 * n + 1), sharex=True, squeeze=False)
    limited = False
    for j in range(n):
        ax = axes[j, 0]
        ax.plot(t, result.joints[:, j])
        for bound in (result.joint_lower[j], result.joint_upper[j]):
            if np.isfinite(bound):
                ax.axhline(bound, color="r", linestyle="--", linewidth=0.8)
                limited = True
        ax.set_ylabel(f"{result.joint_names[j]} [{units[j]}]")
        _events(ax, result)
    legend(axes[0, 0], loc="best", fontsize="small")
    time_axis(axes[-1, 0])
    fig.suptitle(f"{result.scenario}: joints" + (" (dashed: limits)" if limited else ""))
    return fig


def _manipulability(result: SimulationResult) -> Any:
    plt = pyplot()
    t = result.time_states
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(t, result.manipulability, label="w")
    floor = result.manipulability_floor
    if floor is not None and np.isfinite(floor).any():
        ax.plot(t, floor, "r--", linewidth=1.0, label="floor")
    unit = result.manipulability_unit
    ax.set_ylabel(f"manipulability w [{unit_label(unit)}]" if unit else "manipulability w")
    time_axis(ax)
    _events(ax, result)
    if len(ax.get_lines()) > 1:  # w alone needs no legend
        legend(ax, loc="best", fontsize="small")
    fig.suptitle(f"{result.scenario}: manipulability (Yoshikawa)")
    return fig


def _rates(result: SimulationResult) -> Any:
    nv = result.zeta.shape[1]
    plt = pyplot()
    ts = result.time
    units = _zeta_units(result)
    cols = 2 if nv > 1 else 1
    rows = (nv + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 1.8 * rows + 1.2), sharex=True,
                             squeeze=False)
    for i in range(nv):
        ax = axes[i // cols, i % cols]
        lower = result.zeta_lower[:, i]
        upper = result.zeta_upper[:, i]
        ax.plot(ts, result.zeta[:, i], linewidth=1.0, label="command")
        shown = [result.zeta[:, i]]
        for bound in (lower, upper):
            if np.isfinite(bound).any():
                finite = np.where(np.isfinite(bound), bound, np.nan)
                ax.plot(ts, finite, "r--", linewidth=0.8, label="hard box")
                shown.append(finite)
        if np.isfinite(lower).any() or np.isfinite(upper).any():
            ax.fill_between(ts, np.where(np.isfinite(lower), lower, np.nan),
                            np.where(np.isfinite(upper), upper, np.nan),
                            color="tab:red", alpha=0.08, linewidth=0)
        window = _rate_window(result, i)
        if window is not None:
            for side in window:
                ax.plot(ts, side, ":", color="tab:green", linewidth=0.9, label=RATE_WINDOW_LABEL)
        ax.set_ylabel(f"{result.zeta_names[i]} [{units[i]}]")
        min_span(ax, np.concatenate(shown), RATE_SPAN)
        _events(ax, result)
    drawn = [axes[i // cols, i % cols] for i in range(nv)]
    legend(drawn[0], drawn, loc="best", fontsize="x-small")  # every panel's kinds of line, once
    for i in range(nv, rows * cols):
        axes[i // cols, i % cols].axis("off")
    for col in range(cols):  # the lowest drawn panel of each column carries the time axis
        last = max(i for i in range(nv) if i % cols == col) // cols
        time_axis(axes[last, col])
    title = f"{result.scenario}: command zeta and its hard box (red dashed, shaded)"
    if result.command_rate_limit is not None:
        title += f"\nand the {RATE_WINDOW_LABEL} (green dotted)"
    fig.suptitle(title)
    return fig


def _rate_window(result: SimulationResult, i: int) -> tuple[Any, Any] | None:
    """``zeta_(k-1) -/+ a_max dt`` of entry ``i`` per step, or None where it is not bounded."""
    limit = result.command_rate_limit
    if limit is None or not np.isfinite(limit[i]):
        return None
    column = result.zeta[:, i]
    previous = np.empty_like(column)
    previous[1:] = column[:-1]
    start = result.command_initial
    previous[0] = np.nan if start is None else start[i]
    step = limit[i] * result.dt
    return previous - step, previous + step


def _residuals(result: SimulationResult) -> Any:
    values = result.level_residuals
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9, 4))
    for level in range(values.shape[1]):
        series = values[:, level]
        if np.isfinite(series).any():
            label = f"level {level}"
            if level < len(result.level_names):
                label += f" ({result.level_names[level]})"
            ax.semilogy(result.time, np.maximum(series, LOG_FLOOR), label=label)
    ax.set_ylabel("residual norm (level units)")
    time_axis(ax)
    _events(ax, result)
    legend(ax, loc="best", fontsize="small")
    fig.suptitle(f"{result.scenario}: per-level residuals (levels from 0, highest priority)")
    return fig


def _payload_moment(result: SimulationResult) -> Any:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(result.time_states, np.asarray(result.payload_moment))
    ax.set_ylabel("payload moment [N m]")
    time_axis(ax)
    _events(ax, result)
    legend(ax, loc="best", fontsize="small")
    fig.suptitle(f"{result.scenario}: payload moment F |(x_E, y_E)|")
    return fig


def _builders(result: SimulationResult, reference: SimulationResult | None = None
              ) -> Iterator[tuple[str, Builder]]:
    """The run's figures that have something to show, as ``(file name, builder)``."""
    yield "tool_tracking.png", lambda: _tool_tracking(result)
    if result.eta.shape[1]:
        yield "vehicle_pose.png", lambda: _vehicle_pose(result)
    if result.joints.shape[1]:
        yield "joints.png", lambda: _joints(result)
    yield "manipulability.png", lambda: _manipulability(result)
    if result.zeta.shape[1]:
        yield "rates.png", lambda: _rates(result)
    if np.isfinite(result.level_residuals).any():
        yield "residuals.png", lambda: _residuals(result)
    if result.payload_moment is not None:
        yield "payload_moment.png", lambda: _payload_moment(result)
    yield from dynamic_builders(result, reference)


def run_figures(result: SimulationResult) -> dict[str, Any]:
    """The run's figures as matplotlib figures, by file name (close them when done)."""
    return dict(built(_builders(result)))


def plot_results(result: SimulationResult, out_dir: str | Path, *,
                 progress: bool = False, reference: SimulationResult | None = None
                 ) -> list[Path]:
    """Write the figures of ``result`` into ``out_dir``; return their paths.

    Args:
        result: The run.
        reference: For a dynamic run, the kinematic run of the same scenario (drawn beside it).
        out_dir: Output directory (created if needed). A figure path there that is a symbolic
            link is replaced by the figure, never followed.
        progress: Report the figures as they are written (on standard error).
    """
    return write_figures(_builders(result, reference), output_dir(out_dir),
                         label=f"{result.scenario} figures", progress=progress)
