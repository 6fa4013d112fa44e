"""Metrics of a run on the dynamic plant: what the floating vehicle and its actuators did.

Computed from the recorded series (:class:`~uvms_qp.sim.dynamic_plant.DynamicSeries`, one entry
per servo tick, and the run's states), next to the kinematic metrics of
:mod:`uvms_qp.sim.metrics`:

- ``velocity_tracking_error_rms`` and ``velocity_tracking_error_max`` (by actuated DOF, [m/s] or
  [rad/s]): ``nu_ref - nu`` at the start of every servo tick, the reference being the
  controller's command;
- ``roll_max`` and ``pitch_max`` [rad]: the largest ``|phi|`` and ``|theta|`` of the vehicle
  (the disturbance the arm's motion and a payload cause), ``roll_rms`` and ``pitch_rms`` (of
  any spatial vehicle, kinematic runs too);
- ``thrust_max`` (by thruster) [N]: the largest force magnitude; ``saturation_share`` (by
  thruster): the share of servo ticks whose allocated command sat at a force limit, and
  ``saturation_share_max``;
- ``energy`` [J]: the thrusters' electrical energy over the run; ``power_mean`` [W];
- ``joint_torque_max`` (by joint) [N m]: the largest torque a joint's servo produced (the
  parameter sets state no per-joint torque rating to hold it against);
- ``payload_mass`` [kg] (mass in air) once the tool took a payload, and ``payload_rating_share``
  (``payload_mass`` over the arm's rated payload at full reach, when the parameter set states
  one): above 1 the arm holds more than it is rated for. The run is not stopped;
  :func:`rating_notes` says so in words (a record's ``warnings``, the command line's warnings);
- ``unmet_force_max`` [N] and ``unmet_moment_max`` [N m]: the largest force and moment (norms)
  of a demanded wrench the thrusters could not give (0 when the allocation always met it).

A scenario phase gets ``roll_max``, ``pitch_max``, ``pitch_rms`` and, on a dynamic plant,
``energy`` (drawn within the window), ``power_mean`` and ``saturation_share_max`` of its window
(:func:`phase_metrics`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from .dynamic_plant import DynamicSeries
    from .runner import SimulationResult

#: Units of the actuated DOFs' velocities.
_RATE_UNITS = {"u": "m/s", "v": "m/s", "w": "m/s", "p": "rad/s", "q": "rad/s", "r": "rad/s"}
_NU = ("u", "v", "w", "p", "q", "r")


def _rounded(values: Any) -> list[float]:
    return [float(x) for x in values]


def attitude_metrics(result: SimulationResult) -> dict[str, float]:
    """``roll_max``, ``pitch_max``, ``roll_rms``, ``pitch_rms`` [rad] of a spatial vehicle."""
    eta = result.eta
    if eta.shape[1] != 6 or not eta.shape[0]:
        return {}
    roll, pitch = eta[:, 3], eta[:, 4]
    return {"roll_max": float(np.max(np.abs(roll))), "pitch_max": float(np.max(np.abs(pitch))),
            "roll_rms": float(np.sqrt(np.mean(roll * roll))),
            "pitch_rms": float(np.sqrt(np.mean(pitch * pitch)))}


def dynamic_metrics(result: SimulationResult) -> dict[str, Any]:
    """The metrics above: roll and pitch of any spatial vehicle, the rest on a dynamic plant."""
    out: dict[str, Any] = attitude_metrics(result)
    series: DynamicSeries | None = result.dynamics
    if series is None:
        return out
    ticks = series.time.shape[0]
    actuated = [_NU.index(d) for d in series.actuated]
    if ticks:
        error = series.velocity_reference[:, actuated] - series.body_velocity[:, actuated]
        rms = np.sqrt(np.mean(error * error, axis=0))
        peak = np.max(np.abs(error), axis=0)
        names = [_NU[i] for i in actuated]
        out["velocity_tracking_error_rms"] = dict(zip(names, _rounded(rms), strict=True))
        out["velocity_tracking_error_max"] = dict(zip(names, _rounded(peak), strict=True))
    names = list(series.thruster_names)
    if ticks:
        thrust = np.max(np.abs(series.thrust), axis=0)
        share = np.mean(series.saturated, axis=0)
        out["thrust_max"] = dict(zip(names, _rounded(thrust), strict=True))
        out["saturation_share"] = dict(zip(names, _rounded(share), strict=True))
        out["saturation_share_max"] = float(share.max())
        out["energy"] = float(series.energy[-1])
        duration = ticks * (result.dt * result.steps / ticks if result.steps else 0.0)
        out["power_mean"] = float(series.energy[-1] / duration) if duration > 0 else 0.0
        torque = np.max(np.abs(series.joint_torque), axis=0)
        out["joint_torque_max"] = dict(zip(result.joint_names, _rounded(torque), strict=True))
        unmet = np.abs(series.wrench_unmet)
        out["unmet_force_max"] = float(np.linalg.norm(unmet[:, :3], axis=1).max())
        out["unmet_moment_max"] = float(np.linalg.norm(unmet[:, 3:], axis=1).max())
    payload = result.plant_settings.get("payload")
    if series.payload_time is not None and payload is not None:
        out["payload_mass"] = float(payload["mass"])
        rated = result.plant_settings.get("rated_payload")
        if rated:
            out["payload_rating_share"] = float(payload["mass"]) / float(rated)
    return out


def rating_notes(metrics: dict[str, Any], plant_settings: dict[str, Any]) -> list[str]:
    """One line per rating a run exceeded: a payload beyond the arm's rated payload.

    Args:
        metrics: The run's metrics (``payload_mass``, ``payload_rating_share``).
        plant_settings: Its plant's settings (``rated_payload`` [kg]).
    """
    share = metrics.get("payload_rating_share")
    if share is None or share <= 1.0:
        return []
    rated = float(plant_settings["rated_payload"])
    return [f"the payload of {metrics['payload_mass']:g} kg exceeds the arm's rated payload of "
            f"{rated:g} kg at full reach ({100 * share:.0f} % of it); the run was not limited"]


def phase_metrics(result: SimulationResult, start: float, end: float) -> dict[str, Any]:
    """Attitude and actuator metrics of the window ``start <= t <= end`` [s] (module docstring)."""
    out: dict[str, Any] = {}
    eta, t = result.eta, result.time_states
    eps = 1e-9 * max(1.0, float(t[-1])) if t.size else 0.0
    if eta.shape[1] == 6:
        mask = (t >= start - eps) & (t <= end + eps)
        if mask.any():
            roll, pitch = eta[mask, 3], eta[mask, 4]
            out["roll_max"] = float(np.max(np.abs(roll)))
            out["pitch_max"] = float(np.max(np.abs(pitch)))
            out["pitch_rms"] = float(np.sqrt(np.mean(pitch * pitch)))
    series: DynamicSeries | None = result.dynamics
    if series is None or not series.time.size:
        return out
    ticks = (series.time >= start - eps) & (series.time < end - eps)
    if not ticks.any():
        return out
    index = np.flatnonzero(ticks)
    first, last = int(index[0]), int(index[-1])
    before = float(series.energy[first - 1]) if first else 0.0
    energy = float(series.energy[last]) - before
    span = float(series.time[last] - series.time[first]) + (
        float(series.time[1] - series.time[0]) if series.time.size > 1 else 0.0)
    out["energy"] = energy
    out["power_mean"] = energy / span if span > 0.0 else 0.0
    out["saturation_share_max"] = float(np.mean(series.saturated[ticks], axis=0).max())
    return out
