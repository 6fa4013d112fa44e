"""Figures of a run (PNG, headless matplotlib "Agg" back-end).

One file per topic: ``tool_tracking.png`` (tool and target per axis, tracking error),
``vehicle_pose.png`` (vehicle position and attitude), ``joints.png`` (joint angles against their
limits), ``manipulability.png``, ``rates.png`` (every entry of zeta against its hard bounds),
``residuals.png`` (per-level residual norms, log scale) and, with a payload task,
``payload_moment.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._figures import output_dir, pyplot, save

if TYPE_CHECKING:  # pragma: no cover
    from .runner import SimulationResult


def _events(ax: Any, result: SimulationResult) -> None:
    for event in result.events:
        ax.axvline(event["time"], color="0.6", linestyle=":", linewidth=1.0)


def plot_results(result: SimulationResult, out_dir: str | Path) -> list[Path]:
    """Write the figures of ``result`` into ``out_dir``; return their paths."""
    plt = pyplot()
    out = output_dir(out_dir)
    t = result.time_states
    ts = result.time
    files: list[Path] = []

    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for i, label in enumerate("xyz"):
        axes[i].plot(t, result.ee_position[:, i], label="tool")
        axes[i].plot(t, result.target_position[:, i], "--", label="target")
        axes[i].set_ylabel(f"{label} [m]")
        _events(axes[i], result)
    axes[0].legend(loc="best")
    error = np.linalg.norm(result.ee_position - result.target_position, axis=1)
    axes[3].semilogy(t, np.maximum(error, 1e-12))
    axes[3].set_ylabel("|error| [m]")
    axes[3].set_xlabel("t [s]")
    fig.suptitle(f"{result.scenario}: tool tracking (world NED)")
    files.append(save(fig, out / "tool_tracking.png"))

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, label in enumerate("xyz"):
        axes[0].plot(t, result.vehicle_position[:, i], label=label)
    axes[0].set_ylabel("position [m]")
    axes[0].legend(loc="best")
    angle_names = ("phi", "theta", "psi") if result.eta.shape[1] == 6 else ("psi",)
    for j, name in enumerate(angle_names):
        axes[1].plot(t, result.eta[:, result.eta.shape[1] - len(angle_names) + j], label=name)
    if result.heading is not None:
        axes[1].axhline(result.heading, color="k", linestyle="--", label="current heading")
    axes[1].set_ylabel("attitude [rad]")
    axes[1].set_xlabel("t [s]")
    axes[1].legend(loc="best")
    for ax in axes:
        _events(ax, result)
    fig.suptitle(f"{result.scenario}: vehicle pose")
    files.append(save(fig, out / "vehicle_pose.png"))

    n = result.joints.shape[1]
    fig, axes = plt.subplots(max(n, 1), 1, figsize=(8, 1.8 * max(n, 1) + 1), sharex=True,
                             squeeze=False)
    for j in range(n):
        ax = axes[j, 0]
        ax.plot(t, result.joints[:, j])
        ax.axhline(result.joint_lower[j], color="r", linestyle="--")
        ax.axhline(result.joint_upper[j], color="r", linestyle="--")
        ax.set_ylabel(f"{result.joint_names[j]} [rad]")
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{result.scenario}: joints and limits")
    files.append(save(fig, out / "joints.png"))

    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(t, result.manipulability)
    ax.set_ylabel("manipulability")
    ax.set_xlabel("t [s]")
    _events(ax, result)
    fig.suptitle(f"{result.scenario}: manipulability")
    files.append(save(fig, out / "manipulability.png"))

    nv = result.zeta.shape[1]
    cols = 2
    rows = (nv + 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(10, 1.7 * rows + 1), sharex=True,
                             squeeze=False)
    for i in range(nv):
        ax = axes[i // cols, i % cols]
        ax.plot(ts, result.zeta[:, i])
        for bound in (result.zeta_lower[:, i], result.zeta_upper[:, i]):
            if np.isfinite(bound).any():
                ax.plot(ts, np.where(np.isfinite(bound), bound, np.nan), "r--", linewidth=0.8)
        ax.set_ylabel(result.zeta_names[i])
    for i in range(nv, rows * cols):
        axes[i // cols, i % cols].axis("off")
    fig.suptitle(f"{result.scenario}: commanded rates and hard bounds [m/s, rad/s]")
    files.append(save(fig, out / "rates.png"))

    fig, ax = plt.subplots(figsize=(9, 4))
    for level in range(result.level_residuals.shape[1]):
        values = result.level_residuals[:, level]
        if np.isfinite(values).any():
            label = f"level {level + 1}"
            if level < len(result.level_names):
                label += f" ({result.level_names[level]})"
            ax.semilogy(ts, np.maximum(values, 1e-12), label=label)
    ax.set_ylabel("residual norm")
    ax.set_xlabel("t [s]")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize="small")
    _events(ax, result)
    fig.suptitle(f"{result.scenario}: per-level residuals")
    files.append(save(fig, out / "residuals.png"))

    if result.payload_moment is not None:
        fig, ax = plt.subplots(figsize=(8, 3.5))
        ax.plot(t, result.payload_moment)
        ax.set_ylabel("payload moment [N m]")
        ax.set_xlabel("t [s]")
        _events(ax, result)
        fig.suptitle(f"{result.scenario}: payload moment F |(x_E, y_E)|")
        files.append(save(fig, out / "payload_moment.png"))
    return files
