"""Run one scenario under every scheme it names and tabulate the metrics side by side.

:func:`compare` loads a scenario, runs its HQP stack and each closed-form scheme listed in the
scenario's ``schemes`` (each on a fresh copy of the scenario, so tasks and events start clean),
records the schemes' own diagnostic scalars (shaping function, fuzzy weights, path rate...) every
step, and returns a :class:`Comparison`. :meth:`Comparison.write` stores one ``results.json`` per
scheme (the simulator's writer, in ``DIR/<scheme>/``), the recorded diagnostics
(``DIR/<scheme>/scheme_info.json``) and the table (``DIR/comparison.md``, ``DIR/comparison.json``),
whose first row (``plants`` in the JSON) says which plant each run drove: the scenario's
``[plant]`` (kinematic by default) or the one :meth:`Scenario.with_plant` set.

Besides the simulator's metrics, the table reports a few that the papers' claims need:
``min_manipulability_time`` [s], ``joint_rate_max`` [rad/s], ``vehicle_speed_max`` [m/s],
``vehicle_yaw_final`` [rad], and ``tool_base_radius_max``/``_mean`` [m], the horizontal distance
of the tool from the arm base z axis (``sqrt(x_E^2 + y_E^2)`` in the arm base frame): the payload
moment per newton of Wang et al. (2017), Eq. (20).

The closed-form schemes are the papers' unconstrained resolutions: they ignore the scenario's hard
bounds, while each of their steps reports status ``optimal`` (the formula was evaluated). A run
whose ``bound_violation_max`` exceeds :data:`BOUND_TOLERANCE` is therefore marked ``(exceeded)``
in the table and named in :meth:`Comparison.notes` (also in ``comparison.md`` and, with
``exceeds_hard_bounds`` per scheme, in ``comparison.json``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..errors import ConfigError
from ..schemes import build_scheme
from ._files import write_atomic
from .dynamic_metrics import rating_notes
from .results import write_results
from .runner import SimulationResult, simulate
from .scenario import Scenario, load_scenario

#: Unit of a table metric whose value is a dict by unit (one row per unit).
BY_UNIT = "by unit"
#: Rows of the comparison table: (metric key, unit). A metric of :data:`PER_KEY` (a dict) gets one
#: row per key: ``"key (sub)"`` in ``unit``, or ``key`` in the unit ``sub`` for :data:`BY_UNIT`;
#: other dicts (counts per stage or status) fill one row.
TABLE_METRICS: tuple[tuple[str, str], ...] = (
    ("ee_error_max", "m"),
    ("ee_error_rms", "m"),
    ("min_manipulability", ""),
    ("min_manipulability_time", "s"),
    ("vehicle_displacement_max", "m"),
    ("vehicle_speed_max", "m/s"),
    ("vehicle_yaw_final", "rad"),
    ("vehicle_yaw_error_final", "rad"),
    ("joint_rate_max", "rad/s"),
    ("joint_limit_violation_max", "rad"),
    ("bound_violation_max", ""),
    ("payload_moment_max", "N m"),
    ("payload_objective_max", "N m^2"),
    ("tool_base_radius_max", "m"),
    ("tool_base_radius_mean", "m"),
    ("command_reversals_per_s_max", "1/s"),
    ("command_reversals_worst_axis", ""),
    ("command_change_max", BY_UNIT),
    ("settling_time", "s"),
    ("step_time_median_us", "us"),
    ("nan_steps", ""),
    ("unproven_steps", ""),
    ("stage_counts", "steps"),
    ("status_counts", "steps"),
)

#: Rows added when a run drove the dynamic plant: the floating vehicle's attitude and the
#: thrusters' energy (``docs/dynamics.md``).
DYNAMIC_TABLE_METRICS: tuple[tuple[str, str], ...] = (
    ("roll_max", "rad"),
    ("pitch_max", "rad"),
    ("energy", "J"),
)
#: Dict-valued table metrics with one row per key (by unit, by task).
PER_KEY = ("command_change_max", "settling_time")

#: Metrics left out for a scheme that follows no tool trajectory (``needs_trajectory = False``).
UNTRACKED_METRICS = ("ee_error_max", "ee_error_rms", "ee_error_final")

#: Largest hard-row violation (units of the rows: [m/s], [rad/s], ...) a run may show before the
#: table flags it as exceeding the hard bounds.
BOUND_TOLERANCE = 1e-6
#: Marker of a closed-form run that exceeds the scenario's hard bounds.
BOUNDS_NOTE = "exceeds hard bounds (closed-form schemes ignore them)"


class _Recorder:
    """Wrap a controller or scheme: same ``step``/``reset``, plus a per-step log of its ``info``."""

    def __init__(self, scheme: Any) -> None:
        self.scheme = scheme
        self.solver_name = getattr(scheme, "solver_name", None)
        self.series: dict[str, list[float]] = {}
        self._count = 0

    def reset(self) -> None:
        reset = getattr(self.scheme, "reset", None)
        if callable(reset):
            reset()
        self.series = {}
        self._count = 0

    def step(self, state: Any, t: float) -> Any:
        result = self.scheme.step(state, t)
        info = getattr(self.scheme, "info", None) or {}
        for key, value in info.items():
            column = self.series.setdefault(key, [math.nan] * self._count)
            column.append(float(value))
        self._count += 1
        for column in self.series.values():
            if len(column) < self._count:
                column.append(math.nan)
        return result

    def arrays(self) -> dict[str, FloatArray]:
        return {key: np.asarray(values) for key, values in self.series.items()}


@dataclass
class SchemeRun:
    """One scheme's run of the scenario.

    Attributes:
        name: Scheme name (``"hqp"`` for the scenario's stack).
        result: The simulator's record.
        info: Per-step diagnostic series of the scheme (name -> (N,) array).
        metrics: Simulator metrics plus the extra ones of this module.
    """

    name: str
    result: SimulationResult
    info: dict[str, FloatArray] = field(default_factory=dict)
    metrics: dict[str, Any] = field(default_factory=dict)

    @property
    def plant(self) -> str | None:
        """The plant the run drove (``"kinematic"`` or ``"dynamic"``), None without a record."""
        plant = getattr(self.result, "plant", None)
        return None if plant is None else str(plant)


@dataclass
class Comparison:
    """All runs of one scenario.

    Attributes:
        scenario: Scenario name.
        description: Its description.
        runs: One :class:`SchemeRun` per scheme, in the scenario's order (``hqp`` first).
    """

    scenario: str
    description: str
    runs: list[SchemeRun]

    def run(self, name: str) -> SchemeRun:
        """The run of scheme ``name``.

        Raises:
            KeyError: no such scheme in this comparison (the known ones are listed).
        """
        for run in self.runs:
            if run.name == name:
                return run
        raise KeyError(f"no run of scheme {name!r}; runs: {', '.join(r.name for r in self.runs)}")

    def table(self) -> list[tuple[str, str, list[Any]]]:
        """Rows ``(metric, unit, values per run)`` for metrics present in at least one run.

        A metric of :data:`PER_KEY` (settling time by task, command change by unit) gives one
        row per key, in the order the runs name them. When a run drove the dynamic plant, the
        rows of :data:`DYNAMIC_TABLE_METRICS` follow.
        """
        rows: list[tuple[str, str, list[Any]]] = []
        dynamic = any(run.plant == "dynamic" for run in self.runs)
        for key, unit in TABLE_METRICS + (DYNAMIC_TABLE_METRICS if dynamic else ()):
            values = [run.metrics.get(key) for run in self.runs]
            if key in PER_KEY and any(isinstance(v, dict) for v in values):
                subs = list(dict.fromkeys(k for v in values if isinstance(v, dict) for k in v))
                for sub in subs:
                    cells = [v.get(sub) if isinstance(v, dict) else None for v in values]
                    rows.append((key, sub, cells) if unit == BY_UNIT
                                else (f"{key} ({sub})", unit, cells))
            elif any(v is not None for v in values):
                rows.append((key, unit, values))
        return rows

    def exceeds_bounds(self, run: SchemeRun) -> bool:
        """True when ``run`` broke a hard row (box or inequality) by more than the tolerance.

        A closed-form scheme reports every step as ``optimal`` (its formula was evaluated), yet
        the papers' schemes ignore the scenario's hard bounds: this is the check that says so.
        """
        value = run.metrics.get("bound_violation_max")
        if value is None:
            return False
        return not float(value) <= BOUND_TOLERANCE  # NaN counts as exceeded

    def notes(self) -> list[str]:
        """One line per run that exceeds the hard bounds, with the largest violation."""
        lines = []
        for run in self.runs:
            if self.exceeds_bounds(run):
                what = "exceeds hard bounds" if run.name == "hqp" else BOUNDS_NOTE
                value = format_value(run.metrics.get("bound_violation_max"))
                lines.append(f"{run.name}: {what}, by up to {value} (bound_violation_max); "
                             "its steps' status does not show it")
        return lines

    def warnings(self) -> list[dict[str, Any]]:
        """The runs' warnings (a payload beyond the arm's rating...), each distinct one once.

        Each is ``{"warning": text, "runs": [scheme names]}``, in the order the runs give them.
        """
        found: dict[str, list[str]] = {}
        for run in self.runs:
            settings = getattr(run.result, "plant_settings", None) or {}
            for note in rating_notes(run.metrics, settings):
                found.setdefault(note, []).append(run.name)
        return [{"warning": note, "runs": names} for note, names in found.items()]

    def warning_lines(self) -> list[str]:
        """:meth:`warnings` as text, each naming the runs that gave it."""
        return [f"{w['warning']} (runs: {', '.join(w['runs'])})" for w in self.warnings()]

    def cells(self) -> list[tuple[str, str, list[str]]]:
        """:meth:`table` as text, with the bound violations that exceed the tolerance marked.

        A first row ``plant`` says which plant each run drove (kinematic or dynamic).
        """
        rows = []
        plants = [run.plant for run in self.runs]
        if any(plant is not None for plant in plants):
            rows.append(("plant", "", [plant or "-" for plant in plants]))
        for key, unit, values in self.table():
            texts = [format_value(v) for v in values]
            if key == "bound_violation_max":
                texts = [f"{text} (exceeded)" if self.exceeds_bounds(run) else text
                         for run, text in zip(self.runs, texts, strict=True)]
            rows.append((key, unit, texts))
        return rows

    def markdown(self) -> str:
        """The table as GitHub markdown (one column per scheme), then the notes, if any."""
        names = [run.name for run in self.runs]
        lines = [
            f"| metric | unit | {' | '.join(names)} |",
            "|---|---|" + "---|" * len(names),
        ]
        for key, unit, texts in self.cells():
            lines.append(f"| {key} | {unit} | {' | '.join(texts)} |")
        notes = self.notes() + self.warning_lines()
        if notes:
            lines.append("")
            lines.extend(f"- {note}" for note in notes)
        return "\n".join(lines)

    def write(self, out_dir: str | Path) -> list[Path]:
        """Write every run's ``results.json`` and diagnostics, and the comparison table.

        Every file is written atomically (mode 0644); a path there that is a symbolic link is
        replaced, not followed.
        """
        directory = Path(out_dir)
        directory.mkdir(parents=True, exist_ok=True)
        written = []
        for run in self.runs:
            sub = directory / run.name
            written.append(write_results(run.result, sub))
            info_path = sub / "scheme_info.json"
            payload = {
                "scheme": run.name,
                "time": run.result.time.tolist(),
                "series": {k: _json_list(v) for k, v in run.info.items()},
                "metrics": {k: _json_value(v) for k, v in run.metrics.items()},
            }
            write_atomic(info_path, json.dumps(payload, allow_nan=False))
            written.append(info_path)
        md = directory / "comparison.md"
        write_atomic(md, f"# {self.scenario}\n\n{self.description}\n\n{self.markdown()}\n")
        table = {
            "scenario": self.scenario,
            "schemes": [run.name for run in self.runs],
            "plants": [run.plant for run in self.runs],
            "metrics": {_json_key(key, unit): {"unit": unit,
                                               "values": [_json_value(v) for v in values]}
                        for key, unit, values in self.table()},
            "exceeds_hard_bounds": [self.exceeds_bounds(run) for run in self.runs],
            "notes": self.notes(),
            "warnings": self.warnings(),
        }
        js = directory / "comparison.json"
        write_atomic(js, json.dumps(table, allow_nan=False, indent=1))
        return [*written, md, js]


def format_value(value: Any) -> str:
    """Compact text of a metric value for tables (counts: ``primary 598, alternate 2``)."""
    if value is None:
        return "-"
    if isinstance(value, dict):
        return ", ".join(f"{key} {format_value(count)}" for key, count in value.items())
    if isinstance(value, bool | int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        if not math.isfinite(value):
            return str(value)
        return f"{value:.4g}"
    return str(value)


def _json_value(value: Any) -> Any:
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_value(v) for k, v in value.items()}
    return value


def _json_key(key: str, unit: str) -> str:
    """The key of a table row in ``comparison.json`` (a row by unit carries its unit)."""
    by_unit = any(k == key and u == BY_UNIT for k, u in TABLE_METRICS)
    return f"{key} ({unit})" if by_unit else key


def _json_list(values: FloatArray) -> list[float | None]:
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values).tolist()]


def extra_metrics(result: SimulationResult, model: Any) -> dict[str, Any]:
    """The comparison's extra metrics of one run (see the module docstring)."""
    out: dict[str, Any] = {}
    mu = np.asarray(result.manipulability, dtype=np.float64)
    if mu.size and np.isfinite(mu).any():
        out["min_manipulability_time"] = float(result.time_states[int(np.nanargmin(mu))])
    nveh = int(model.n_vehicle)
    arm = result.zeta[:, nveh:]
    out["joint_rate_max"] = float(np.abs(arm).max()) if arm.size else 0.0
    if nveh:
        out["vehicle_speed_max"] = float(np.max(result.vehicle_speed, initial=0.0))
    if result.yaw is not None:
        out["vehicle_yaw_final"] = float(result.yaw[-1])
    radius = tool_base_radius(result, model)
    out["tool_base_radius_max"] = float(radius.max())
    out["tool_base_radius_mean"] = float(radius.mean())
    return out


def tool_base_radius(result: SimulationResult, model: Any, frame: str = "tool") -> FloatArray:
    """Horizontal distance of the tool from the arm base z axis per state (N+1,) [m]."""
    radius = np.empty(result.q.shape[0])
    for k, q in enumerate(result.q):
        p = model.state(q).pose_in(frame, "arm_base")[:3, 3]
        radius[k] = math.hypot(float(p[0]), float(p[1]))
    return radius


def compare(
    source: str | Path | Scenario,
    schemes: list[str] | None = None,
    *,
    progress: bool = False,
) -> Comparison:
    """Run a scenario under each of its schemes.

    Args:
        source: Scenario file, bundled scenario name, or a loaded scenario.
        schemes: Subset of the scenario's schemes to run (default: all, ``hqp`` first).
        progress: Show progress bars for long runs.

    Raises:
        ConfigError: invalid scenario, or a scheme name that is unknown or not in the scenario.
    """
    base = source if isinstance(source, Scenario) else load_scenario(source)
    names = list(base.schemes)
    if schemes is not None:
        for name in schemes:
            if name not in names:
                raise ConfigError(
                    f"scheme {name!r} is not compared by scenario {base.name!r}; "
                    f"its schemes: {', '.join(names)}", "schemes"
                )
        names = [n for n in names if n in schemes]
    runs = []
    for name in names:
        stack = base.build_stack()  # each run starts from fresh tasks, no event applied
        scheme = (base.make_controller(stack=stack) if name == "hqp"
                  else build_scheme(name, base, base.scheme_path(name), stack=stack))
        recorder = _Recorder(scheme)
        result = simulate(base, recorder, stack=stack, scheme_name=name, progress=progress)
        if name != "hqp":
            result.solver = str(getattr(scheme, "solver_name", "closed-form"))
        metrics = dict(result.metrics())
        metrics.update(extra_metrics(result, base.model))
        if not getattr(scheme, "needs_trajectory", True):
            # it follows no trajectory (e.g. natural motion): a tool error would be meaningless
            for key in UNTRACKED_METRICS:
                metrics.pop(key, None)
        runs.append(SchemeRun(name, result, recorder.arrays(), metrics))
    return Comparison(base.name, base.description, runs)
