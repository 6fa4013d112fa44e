"""Figures of a scheme comparison, with every scheme overlaid (matplotlib, Agg back-end).

They mirror the papers' plots: vehicle pose histories (``000``, Fig. 2/5 left; ``001``, Fig. 9/12),
joint histories with limits (Fig. 2/5 right; ``001``, Fig. 10/13; ``003``, Fig. 3/5/7 c-d),
vehicle body rates (``001``, Fig. 11/14), manipulability (``000``, Fig. 7; ``003``, Fig. 3g),
tool tracking error, the schemes' own diagnostics (shaping function, fuzzy weights, SC path rate),
and, for planar models, configuration snapshots (``000``, Fig. 3/6).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._figures import output_dir, pyplot, save
from .paper_figures import plot_paper_figures

if TYPE_CHECKING:  # pragma: no cover
    from .comparison import Comparison

#: Number of configuration snapshots drawn per scheme for planar models.
SNAPSHOTS = 7


def _labels(model: Any) -> list[str]:
    if model.vehicle_kind == "planar":
        return ["x [m]", "y [m]", "psi [rad]"]
    if model.vehicle_kind == "spatial":
        return ["x [m]", "y [m]", "z [m]", "phi [rad]", "theta [rad]", "psi [rad]"]
    return []


def plot_comparison(comparison: Comparison, model: Any, out_dir: str | Path) -> list[Path]:
    """Write the comparison figures as PNG files into ``out_dir`` and return their paths.

    Args:
        comparison: The runs to overlay.
        model: The scenario's model (for labels, frames and joint limits).
        out_dir: Output directory (created if needed).
    """
    plt = pyplot()
    directory = output_dir(out_dir)
    runs = comparison.runs
    paths: list[Path] = []
    title = comparison.scenario

    labels = _labels(model)
    if labels:
        fig, axes = plt.subplots(len(labels), 1, figsize=(7, 1.8 * len(labels)), sharex=True)
        for run in runs:
            for i, ax in enumerate(np.atleast_1d(axes)):
                ax.plot(run.result.time_states, run.result.eta[:, i], label=run.name)
                ax.set_ylabel(labels[i])
        np.atleast_1d(axes)[0].set_title(f"{title}: vehicle pose")
        np.atleast_1d(axes)[0].legend(fontsize=7)
        np.atleast_1d(axes)[-1].set_xlabel("t [s]")
        paths.append(save(fig, directory / "vehicle_pose.png"))

        nveh = int(model.n_vehicle)
        fig, axes = plt.subplots(nveh, 1, figsize=(7, 1.8 * nveh), sharex=True)
        for run in runs:
            for i, ax in enumerate(np.atleast_1d(axes)):
                ax.plot(run.result.time, run.result.zeta[:, i], label=run.name)
                name = model.zeta_names[i]
                ax.set_ylabel(f"{name} [{'rad/s' if name in ('p', 'q', 'r') else 'm/s'}]")
        np.atleast_1d(axes)[0].set_title(f"{title}: vehicle body rates")
        np.atleast_1d(axes)[0].legend(fontsize=7)
        np.atleast_1d(axes)[-1].set_xlabel("t [s]")
        paths.append(save(fig, directory / "vehicle_rates.png"))

    n = int(model.n_joints)
    fig, axes = plt.subplots(n, 1, figsize=(7, 1.6 * n), sharex=True)
    lower = np.asarray(model.joint_lower, dtype=np.float64)
    upper = np.asarray(model.joint_upper, dtype=np.float64)
    for run in runs:
        for i, ax in enumerate(np.atleast_1d(axes)):
            ax.plot(run.result.time_states, run.result.joints[:, i], label=run.name)
    for i, ax in enumerate(np.atleast_1d(axes)):
        for bound in (lower[i], upper[i]):
            if np.isfinite(bound):
                ax.axhline(bound, color="k", linestyle="--", linewidth=0.8)
        ax.set_ylabel(f"{model.joint_names[i]} [rad]")
    np.atleast_1d(axes)[0].set_title(f"{title}: joints (dashed: limits)")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    np.atleast_1d(axes)[-1].set_xlabel("t [s]")
    paths.append(save(fig, directory / "joints.png"))

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for run in runs:
        r = run.result
        ax1.plot(r.time_states, r.manipulability, label=run.name)
        err = np.linalg.norm(r.ee_position - r.target_position, axis=1)
        ax2.plot(r.time_states, err, label=run.name)
    ax1.set_ylabel("manipulability")
    ax1.set_title(f"{title}: manipulability and tool error")
    ax1.legend(fontsize=7)
    ax2.set_ylabel("tool error [m]")
    ax2.set_yscale("symlog", linthresh=1e-4)
    ax2.set_xlabel("t [s]")
    paths.append(save(fig, directory / "manipulability_tracking.png"))

    keys = sorted({key for run in runs for key in run.info if key != "manipulability"})
    if keys:
        fig, axes = plt.subplots(len(keys), 1, figsize=(7, 1.5 * len(keys) + 0.6), sharex=True,
                                 squeeze=False)
        for ax, key in zip(axes[:, 0], keys, strict=True):
            for run in runs:
                if key in run.info:
                    ax.plot(run.result.time, run.info[key], label=run.name)
            ax.set_ylabel(key, fontsize=7)
        axes[0, 0].set_title(f"{title}: scheme diagnostics")
        axes[0, 0].legend(fontsize=7)
        axes[-1, 0].set_xlabel("t [s]")
        paths.append(save(fig, directory / "scheme_diagnostics.png"))

    if model.vehicle_kind in ("planar", "spatial"):
        paths.append(_snapshots(plt, comparison, model, directory / "configurations.png"))
    paths.extend(plot_paper_figures(comparison, model, directory))
    return paths


def _chain_frames(model: Any) -> list[str]:
    links = sorted((f for f in model.frames if f.startswith("link")), key=lambda f: int(f[4:]))
    return ["vehicle", "arm_base", *links, "tool"]


def _snapshots(plt: Any, comparison: Comparison, model: Any, path: Path) -> Path:
    """Configurations at evenly spaced times, one panel per scheme.

    Planar models are drawn from above (``000``, Fig. 3/6); spatial ones from the side, in the
    world x-z plane with z down (``003``, Fig. 2/4/6).
    """
    runs = comparison.runs
    frames = _chain_frames(model)
    planar = model.vehicle_kind == "planar"
    # (horizontal axis index, vertical axis index, labels, flip vertical)
    h, v = (1, 0) if planar else (0, 2)
    xlabel, ylabel = ("y (east) [m]", "x (north) [m]") if planar else ("x [m]", "z (down) [m]")
    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 4.2), squeeze=False)
    for ax, run in zip(axes[0], runs, strict=True):
        r = run.result
        picks = np.linspace(0, r.q.shape[0] - 1, SNAPSHOTS).round().astype(int)
        shades = np.linspace(0.25, 1.0, picks.size)
        for shade, k in zip(shades, picks, strict=True):
            state = model.state(r.q[k])
            pts = np.array([state.position(f) for f in frames])
            ax.plot(pts[:, h], pts[:, v], "-o", color=(0.1, 0.3, 0.8, shade), markersize=2.5)
            ax.plot(pts[:2, h], pts[:2, v], "-", color=(0.8, 0.3, 0.1, shade), linewidth=3)
        target = r.target_position
        ax.plot(target[:, h], target[:, v], "k:", linewidth=0.8)
        ax.set_title(run.name, fontsize=9)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        if not planar:
            ax.invert_yaxis()
        ax.set_aspect("equal")
    fig.suptitle(f"{comparison.scenario}: configurations (vehicle red, arm blue, later darker)")
    return save(fig, path)
