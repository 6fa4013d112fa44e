"""Figures of a run on the dynamic plant (PNG, headless), beside the run's other figures.

- ``thrusters.png``: each thruster's force with its forward and reverse limits (dashed), and the
  electrical power of all thrusters;
- ``velocity_tracking.png``: the vehicle's body velocity against the controller's reference, one
  panel per actuated DOF, sampled at every servo tick;
- ``attitude_disturbance.png``: roll and pitch of the vehicle, and the unmet part of the demanded
  wrench (what the thrusters could not give);
- ``joint_torques.png``: the torque each joint servo produced;
- ``against_kinematic.png`` (given the kinematic run of the same scenario): the tool's error, the
  vehicle's position and its pitch on both plants.

Dotted vertical lines mark the scenario's events and the payload's pick-up, each named in the
figure's legend.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

from ._figures import Builder, legend, mark_events, pyplot, time_axis
from .metrics import ee_errors

if TYPE_CHECKING:  # pragma: no cover
    from .dynamic_plant import DynamicSeries
    from .runner import SimulationResult

_NU = ("u", "v", "w", "p", "q", "r")
_UNITS = {"u": "m/s", "v": "m/s", "w": "m/s", "p": "rad/s", "q": "rad/s", "r": "rad/s"}


def _marks(ax: Any, result: SimulationResult) -> None:
    mark_events(ax, result.events, result.dynamics.payload_time)


def _thrusters(result: SimulationResult) -> Any:
    series: DynamicSeries = result.dynamics
    plt = pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True,
                             gridspec_kw={"height_ratios": [3, 1]})
    for i, name in enumerate(series.thruster_names):
        axes[0].plot(series.time, series.thrust[:, i], label=name, linewidth=1.0)
    axes[0].axhline(float(series.thrust_upper.min()), color="k", linestyle="--", linewidth=0.8,
                    label="forward limit")
    axes[0].axhline(float(series.thrust_lower.max()), color="0.4", linestyle="--",
                    linewidth=0.8, label="reverse limit")
    axes[0].set_ylabel("thrust [N]")
    axes[1].plot(series.time, series.power, color="k", label="all thrusters")
    axes[1].set_ylabel("power [W]")
    time_axis(axes[1])
    for ax in axes:
        _marks(ax, result)
        legend(ax, loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="x-small")
    fig.suptitle(f"{result.scenario}: thruster forces and electrical power "
                 f"({series.energy[-1]:.0f} J in all)" if series.energy.size else
                 f"{result.scenario}: thruster forces")
    return fig


def _velocity_tracking(result: SimulationResult) -> Any:
    series: DynamicSeries = result.dynamics
    plt = pyplot()
    dofs = list(series.actuated)
    fig, axes = plt.subplots(len(dofs), 1, figsize=(9, 1.6 * len(dofs) + 1.0), sharex=True,
                             squeeze=False)
    for row, name in enumerate(dofs):
        ax = axes[row, 0]
        j = _NU.index(name)
        ax.plot(series.time, series.velocity_reference[:, j], color="k", linestyle="--",
                linewidth=1.0, label="reference")
        ax.plot(series.time, series.body_velocity[:, j], color="tab:blue", linewidth=1.0,
                label="vehicle")
        ax.set_ylabel(f"{name} [{_UNITS[name]}]")
        _marks(ax, result)
    legend(axes[0, 0], loc="upper right", fontsize="small")
    time_axis(axes[-1, 0])
    fig.suptitle(f"{result.scenario}: vehicle body velocity against the controller's reference")
    return fig


def _attitude(result: SimulationResult) -> Any:
    series: DynamicSeries = result.dynamics
    plt = pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    t = result.time_states
    axes[0].plot(t, result.eta[:, 3], label="roll phi")
    axes[0].plot(t, result.eta[:, 4], label="pitch theta")
    axes[0].set_ylabel("attitude [rad]")
    unmet = np.abs(series.wrench_unmet)
    axes[1].plot(series.time, np.linalg.norm(unmet[:, :3], axis=1), label="force [N]")
    axes[1].plot(series.time, np.linalg.norm(unmet[:, 3:], axis=1), label="moment [N m]")
    axes[1].set_ylabel("unmet wrench")
    time_axis(axes[1])
    for ax in axes:
        _marks(ax, result)
        legend(ax, loc="best", fontsize="small")
    fig.suptitle(f"{result.scenario}: roll and pitch disturbance, wrench the thrusters lacked")
    return fig


def _joint_torques(result: SimulationResult) -> Any:
    series: DynamicSeries = result.dynamics
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for i, name in enumerate(result.joint_names):
        ax.plot(series.time, series.joint_torque[:, i], label=name, linewidth=1.0)
    ax.set_ylabel("joint torque [N m]")
    time_axis(ax)
    _marks(ax, result)
    legend(ax, loc="best", fontsize="small")
    fig.suptitle(f"{result.scenario}: torques of the arm's joint servos")
    return fig


def _against_kinematic(result: SimulationResult, reference: SimulationResult) -> Any:
    plt = pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    runs = (("kinematic", reference, "0.5", "--"), ("dynamic", result, "tab:blue", "-"))
    for label, run, colour, style in runs:
        axes[0].semilogy(run.time_states, np.maximum(ee_errors(run), 1e-9), color=colour,
                         linestyle=style, label=label)
        for i, axis in enumerate("xyz"):
            axes[1].plot(run.time_states, run.vehicle_position[:, i], color=colour,
                         linestyle=style, alpha=(0.5 + 0.25 * i), label=f"{axis} ({label})")
        axes[2].plot(run.time_states, run.eta[:, 4], color=colour, linestyle=style,
                     label=f"pitch ({label})")
    axes[0].set_ylabel("tool error [m]")
    axes[1].set_ylabel("vehicle position [m]")
    axes[2].set_ylabel("pitch [rad]")
    time_axis(axes[2])
    for ax in axes:
        _marks(ax, result)
        legend(ax, loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize="x-small")
    fig.suptitle(f"{result.scenario}: the floating vehicle against the kinematic run")
    return fig


def dynamic_builders(result: SimulationResult, reference: SimulationResult | None = None
                     ) -> Iterator[tuple[str, Builder]]:
    """The dynamic run's figures as ``(file name, builder)`` (none for a kinematic run).

    ``reference``: the kinematic run of the same scenario, drawn beside the dynamic one in
    ``against_kinematic.png`` (tool error, vehicle position, pitch).
    """
    series = result.dynamics
    if series is None or not series.time.size:
        return
    if reference is not None and result.eta.shape[1] == 6:
        yield "against_kinematic.png", lambda: _against_kinematic(result, reference)
    yield "thrusters.png", lambda: _thrusters(result)
    yield "velocity_tracking.png", lambda: _velocity_tracking(result)
    if result.eta.shape[1] == 6:
        yield "attitude_disturbance.png", lambda: _attitude(result)
    if series.joint_torque.shape[1]:
        yield "joint_torques.png", lambda: _joint_torques(result)
