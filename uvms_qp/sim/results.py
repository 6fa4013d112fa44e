"""``results.json``: the record of one run.

Top level: ``scenario``, ``scheme``, ``solver``, ``model``, ``dt`` [s], ``steps``, ``duration``
[s], ``wall_time_s``, ``metrics`` (see :mod:`uvms_qp.sim.metrics`), ``phases`` (metrics per
scenario phase), ``events`` (applied run-time changes) and ``series``:

- per state (N+1 entries, times ``time``): ``time`` [s], ``q``, ``vehicle_pose`` (eta [m, rad]),
  ``joints`` [rad], ``ee_pose`` (tracked frame ``[x, y, z, qx, qy, qz, qw]``, world),
  ``target_position`` [m], ``manipulability``, ``payload_moment`` [N m] and
  ``payload_objective`` [N m^2] (when set);
- per step (N entries, at ``time[:N]``): ``zeta`` [m/s, rad/s] (names in ``zeta_names``),
  ``zeta_lower``/``zeta_upper`` (hard box, ``null`` = unbounded), ``step_time_us``, ``status``,
  ``level_residuals``, ``bound_violation``, ``task_residuals`` (by task name, units in
  ``task_units``), ``stage`` (fallback stage that produced the command, ``"primary"`` on the
  happy path; :data:`uvms_qp.safety.STAGES`), ``clipped`` (amount the final saturation removed
  [m/s, rad/s]) and ``deadline_missed`` (booleans).

``metrics`` also holds ``stage_counts`` (steps per stage), ``deadline_missed_steps`` and
``clipped_max``.

Non-finite numbers are written as ``null`` (strict JSON). The file is written atomically (a
temporary file renamed into place), so a failed run never leaves a partial ``results.json``.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

if TYPE_CHECKING:  # pragma: no cover
    from .runner import SimulationResult

RESULTS_FILE = "results.json"


def _clean(value: Any) -> Any:
    """Convert numpy values and non-finite floats into strict-JSON-friendly Python values."""
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.floating, float)):
        number = float(value)
        return number if math.isfinite(number) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def _ee_pose(result: SimulationResult) -> np.ndarray:
    poses = np.zeros((result.ee_position.shape[0], 7))
    poses[:, :3] = result.ee_position
    for k, R in enumerate(result.ee_rotation):
        poses[k, 3:] = pin.Quaternion(R).coeffs()  # x, y, z, w
    return poses


def results_dict(result: SimulationResult, *, series: bool = True) -> dict[str, Any]:
    """The content of ``results.json`` for one run (see the module docstring)."""
    data: dict[str, Any] = {
        "scenario": result.scenario,
        "scheme": result.scheme,
        "solver": result.solver,
        "model": result.model,
        "dt": result.dt,
        "steps": result.steps,
        "duration": result.steps * result.dt,
        "wall_time_s": result.wall_time,
        "metrics": result.metrics(),
        "phases": result.phase_metrics(),
        "events": result.events,
    }
    if series:
        record: dict[str, Any] = {
            "time": result.time_states,
            "zeta_names": list(result.zeta_names),
            "joint_names": list(result.joint_names),
            "q": result.q,
            "vehicle_pose": result.eta,
            "joints": result.joints,
            "ee_pose": _ee_pose(result),
            "target_position": result.target_position,
            "manipulability": result.manipulability,
            "zeta": result.zeta,
            "zeta_lower": result.zeta_lower,
            "zeta_upper": result.zeta_upper,
            "step_time_us": result.step_time * 1e6,
            "status": result.status,
            "level_residuals": result.level_residuals,
            "level_names": result.level_names,
            "bound_violation": result.bound_violation,
            "task_residuals": result.task_residuals,
            "task_units": result.task_units,
            "stage": result.stage,
            "clipped": result.clipped,
            "deadline_missed": result.deadline_missed,
        }
        if result.payload_moment is not None:
            record["payload_moment"] = result.payload_moment
        if result.payload_objective is not None:
            record["payload_objective"] = result.payload_objective
        data["series"] = record
    return _clean(data)  # type: ignore[no-any-return]


def write_results(result: SimulationResult, out_dir: str | Path) -> Path:
    """Write ``out_dir/results.json`` atomically and return its path."""
    directory = Path(out_dir)
    directory.mkdir(parents=True, exist_ok=True)
    target = directory / RESULTS_FILE
    text = json.dumps(results_dict(result), allow_nan=False, separators=(",", ":"))
    fd, tmp = tempfile.mkstemp(prefix=".results-", suffix=".json", dir=directory)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target
