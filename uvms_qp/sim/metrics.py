"""Run metrics: the numbers ``results.json`` reports (schema in the project design notes).

All metrics are computed from the recorded series of a
:class:`~uvms_qp.sim.runner.SimulationResult` (states at ``t_k = k dt``, ``k = 0..N``, and
commands for ``k = 0..N-1``), independently of the controller's own diagnostics:

- ``ee_error_max``, ``ee_error_rms`` [m]: ``|p_tool(t_k) - p_d(t_k)|`` of the tracked frame;
- ``min_manipulability``: smallest manipulability measure along the run;
- ``vehicle_displacement_max`` [m]: largest ``|p_vehicle(t_k) - p_vehicle(0)|``;
- ``vehicle_yaw_error_final`` [rad]: ``|wrap(psi(T) - psi_c)|`` when a current heading is set;
- ``joint_limit_violation_max`` [rad]: largest excursion of a joint beyond its limits (0 if none);
- ``joint_margin_min`` [rad]: smallest distance of a joint to its nearest limit;
- ``bound_violation_max``: largest violation of a hard row (box or inequality) by a command;
- ``payload_moment_max`` [N m]: largest moment of the payload about the arm base's vertical
  axis, ``F sqrt(x_E^2 + y_E^2)``, when a payload is set (``_start``/``_final`` too);
- ``payload_objective_max`` [N m^2]: largest ``(x_E^2 + y_E^2) F``, the objective of
  Wang et al. (2017), Eq. (20), that a payload task bounds or reduces;
- ``step_time_median_us``, ``step_time_p99_us``: wall time of the controller step [us];
- ``nan_steps``: steps whose command was not finite (replaced by zero);
- ``status_counts``: steps per status; ``unproven_steps``: steps whose command is inside the hard
  set but not proven the lexicographic optimum by the optimality certificate (status
  ``unproven``; see ``docs/solver.md``);
- ``command_reversals_per_s`` (by entry of zeta), ``command_reversals_per_s_max`` and
  ``command_reversals_worst_axis`` [1/s]: how often each entry of the command reverses, counted
  after the start-up transient (the first :data:`TRANSIENT` seconds) and divided by the time
  counted (the worst axis is None when no entry reverses). A reversal
  (:func:`uvms_qp.controller.history.command_reversals`) is a change of sign from one command to
  the next with both commands above ``REVERSAL_THRESHOLD`` (1 %) of the entry's bound
  (:func:`axis_bounds`): noise around zero is not a reversal, nor is a smooth change of
  direction (it passes through the small values), while a command that bangs between its bounds
  reverses every step (1 / dt per second);
- ``command_change_max`` [m/s^2, rad/s^2] (by unit): the largest ``|zeta_k - zeta_{k-1}| / dt``
  of the entries of each unit, from rest (``zeta_{-1} = 0``): what the vehicle's thrusters and
  the arm's actuators would have to deliver;
- ``settling_time`` [s] (by regulated task): the time after which the task's error norm stays
  within :data:`SETTLING_FRACTION` of its largest value (or below :data:`SETTLING_FLOOR`), None
  when the run ends outside that band.

Scenario phases (``[[phases]]``) get the same quantities restricted to their time window.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray
from ..controller.history import command_reversals
from .current import wrap_angle

if TYPE_CHECKING:  # pragma: no cover
    from .runner import SimulationResult

#: Start-up transient [s] left out of the reversal counts.
TRANSIENT = 1.0
#: Settling band: fraction of the largest error norm of the run.
SETTLING_FRACTION = 0.02
#: Settling band floor [the task's error unit]: errors below it count as settled.
SETTLING_FLOOR = 1e-6


def _finite_max(values: FloatArray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.max()) if finite.size else None


def _finite_min(values: FloatArray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.min()) if finite.size else None


def _rms(values: FloatArray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(math.sqrt(float(np.mean(finite * finite)))) if finite.size else None


def axis_bounds(zeta: FloatArray, lower: FloatArray, upper: FloatArray) -> FloatArray:
    """The bound of each entry of the command (nv,) [m/s, rad/s], the scale of its reversals.

    The median over the steps of ``max(|lower_k|, |upper_k|)`` of the hard box's finite sides
    (the rate bound the entry works against, robust to the steps where a position limit
    narrows the box); for an entry the box never bounds, the largest ``|zeta_k|`` of the run.

    Args:
        zeta: Commands (N, nv).
        lower: Box lower bounds per step (N, nv) (``-inf`` where none).
        upper: Box upper bounds per step (N, nv) (``+inf`` where none).
    """
    if zeta.shape[0] == 0:
        return np.zeros(zeta.shape[1])
    low, high = np.abs(lower), np.abs(upper)
    low[~np.isfinite(low)] = np.nan
    high[~np.isfinite(high)] = np.nan
    widest = np.fmax(low, high)  # the finite side where only one is
    bounds = np.full(zeta.shape[1], np.nan)
    bounded = np.isfinite(widest).any(axis=0)
    if bounded.any():
        bounds[bounded] = np.nanmedian(widest[:, bounded], axis=0)
    peak = np.abs(np.where(np.isfinite(zeta), zeta, 0.0)).max(axis=0)
    return np.asarray(np.where(np.isfinite(bounds), bounds, peak), dtype=np.float64)


def reversal_metrics(result: SimulationResult, steps: NDArray[np.bool_]) -> dict[str, Any]:
    """``command_reversals_per_s`` (by entry), its maximum and worst entry over ``steps``.

    The counts are divided by the time the selected steps span (``count * dt``); None when no
    step is selected. The worst entry is None when no entry reverses (every rate 0).
    """
    selected = int(np.count_nonzero(steps))
    names = list(result.zeta_names)
    if selected == 0 or not names:
        return {"command_reversals_per_s": None, "command_reversals_per_s_max": None,
                "command_reversals_worst_axis": None}
    bounds = axis_bounds(result.zeta, result.zeta_lower, result.zeta_upper)
    counts = command_reversals(result.zeta[steps], bounds)
    rates = counts / (selected * result.dt)
    worst = int(np.argmax(rates))
    return {
        "command_reversals_per_s": dict(zip(names, rates.tolist(), strict=True)),
        "command_reversals_per_s_max": float(rates[worst]),
        "command_reversals_worst_axis": names[worst] if rates[worst] > 0.0 else None,
    }


def command_change_max(result: SimulationResult) -> dict[str, float]:
    """Largest ``|zeta_k - zeta_{k-1}| / dt`` per unit group, from rest (``zeta_{-1} = 0``).

    Returns:
        ``{"m/s^2": ..., "rad/s^2": ...}`` (the units present in the command).
    """
    zeta = result.zeta
    if zeta.shape[0] == 0:
        return {}
    change = np.abs(np.diff(zeta, axis=0, prepend=np.zeros((1, zeta.shape[1])))) / result.dt
    peak = np.where(np.isfinite(change), change, 0.0).max(axis=0)
    out: dict[str, float] = {}
    for unit, value in zip(result.zeta_units, peak.tolist(), strict=True):
        key = f"{unit}^2"
        out[key] = max(out.get(key, 0.0), value)
    return out


def settling_time(time: FloatArray, errors: FloatArray) -> float | None:
    """Time [s] after which ``errors`` stays within the settling band, or None.

    The band is ``max(SETTLING_FRACTION * max(errors), SETTLING_FLOOR)``; None when the last
    error is outside it (not settled) or no error is finite.
    """
    finite = np.isfinite(errors)
    if not finite.any():
        return None
    band = max(SETTLING_FRACTION * float(errors[finite].max()), SETTLING_FLOOR)
    outside = np.flatnonzero(~(errors <= band))  # NaN counts as outside
    if outside.size == 0:
        return float(time[0])
    last = int(outside[-1])
    return None if last == errors.shape[0] - 1 else float(time[last + 1])


def settling_times(result: SimulationResult) -> dict[str, float | None]:
    """:func:`settling_time` of every regulated task of the run, by task name."""
    return {name: settling_time(result.time_states, errors)
            for name, errors in result.task_errors.items()}


def ee_errors(result: SimulationResult) -> FloatArray:
    """Tool position error ``|p_tool - p_d|`` per state (N+1,) [m]; NaN where no target."""
    return np.asarray(
        np.linalg.norm(result.ee_position - result.target_position, axis=1), dtype=np.float64
    )


def joint_excursion(result: SimulationResult) -> FloatArray:
    """Signed distance of every joint to its nearest limit (N+1, n_joints) [rad].

    Positive inside the limits, negative outside (the amount of violation).
    """
    lower = result.joint_lower[None, :]
    upper = result.joint_upper[None, :]
    return np.asarray(
        np.minimum(result.joints - lower, upper - result.joints), dtype=np.float64
    )


def yaw_errors(result: SimulationResult) -> FloatArray | None:
    """``wrap(psi - psi_c)`` per state [rad], or None without a heading or a yawing vehicle."""
    if result.heading is None or result.yaw is None:
        return None
    return np.array([wrap_angle(float(y) - result.heading) for y in result.yaw])


def _window_metrics(
    result: SimulationResult, mask: NDArray[np.bool_], origin: int
) -> dict[str, Any]:
    """Metrics of the states selected by ``mask``; displacement measured from state ``origin``."""
    errors = ee_errors(result)[mask]
    vehicle = result.vehicle_position
    displacement = np.linalg.norm(vehicle[mask] - vehicle[origin], axis=1)
    margins = joint_excursion(result)[mask]
    metrics: dict[str, Any] = {
        "ee_error_max": _finite_max(errors),
        "ee_error_rms": _rms(errors),
        "ee_error_final": None if errors.size == 0 else _finite_max(errors[-1:]),
        "min_manipulability": _finite_min(result.manipulability[mask]),
        "vehicle_displacement_max": float(displacement.max()) if displacement.size else 0.0,
        "joint_limit_violation_max": float(max(0.0, -float(margins.min())))
        if margins.size
        else 0.0,
        "joint_margin_min": float(margins.min()) if margins.size else None,
    }
    yaw = yaw_errors(result)
    if yaw is not None:
        selected = yaw[mask]
        metrics["vehicle_yaw_error_final"] = float(abs(selected[-1])) if selected.size else None
        metrics["vehicle_yaw_error_max"] = float(np.abs(selected).max()) if selected.size else None
    if result.payload_moment is not None:
        moments = result.payload_moment[mask]
        metrics["payload_moment_max"] = _finite_max(moments)
        metrics["payload_moment_start"] = float(moments[0]) if moments.size else None
        metrics["payload_moment_final"] = float(moments[-1]) if moments.size else None
    if result.payload_objective is not None:
        objective = result.payload_objective[mask]
        metrics["payload_objective_max"] = _finite_max(objective)
        metrics["payload_objective_start"] = float(objective[0]) if objective.size else None
        metrics["payload_objective_final"] = float(objective[-1]) if objective.size else None
    return metrics


def compute_metrics(result: SimulationResult) -> dict[str, Any]:
    """Return the run metrics (see the module docstring); ``None`` where not applicable."""
    everything = np.ones(result.time_states.shape[0], dtype=bool)
    metrics = _window_metrics(result, everything, 0)
    metrics["bound_violation_max"] = (
        float(result.bound_violation.max()) if result.bound_violation.size else 0.0
    )
    times_us = result.step_time * 1e6
    metrics["step_time_median_us"] = float(np.median(times_us)) if times_us.size else None
    metrics["step_time_p99_us"] = float(np.percentile(times_us, 99)) if times_us.size else None
    metrics["nan_steps"] = int(result.nan_steps)
    statuses: dict[str, int] = {}
    for status in result.status:
        statuses[status] = statuses.get(status, 0) + 1
    metrics["status_counts"] = statuses
    metrics["unproven_steps"] = statuses.get("unproven", 0)
    steps = result.time >= TRANSIENT - 1e-9 * result.dt
    metrics.update(reversal_metrics(result, steps))
    metrics["command_change_max"] = command_change_max(result)
    metrics["settling_time"] = settling_times(result)
    if result.heading is None:
        metrics.pop("vehicle_yaw_error_final", None)
        metrics.pop("vehicle_yaw_error_max", None)
    return metrics


def phase_metrics(result: SimulationResult, start: float, end: float) -> dict[str, Any]:
    """Metrics of the states with ``start <= t <= end`` [s] (displacement from the first one)."""
    t = result.time_states
    eps = 1e-9 * max(1.0, float(t[-1]))
    mask = (t >= start - eps) & (t <= end + eps)
    if not mask.any():
        return {}
    origin = int(np.flatnonzero(mask)[0])
    metrics = _window_metrics(result, mask, origin)
    steps = mask[:-1]
    if result.bound_violation.size and steps.any():
        metrics["bound_violation_max"] = float(result.bound_violation[steps].max())
    if result.vehicle_speed.size and steps.any():
        metrics["vehicle_speed_max"] = float(result.vehicle_speed[steps].max())
    metrics.update(reversal_metrics(result, steps))
    return metrics
