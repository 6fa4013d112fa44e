"""``results.json``: the record of one run.

Top level: ``scenario``, ``scheme``, ``solver``, ``model``, ``plant`` (``"kinematic"`` or
``"dynamic"``) with ``plant_settings`` (its parameter set and source, the arm's rated payload,
rates, coordination, feed-forward, payload, gains), ``warnings`` (only when a run exceeded a
rating, e.g. a payload beyond the arm's rated payload: one sentence each) and ``sensors`` (noise
and delay, ``null`` when exact), ``dt`` [s],
``steps``, ``duration`` [s], ``wall_time_s``, ``metrics`` (see
:mod:`uvms_qp.sim.metrics`; a dynamic run adds :mod:`uvms_qp.sim.dynamic_metrics`), ``phases``
(metrics per scenario phase), ``events`` (applied run-time changes), ``stopped`` (only when the run
ended early: ``time`` [s], ``step`` and ``error``), ``kinematic_reference`` (a dynamic run's record
of the kinematic run of the same scenario: its ``metrics`` and ``wall_time_s``) and ``series``:

- per state (N+1 entries, times ``time``): ``time`` [s], ``q``, ``vehicle_pose`` (eta [m, rad]),
  ``joints`` [rad or m, ``joint_units``], ``ee_pose`` (tracked frame
  ``[x, y, z, qx, qy, qz, qw]``, world), ``target_position`` [m], ``manipulability``
  [``manipulability_unit``], ``manipulability_floor`` (with a floor task), ``payload_moment``
  [N m] and ``payload_objective`` [N m^2] (when set), ``task_errors`` (error norm of every
  regulated task, by name; units in ``task_error_units``);
- per step (N entries, at ``time[:N]``): ``zeta`` (names in ``zeta_names``, units in
  ``zeta_units``: m/s, rad/s),
  ``zeta_lower``/``zeta_upper`` (hard box, ``null`` = unbounded), ``step_time_us``, ``status``,
  ``level_residuals``, ``bound_violation``, ``task_residuals`` (by task name, units in
  ``task_units``), ``stage`` (fallback stage that produced the command, ``"primary"`` on the
  happy path; :data:`uvms_qp.safety.STAGES`), ``clipped`` (amount the final saturation removed
  [m/s, rad/s]) and ``deadline_missed`` (booleans);
- ``command_rate_limit``: the acceleration bound of each entry of zeta [m/s^2, rad/s^2] of the
  stack's command-rate bounds (``null`` where none), when the stack has them;
- ``dynamics`` (dynamic plant): the servo-rate record
  (:class:`~uvms_qp.sim.dynamic_plant.DynamicSeries`: thruster forces, commands and limits,
  saturation, power and energy, demanded and unmet wrenches, true and reference body velocity,
  joint rates, references and torques).

``metrics`` also holds ``stage_counts`` (steps per stage), ``deadline_missed_steps`` and
``clipped_max``.

``provenance`` (:func:`provenance`) says where the record comes from: the versions of the package,
of Pinocchio, numpy, scipy, qpsolvers and every solver back-end, Python, the platform, the date
(UTC) and the command line.

Non-finite numbers are written as ``null`` (strict JSON). The file is written atomically (a
temporary file renamed into place, mode 0644), so a failed run never leaves a partial
``results.json`` and a ``results.json`` that is a symbolic link is replaced, not followed.
"""

from __future__ import annotations

import datetime
import json
import math
import platform
import shlex
import sys
from collections.abc import Sequence
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .. import __version__
from ._files import write_atomic
from .dynamic_metrics import rating_notes

if TYPE_CHECKING:  # pragma: no cover
    from .runner import SimulationResult

RESULTS_FILE = "results.json"
#: Distributions whose versions the provenance block records: the package, its numerical and
#: kinematics libraries and every solver back-end (None when not installed).
PROVENANCE_PACKAGES = ("uvms-qp", "numpy", "scipy", "pin", "qpsolvers", "daqp", "proxsuite",
                       "osqp", "clarabel", "quadprog", "piqp", "highspy")


def command_line(argv: Sequence[str] | None = None) -> str:
    """``argv`` (default ``sys.argv``) as one shell-quoted line, the program named as typed.

    ``sys.argv[0]`` is a full path: it becomes ``uvms-qp`` for the console script, ``python -m
    uvms_qp`` for the package's ``__main__`` and the script's name otherwise.
    """
    if argv is not None:
        return shlex.join(argv)
    if not sys.argv:
        return ""
    program = Path(sys.argv[0])
    name = f"python -m {program.parent.name}" if program.name == "__main__.py" else program.name
    return " ".join([name, shlex.join(sys.argv[1:])]).strip()


def provenance(command: Sequence[str] | None = None) -> dict[str, Any]:
    """Where a result comes from: versions, Python, platform, date and command line.

    Args:
        command: The command that produced the result (default: this process's, see
            :func:`command_line`).

    Returns:
        ``{"versions": {distribution: version or None}, "python", "platform", "date"`` (UTC,
        ISO 8601) ``, "command"}``.
    """
    versions: dict[str, str | None] = {"uvms-qp": __version__}
    for name in PROVENANCE_PACKAGES[1:]:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return {
        "versions": versions,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "command": command_line(command),
    }


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


def _dynamics(series: Any) -> dict[str, Any]:
    """The servo-rate record of a dynamic run (``DynamicSeries``, by field name)."""
    return dict(vars(series))


def results_dict(result: SimulationResult, *, series: bool = True,
                 command: Sequence[str] | None = None,
                 reference: SimulationResult | None = None) -> dict[str, Any]:
    """The content of ``results.json`` for one run (see the module docstring).

    Args:
        result: The run.
        series: Include the recorded series.
        command: Command line of the provenance block (default: ``sys.argv``).
        reference: The kinematic run of the same scenario, whose metrics a dynamic run's
            record carries as ``kinematic_reference`` (None: none).
    """
    data: dict[str, Any] = {
        "scenario": result.scenario,
        "scheme": result.scheme,
        "solver": result.solver,
        "model": result.model,
        "plant": result.plant,
        "dt": result.dt,
        "steps": result.steps,
        "duration": result.steps * result.dt,
        "wall_time_s": result.wall_time,
        "metrics": result.metrics(),
        "phases": result.phase_metrics(),
        "events": result.events,
        "provenance": provenance(command),
    }
    data["plant_settings"] = result.plant_settings
    notes = rating_notes(data["metrics"], result.plant_settings)
    if notes:
        data["warnings"] = notes
    data["sensors"] = result.sensors
    if result.stopped is not None:
        data["stopped"] = result.stopped
    if reference is not None:
        data["kinematic_reference"] = {"metrics": reference.metrics(),
                                       "wall_time_s": reference.wall_time}
    if series:
        record: dict[str, Any] = {
            "time": result.time_states,
            "zeta_names": list(result.zeta_names),
            "zeta_units": list(result.zeta_units),
            "joint_names": list(result.joint_names),
            "joint_units": list(result.joint_units),
            "q": result.q,
            "vehicle_pose": result.eta,
            "joints": result.joints,
            "ee_pose": _ee_pose(result),
            "target_position": result.target_position,
            "manipulability": result.manipulability,
            "manipulability_unit": result.manipulability_unit,
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
        if result.manipulability_floor is not None:
            record["manipulability_floor"] = result.manipulability_floor
        if result.payload_moment is not None:
            record["payload_moment"] = result.payload_moment
        if result.payload_objective is not None:
            record["payload_objective"] = result.payload_objective
        record["task_errors"] = result.task_errors
        record["task_error_units"] = result.task_error_units
        if result.command_rate_limit is not None:
            record["command_rate_limit"] = result.command_rate_limit
        if result.dynamics is not None:
            record["dynamics"] = _dynamics(result.dynamics)
        data["series"] = record
    return _clean(data)  # type: ignore[no-any-return]


def write_results(result: SimulationResult, out_dir: str | Path, *,
                  command: Sequence[str] | None = None,
                  reference: SimulationResult | None = None) -> Path:
    """Write ``out_dir/results.json`` atomically (mode 0644) and return its path.

    Args:
        result: The run.
        out_dir: Output directory (created if needed).
        command: Command line of the provenance block (default: ``sys.argv``).
        reference: The kinematic run of the same scenario (see :func:`results_dict`).
    """
    directory = Path(out_dir)
    directory.mkdir(parents=True, exist_ok=True)
    text = json.dumps(results_dict(result, command=command, reference=reference),
                      allow_nan=False,
                      separators=(",", ":"))
    return write_atomic(directory / RESULTS_FILE, text)
