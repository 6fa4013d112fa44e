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
  ``003_229789978cc4b235.txt``, Eq. (20), that a payload task bounds or reduces;
- ``step_time_median_us``, ``step_time_p99_us``: wall time of the controller step [us];
- ``nan_steps``: steps whose command was not finite (replaced by zero);
- ``status_counts``: steps per status; ``unproven_steps``: steps whose command is inside the hard
  set but not proven the lexicographic optimum by the optimality certificate (status
  ``unproven``; see ``docs/solver.md``).

Scenario phases (``[[phases]]``) get the same quantities restricted to their time window.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray
from .current import wrap_angle

if TYPE_CHECKING:  # pragma: no cover
    from .runner import SimulationResult


def _finite_max(values: FloatArray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.max()) if finite.size else None


def _finite_min(values: FloatArray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.min()) if finite.size else None


def _rms(values: FloatArray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(math.sqrt(float(np.mean(finite * finite)))) if finite.size else None


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
    return metrics
