"""The source papers' own figures, drawn from a scheme comparison (matplotlib, Agg back-end).

:func:`plot_comparison <uvms_qp.sim.comparison_figures.plot_comparison>` draws the figures every
comparison has; this module adds, for the four bundled paper models, the figures a reader of each
paper knows, laid out and oriented as in the paper:

* ``soylu_planar``: ``paper000_configurations.png`` (Soylu et al. 2007, Fig. 3 and 6),
  ``paper000_states.png`` (Fig. 2 and 5), ``paper000_manipulability.png`` (Fig. 7);
* ``santos_planar``: ``paper001_configurations.png`` (dos Santos et al. 2006, Fig. 7 and 8),
  ``paper001_states.png`` (Fig. 9-14);
* ``nenchev_pa10_arm``: ``paper002_end_point.png`` (Nenchev and Tsumaki, Fig. 2 and 3, with the
  singularity crossings marked);
* ``wang_9dof``: ``paper003_<scheme>.png`` per run (Wang et al. 2017, Fig. 3, 5 and 7, panels
  (a)-(h)) and ``paper003_payload.png`` (the load's lever arms of every run).

Planar models are drawn with x to the right and y up, as in the papers. A model not in the table
gets no extra figure.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache, partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from ..analytic.singularity_consistent import singularity_crossings
from ._figures import Builder, output_dir, pyplot, write_figures

if TYPE_CHECKING:  # pragma: no cover
    from .comparison import Comparison, SchemeRun

#: Configuration snapshots drawn per run in the planar figures.
SNAPSHOTS = 7
#: Link lengths d3, d5 of the bundled ``nenchev_pa10_arm`` [m] (Nenchev and Tsumaki, Section 4).
PA10_LINKS = (1.0, 1.0)


def paper_figures(comparison: Comparison, model: Any) -> list[tuple[str, Builder]]:
    """The paper figures of ``model`` as ``(file name, builder)`` pairs (none for other models).

    Args:
        comparison: The runs to draw.
        model: The scenario's model; its name selects the paper.
    """
    figures = _PAPERS.get(getattr(model, "name", ""))
    if figures is None or not comparison.runs:
        return []
    return figures(comparison, model)


def plot_paper_figures(comparison: Comparison, model: Any, out_dir: str | Path) -> list[Path]:
    """Write the paper figures of ``model`` (none for other models); return their paths.

    Args:
        comparison: The runs to draw.
        model: The scenario's model; its name selects the paper.
        out_dir: Output directory (created if needed).
    """
    return write_figures(paper_figures(comparison, model), output_dir(out_dir))


# -- shared helpers -------------------------------------------------------------------------------


def _chain_frames(model: Any) -> list[str]:
    links = sorted((f for f in model.frames if f.startswith("link")), key=lambda f: int(f[4:]))
    return ["vehicle", "arm_base", *links, "tool"]


def _planar_snapshots(plt: Any, comparison: Comparison, model: Any, title: str,
                      decorate: Callable[[Any, SchemeRun], None] | None = None) -> Any:
    """One panel per run: configurations in the x-y plane, x to the right, y up."""
    runs = comparison.runs
    frames = _chain_frames(model)
    fig, axes = plt.subplots(1, len(runs), figsize=(4.4 * len(runs), 4.4), squeeze=False)
    for ax, run in zip(axes[0], runs, strict=True):
        r = run.result
        picks = np.linspace(0, r.q.shape[0] - 1, SNAPSHOTS).round().astype(int)
        for shade, k in zip(np.linspace(0.25, 1.0, picks.size), picks, strict=True):
            state = model.state(r.q[k])
            pts = np.array([state.position(f) for f in frames])
            ax.plot(pts[1:, 0], pts[1:, 1], "-o", color=(0.1, 0.3, 0.8, shade), markersize=2.5)
            ax.plot(pts[:2, 0], pts[:2, 1], "-", color=(0.8, 0.3, 0.1, shade), linewidth=3)
        ax.plot(r.target_position[:, 0], r.target_position[:, 1], "k:", linewidth=0.8,
                label="tool reference")
        ax.plot(r.ee_position[:, 0], r.ee_position[:, 1], "g-", linewidth=0.8, label="tool")
        ax.plot(r.vehicle_position[:, 0], r.vehicle_position[:, 1], "-", color="0.5",
                linewidth=0.8, label="vehicle centre")
        if decorate is not None:
            decorate(ax, run)
        ax.set_title(run.name, fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_aspect("equal")
        ax.grid(linewidth=0.3)
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(title, fontsize=10)
    return fig


def _overlay(axes: Any, runs: list[SchemeRun], series: Callable[[SchemeRun], tuple[Any, Any]],
             labels: list[str]) -> None:
    """Plot column i of ``series(run)`` on ``axes[i]`` for every run."""
    for run in runs:
        t, values = series(run)
        for i, ax in enumerate(axes):
            ax.plot(t, values[:, i], label=run.name)
    for ax, label in zip(axes, labels, strict=True):
        ax.set_ylabel(label, fontsize=8)
        ax.grid(linewidth=0.3)


# -- Soylu et al. (2007) ------------------------------------------------------------------------


def _soylu(comparison: Comparison, model: Any) -> list[tuple[str, Builder]]:
    return [(name, partial(draw, comparison, model)) for name, draw in (
        ("paper000_configurations.png", _soylu_configurations),
        ("paper000_states.png", _soylu_states),
        ("paper000_manipulability.png", _soylu_manipulability),
    )]


def _soylu_configurations(comparison: Comparison, model: Any) -> Any:
    return _planar_snapshots(pyplot(), comparison, model,
                             f"{comparison.scenario}: configurations (Soylu et al. 2007, Fig. 3 "
                             "and 6; vehicle red, arm blue, later darker)")


def _soylu_states(comparison: Comparison, model: Any) -> Any:
    plt = pyplot()
    runs = comparison.runs
    fig, axes = plt.subplots(3, 2, figsize=(9, 6.5), sharex=True)
    _overlay(axes[:, 0], runs, lambda run: (run.result.time_states, run.result.eta),
             ["x_v [m]", "y_v [m]", "q_v [rad]"])
    _overlay(axes[:, 1], runs, lambda run: (run.result.time_states, run.result.joints),
             ["q1 [rad]", "q2 [rad]", "q3 [rad]"])
    axes[0, 0].set_title("vehicle (URV)", fontsize=9)
    axes[0, 1].set_title("manipulator", fontsize=9)
    axes[0, 0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{comparison.scenario}: state histories (Soylu et al. 2007, Fig. 2 and 5)",
                 fontsize=10)
    return fig


def _soylu_manipulability(comparison: Comparison, model: Any) -> Any:
    plt = pyplot()
    runs = comparison.runs
    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 3.4), sharey=True,
                             squeeze=False)
    for ax, run in zip(axes[0], runs, strict=True):
        r = run.result
        ax.plot(r.time_states, r.manipulability, "b-")
        below = np.flatnonzero(r.manipulability < 0.1)
        if below.size:
            t_near = float(r.time_states[below[0]])
            ax.axvline(t_near, color="r", linestyle=":", linewidth=0.8)
            ax.annotate(f"rho < 0.1 at {t_near:.2f} s", (t_near, 0.1), fontsize=7,
                        xytext=(4, 12), textcoords="offset points", color="r")
        ax.set_title(run.name, fontsize=9)
        ax.set_xlabel("t [s]")
        ax.grid(linewidth=0.3)
    axes[0, 0].set_ylabel("measure of manipulability rho [m^2]")
    fig.suptitle(f"{comparison.scenario}: manipulability (Soylu et al. 2007, Fig. 7)",
                 fontsize=10)
    return fig


# -- dos Santos et al. (2006) -------------------------------------------------------------------


def _santos(comparison: Comparison, model: Any) -> list[tuple[str, Builder]]:
    return [(name, partial(draw, comparison, model)) for name, draw in (
        ("paper001_configurations.png", _santos_configurations),
        ("paper001_states.png", _santos_states),
    )]


def _santos_configurations(comparison: Comparison, model: Any) -> Any:
    def current(ax: Any, run: SchemeRun) -> None:
        heading = run.result.heading
        if heading is None:
            return
        x0, y0 = run.result.vehicle_position[0, :2]
        ax.annotate("", xy=(x0 + 2.0 * np.cos(heading), y0 + 2.0 * np.sin(heading)),
                    xytext=(x0, y0), arrowprops={"arrowstyle": "->", "color": "c"})
        ax.text(x0 + 2.0 * np.cos(heading), y0 + 2.0 * np.sin(heading),
                f" current {heading:.2f} rad", fontsize=7, color="c")

    return _planar_snapshots(pyplot(), comparison, model,
                             f"{comparison.scenario}: configurations, circle and current "
                             "(dos Santos et al. 2006, Fig. 7 and 8)", current)


def _santos_states(comparison: Comparison, model: Any) -> Any:
    plt = pyplot()
    runs = comparison.runs
    nveh = int(model.n_vehicle)
    fig, axes = plt.subplots(3, 3, figsize=(11, 6.5), sharex=True)
    _overlay(axes[:, 0], runs, lambda run: (run.result.time_states, run.result.eta),
             ["x [m]", "y [m]", "psi [rad]"])
    _overlay(axes[:, 1], runs, lambda run: (run.result.time_states, run.result.joints),
             ["q1 [rad]", "q2 [rad]", "q3 [rad]"])
    _overlay(axes[:, 2], runs, lambda run: (run.result.time, run.result.zeta[:, :nveh]),
             ["u [m/s]", "v [m/s]", "r [rad/s]"])
    for ax, title in zip(axes[0], ("vehicle pose (Fig. 9, 12)", "joints (Fig. 10, 13)",
                                   "vehicle rates (Fig. 11, 14)"), strict=True):
        ax.set_title(title, fontsize=9)
    axes[0, 0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{comparison.scenario}: state histories (dos Santos et al. 2006)", fontsize=10)
    return fig


# -- Nenchev and Tsumaki ------------------------------------------------------------------------


def _nenchev(comparison: Comparison, model: Any) -> list[tuple[str, Builder]]:
    return [("paper002_end_point.png", partial(_nenchev_end_point, comparison, model))]


def _nenchev_end_point(comparison: Comparison, model: Any) -> Any:
    plt = pyplot()
    runs = comparison.runs
    fig, axes = plt.subplots(2, len(runs), figsize=(4.6 * len(runs), 6), sharex="col",
                             squeeze=False)
    for col, run in enumerate(runs):
        r = run.result
        top, bottom = axes[0, col], axes[1, col]
        for i, (axis, style) in enumerate(zip("xyz", ("-", "--", ":"), strict=True)):
            top.plot(r.time_states, r.ee_position[:, i], style, label=axis)
        for i in range(r.joints.shape[1]):
            bottom.plot(r.time_states, np.degrees(r.joints[:, i]), label=f"q{i + 1}")
        for t_cross, kind in _distinct(singularity_crossings(r.joints, r.time_states,
                                                             *PA10_LINKS)):
            for ax in (top, bottom):
                ax.axvline(t_cross, color="r" if kind != "shoulder" else "m", linewidth=0.7,
                           linestyle="--")
            top.annotate(f"{kind} {t_cross:.2f} s", (t_cross, 0.98), fontsize=6, rotation=90,
                         va="top", ha="right", xycoords=("data", "axes fraction"))
        top.set_title(run.name, fontsize=9)
        top.set_ylabel("end point (wrist centre) [m]")
        bottom.set_ylabel("joint angles [deg]")
        bottom.set_xlabel("t [s]")
        for ax in (top, bottom):
            ax.grid(linewidth=0.3)
            ax.legend(fontsize=7, loc="lower left")
    fig.suptitle(f"{comparison.scenario}: end point and joints (Nenchev and Tsumaki, Fig. 2/3)"
                 "\ndashed: singularities crossed (a run that dwells at one: first crossing only)",
                 fontsize=9)
    return fig


def _distinct(events: list[tuple[float, str]], gap: float = 0.1) -> list[tuple[float, str]]:
    """Crossings without the repeats of one kind within ``gap`` [s] of the previous one.

    A controller dwelling at a singularity (e.g. at the workspace boundary) dithers through it.
    """
    kept: list[tuple[float, str]] = []
    last: dict[str, float] = {}
    for t, kind in events:
        if t - last.get(kind, -np.inf) >= gap:
            kept.append((t, kind))
        last[kind] = t
    return kept


# -- Wang et al. (2017) -------------------------------------------------------------------------


def payload_lever_arms(result: Any, model: Any, frame: str = "tool") -> FloatArray:
    """Lever arms of a load at the tool, per recorded state (N+1, 3) [m].

    Columns: the Eq. (20) lever ``sqrt(x_E^2 + y_E^2)`` in the arm base frame (Wang et al. 2017:
    ``M = lever^2 F``), and the tool's x and y in the vehicle frame, which give the load's pitch
    and roll moments about the vehicle origin (:func:`uvms_qp.analytic.vehicle_payload_moment`:
    ``m = (y F, -x F)``).
    """
    out = np.empty((result.q.shape[0], 3))
    for k, q in enumerate(result.q):
        state = model.state(q)
        base = state.pose_in(frame, "arm_base")[:3, 3]
        body = state.pose_in(frame, "vehicle")[:3, 3]
        out[k] = (np.hypot(base[0], base[1]), body[0], body[1])
    return out


def _rate(values: FloatArray, t: FloatArray) -> FloatArray:
    """Rate of a sampled series, one row per step: forward differences, as Euler integrates."""
    return np.diff(values, axis=0) / np.diff(t)[:, None]


def _wang(comparison: Comparison, model: Any) -> list[tuple[str, Builder]]:
    @cache
    def levers(name: str) -> FloatArray:
        return payload_lever_arms(comparison.run(name).result, model)

    figures: list[tuple[str, Builder]] = [
        (f"paper003_{run.name}.png", partial(_wang_run, comparison, model, run, levers))
        for run in comparison.runs
    ]
    figures.append(("paper003_payload.png", partial(_wang_payload, comparison, levers)))
    return figures


def _wang_run(comparison: Comparison, model: Any, run: SchemeRun,
              levers: Callable[[str], FloatArray]) -> Any:
    """Panels (a)-(h) of Wang et al. (2017), Fig. 3/5/7 for one run."""
    plt = pyplot()
    nveh = int(model.n_vehicle)
    lower = np.degrees(np.asarray(model.joint_lower, dtype=np.float64))
    upper = np.degrees(np.asarray(model.joint_upper, dtype=np.float64))
    r = run.result
    fig, axes = plt.subplots(4, 2, figsize=(11, 11), sharex=True)
    (a, b), (c, d), (e, f), (g, h) = axes
    desired_rate = _rate(r.target_position, r.time_states)
    actual_rate = _rate(r.ee_position, r.time_states)
    for i, axis in enumerate("xyz"):
        line = a.plot(r.time_states, r.target_position[:, i], "-", label=f"{axis} desired")[0]
        a.plot(r.time_states, r.ee_position[:, i], "--", color=line.get_color(),
               label=f"{axis} planned")
        b.plot(r.time, desired_rate[:, i], "-", color=line.get_color(),
               label=f"{axis}' desired")
        b.plot(r.time, actual_rate[:, i], "--", color=line.get_color(),
               label=f"{axis}' planned")
    a.set_ylabel("(a) tool position [m]")
    b.set_ylabel("(b) tool velocity [m/s]")
    pose_labels = ("x", "y", "z", "phi", "theta", "psi")
    for i in (0, 1, 2, 5):
        c.plot(r.time_states, r.eta[:, i], label=f"{pose_labels[i]} [m or rad]")
    c.set_ylabel("(c) vehicle pose")
    for i in range(r.joints.shape[1]):
        line = d.plot(r.time_states, np.degrees(r.joints[:, i]), label=f"q{i + 1}")[0]
        for bound in (lower[i], upper[i]):
            d.axhline(bound, color=line.get_color(), linestyle=":", linewidth=0.6)
    d.set_ylabel("(d) joints [deg] (dotted: limits)")
    for i in range(nveh):
        e.plot(r.time, r.zeta[:, i], label=model.zeta_names[i])
    e.set_ylabel("(e) vehicle rates [m/s, rad/s]")
    for i in range(nveh, r.zeta.shape[1]):
        f.plot(r.time, np.degrees(r.zeta[:, i]), label=model.zeta_names[i])
    f.set_ylabel("(f) joint rates [deg/s]")
    mom = r.manipulability / r.manipulability[0]
    g.plot(r.time_states, mom, "b-", label="MOM / MOM(0)")
    g.set_ylabel("(g) normalised MOM")
    g2 = g.twinx()
    lever = levers(run.name)
    g2.plot(r.time_states, lever[:, 0], "r-", linewidth=0.8, label="Eq. 20 lever [m]")
    g2.plot(r.time_states, lever[:, 1], "r--", linewidth=0.8,
            label="nose-down moment per N [m]")
    g2.legend(fontsize=6, loc="lower right")
    for key in ("alpha_1", "alpha_2", "beta"):
        if key in run.info:
            h.plot(r.time, run.info[key], label=key)
    h.set_ylabel("(h) fuzzy outputs")
    h.set_ylim(-0.05, 1.05)
    for ax in axes.flat:
        ax.grid(linewidth=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6, loc="upper right", ncol=2)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"{comparison.scenario}, {run.name} (Wang et al. 2017, Fig. 3/5/7 (a)-(h); "
                 "solid desired, dashed planned)\nfuzzy rule base and arm mount: this "
                 "library's own (the paper prints neither)", fontsize=10)
    return fig


def _wang_payload(comparison: Comparison, levers: Callable[[str], FloatArray]) -> Any:
    """The load's lever arms of every run."""
    plt = pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for run in comparison.runs:
        lever = levers(run.name)
        top.plot(run.result.time_states, lever[:, 0], label=run.name)
        bottom.plot(run.result.time_states, lever[:, 1], label=run.name)
    top.set_ylabel("Eq. 20 lever sqrt(x_E^2 + y_E^2) [m]")
    bottom.set_ylabel("nose-down moment per newton [N m / N]")
    bottom.set_xlabel("t [s]")
    for ax in (top, bottom):
        ax.grid(linewidth=0.3)
    top.legend(fontsize=7)
    top.set_title(f"{comparison.scenario}: lever arms of a load at the tool "
                  "(arm base frame; vehicle origin, nose-down positive)", fontsize=9)
    return fig


_PAPERS: dict[str, Callable[[Any, Any], list[tuple[str, Builder]]]] = {
    "soylu_planar": _soylu,
    "santos_planar": _santos,
    "nenchev_pa10_arm": _nenchev,
    "wang_9dof": _wang,
}
