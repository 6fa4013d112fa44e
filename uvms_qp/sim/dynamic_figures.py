"""Figures of a run on the dynamic plant (PNG, headless), beside the run's other figures.

- ``thrusters.png``: each thruster's force with its forward and reverse limits (dashed), and the
  electrical power of all thrusters;
- ``velocity_tracking.png``: the vehicle's body velocity against the controller's reference, one
  panel per actuated DOF, sampled at every servo tick;
- ``attitude_disturbance.png``: roll and pitch of the vehicle, and the unmet part of the demanded
  wrench (what the thrusters could not give);
- ``joint_torques.png``: the torque each joint servo produced.

Dotted vertical lines mark the scenario's events and the payload's pick-up.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

from ._figures import Builder, pyplot, time_axis

if TYPE_CHECKING:  # pragma: no cover
    from .dynamic_plant import DynamicSeries
    from .runner import SimulationResult

_NU = ("u", "v", "w", "p", "q", "r")
_UNITS = {"u": "m/s", "v": "m/s", "w": "m/s", "p": "rad/s", "q": "rad/s", "r": "rad/s"}


def _marks(ax: Any, result: SimulationResult) -> None:
    for event in result.events:
        ax.axvline(event["time"], color="0.6", linestyle=":", linewidth=1.0)
    series: DynamicSeries = result.dynamics
    if series.payload_time is not None:
        ax.axvline(series.payload_time, color="tab:brown", linestyle=":", linewidth=1.0,
                   label="payload taken")


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
    axes[0].legend(loc="upper right", fontsize="x-small", ncol=5)
    axes[1].plot(series.time, series.power, color="tab:red")
    axes[1].set_ylabel("power [W]")
    time_axis(axes[1])
    for ax in axes:
        _marks(ax, result)
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
    axes[0, 0].legend(loc="upper right", fontsize="small")
    time_axis(axes[-1, 0])
    fig.suptitle(f"{result.scenario}: vehicle body velocity against the controller's reference")
    return fig


def _attitude(result: SimulationResult) -> Any:
    series: DynamicSeries = result.dynamics
    plt = pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    t = result.time_states
    axes[0].plot(t, np.degrees(result.eta[:, 3]), label="roll phi")
    axes[0].plot(t, np.degrees(result.eta[:, 4]), label="pitch theta")
    axes[0].set_ylabel("attitude [deg]")
    axes[0].legend(loc="best", fontsize="small")
    unmet = np.abs(series.wrench_unmet)
    axes[1].plot(series.time, np.linalg.norm(unmet[:, :3], axis=1), label="force [N]")
    axes[1].plot(series.time, np.linalg.norm(unmet[:, 3:], axis=1), label="moment [N m]")
    axes[1].set_ylabel("unmet wrench")
    axes[1].legend(loc="best", fontsize="small")
    time_axis(axes[1])
    for ax in axes:
        _marks(ax, result)
    fig.suptitle(f"{result.scenario}: roll and pitch disturbance, wrench the thrusters lacked")
    return fig


def _joint_torques(result: SimulationResult) -> Any:
    series: DynamicSeries = result.dynamics
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9, 3.8))
    for i, name in enumerate(result.joint_names):
        ax.plot(series.time, series.joint_torque[:, i], label=name, linewidth=1.0)
    ax.set_ylabel("joint torque [N m]")
    ax.legend(loc="best", fontsize="small")
    time_axis(ax)
    _marks(ax, result)
    fig.suptitle(f"{result.scenario}: torques of the arm's joint servos")
    return fig


def dynamic_builders(result: SimulationResult) -> Iterator[tuple[str, Builder]]:
    """The dynamic run's figures as ``(file name, builder)`` (none for a kinematic run)."""
    series = result.dynamics
    if series is None or not series.time.size:
        return
    yield "thrusters.png", lambda: _thrusters(result)
    yield "velocity_tracking.png", lambda: _velocity_tracking(result)
    if result.eta.shape[1] == 6:
        yield "attitude_disturbance.png", lambda: _attitude(result)
    if series.joint_torque.shape[1]:
        yield "joint_torques.png", lambda: _joint_torques(result)
