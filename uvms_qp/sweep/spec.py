"""Sweep files: a base scenario, what varies from run to run, how many runs, what success is.

:func:`load_sweep` reads a sweep file (TOML; format in ``docs/sweeps.md``) into a
:class:`SweepSpec`, checked as strictly as a scenario file: every error is a
:class:`~uvms_qp.errors.ConfigError` whose message starts with the field path
(``current.speed: a current speed [m/s] must be >= 0, but the spread U(-0.1, 0.3) reaches
-0.1``), and everything is checked before any run starts: the base scenario is loaded, every
spread is held against the range of the quantity it varies (over its whole support, not the
draws), every success criterion must name a metric the runs report.

A spec holds plain data only (the base scenario's parsed TOML, the distributions, the criteria),
so it travels to worker processes and cluster machines as it is; each run rebuilds its scenario
from it (:mod:`uvms_qp.sweep.realise`).
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from .. import dynamics
from ..dynamics.parameters import DEFAULT_GRAVITY, DEFAULT_WATER_DENSITY
from ..errors import ConfigError, UvmsQpError
from ..model import Model
from ..sim.config import Table, describe, did_you_mean, read_toml
from ..sim.scenario import Phase, Scenario, resolve_scenario, scenario_from_dict
from .distributions import Choice, Distribution, check_support, read_distribution
from .outcome import metric_names

#: Most runs a sweep may ask for.
MAX_RUNS = 1_000_000
#: Package folder of the bundled sweep files.
_SWEEP_DATA = "uvms_qp.sweep"
_TOP_KEYS = ("name", "description", "scenario", "plant", "runs", "seed", "duration",
             "plant_parameters", "current", "sensors", "initial", "payload", "success")
PLANTS = ("kinematic", "dynamic")

#: Plant parameters a sweep may spread, as relative factors ``1 + x`` of the scenario's values:
#: path -> what it is. Every one is a positive magnitude, so the factor must stay positive.
PLANT_PARAMETERS: dict[str, str] = {
    "vehicle.mass": "the vehicle's mass [kg]",
    "vehicle.volume": "the vehicle's displaced volume [m^3]",
    "vehicle.inertia": "the vehicle's rotational inertia",
    "vehicle.added_mass": "the vehicle's added-mass matrix",
    "vehicle.linear_damping": "the vehicle's linear damping",
    "vehicle.quadratic_damping": "the vehicle's quadratic damping",
    "links.mass": "the arm links' masses [kg]",
    "links.volume": "the arm links' displaced volumes [m^3]",
    "links.inertia": "the arm links' rotational inertias",
    "links.added_mass": "the arm links' added-mass matrices",
    "links.linear_damping": "the arm links' linear damping",
    "links.quadratic_damping": "the arm links' quadratic damping",
}
#: Key of ``[plant_parameters]`` choosing a named alternative parameter set.
PARAMETER_SET = "set"

#: Measurement noise and delay: key -> (what, unit, needs the dynamic plant).
SENSOR_KEYS: dict[str, tuple[str, str, bool]] = {
    "position_noise": ("a position noise std", "m", False),
    "attitude_noise": ("an attitude noise std", "rad", False),
    "joint_noise": ("a joint noise std", "rad", False),
    "linear_rate_noise": ("a linear rate noise std", "m/s", True),
    "angular_rate_noise": ("an angular rate noise std", "rad/s", True),
    "delay": ("a measurement delay", "s", False),
}
#: Initial-state perturbations (added to the scenario's initial state): key -> unit.
INITIAL_KEYS = {"position": "m", "attitude": "rad", "joints": "rad"}
#: Gravity [m/s^2] and water density [kg/m^3] turning a payload into its weight in water.
GRAVITY = DEFAULT_GRAVITY
WATER_DENSITY = DEFAULT_WATER_DENSITY


@dataclass(frozen=True)
class Variable:
    """One quantity of the sweep file (fixed or drawn per run).

    Attributes:
        name: Its field path in the sweep file (``current.speed``, ``initial.joints``,
            ``plant_parameters.vehicle.added_mass``): the parameter's name in the records.
        dist: Its law.
        count: Independent draws per run (1, or the entries of a vector perturbation).
        unit: Unit of a drawn value (``"relative"`` for plant factors ``1 + x``).
    """

    name: str
    dist: Distribution
    count: int = 1
    unit: str = ""


@dataclass(frozen=True)
class Criterion:
    """A success criterion: ``low <= metric <= high`` (a missing or null metric fails).

    Attributes:
        metric: Flattened metric name (``ee_error_final``, ``level_met_share.0``).
        low: Smallest value allowed, or None.
        high: Largest value allowed, or None.
    """

    metric: str
    low: float | None = None
    high: float | None = None

    def holds(self, metrics: dict[str, Any]) -> bool:
        """Whether the run's ``metrics`` meet the criterion."""
        value = metrics.get(self.metric)
        if not isinstance(value, int | float) or isinstance(value, bool) \
                or not math.isfinite(value):
            return False
        return (self.low is None or value >= self.low) and (self.high is None
                                                             or value <= self.high)

    def describe(self) -> str:
        """``ee_error_final <= 0.005`` and the like."""
        if self.low is not None and self.high is not None:
            return f"{self.low:g} <= {self.metric} <= {self.high:g}"
        if self.high is not None:
            return f"{self.metric} <= {self.high:g}"
        return f"{self.metric} >= {self.low:g}"


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep file.

    Attributes:
        name: Sweep name (the file stem by default).
        description: Free text.
        scenario: The base scenario as the file names it.
        scenario_path: Its file.
        scenario_data: Its parsed TOML (plain data; each run rebuilds its scenario from it).
        plant: ``"kinematic"`` or ``"dynamic"``.
        runs: Number of runs.
        seed: Master seed; run ``i`` draws from :func:`~uvms_qp.sweep.sampling.run_seed`.
        duration: Override of the scenario's simulated time [s], or None.
        variables: What the runs draw, in file order.
        criteria: The success criteria (a run also fails when it raised or stopped early).
        source: The sweep file, or None.
        model_files: Model files (TOML, see docs/models.md) each process registers before its
            first run, for a base scenario that names a model of such a file (``--model-path``).
    """

    name: str
    description: str
    scenario: str
    scenario_path: Path
    scenario_data: dict[str, Any]
    plant: str
    runs: int
    seed: int
    duration: float | None
    variables: tuple[Variable, ...]
    criteria: tuple[Criterion, ...]
    source: Path | None = None
    model_files: tuple[Path, ...] = ()

    @property
    def varied(self) -> tuple[Variable, ...]:
        """The variables whose value changes from run to run."""
        return tuple(v for v in self.variables if v.dist.varies)

    def variable(self, name: str) -> Variable | None:
        """The variable called ``name``, or None."""
        return next((v for v in self.variables if v.name == name), None)

    def with_runs(self, runs: Any, path: str = "--runs") -> SweepSpec:
        """This sweep with another number of runs (the draws of the first runs are unchanged).

        Raises:
            ConfigError: not a positive integer of at most :data:`MAX_RUNS`, at ``path``.
        """
        return dataclasses.replace(self, runs=_check_runs(runs, path))

    def with_model_files(self, paths: Any) -> SweepSpec:
        """This sweep with the model files its runs register first (absolute paths).

        Raises:
            ConfigError: a path that is not a file (``--model-path``).
        """
        files = []
        for path in paths:
            path = Path(path).resolve()
            if not path.is_file():
                raise ConfigError(f"no model file {str(path)!r}", "--model-path")
            files.append(path)
        return dataclasses.replace(self, model_files=tuple(files))

    def digest(self) -> str:
        """A fingerprint of what decides each run (everything but the number of runs).

        Two sweeps with the same digest draw the same parameters for the same run index and
        run them on the same scenario, so their records may share one output folder.
        """
        content = {
            "scenario": self.scenario_data, "plant": self.plant, "seed": self.seed,
            "duration": self.duration,
            "variables": [[v.name, v.count, dataclasses.asdict(v.dist)] for v in self.variables],
            "criteria": [dataclasses.asdict(c) for c in self.criteria],
        }
        text = json.dumps(content, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


# ----------------------------------------------------------------------------------------------
# Locating sweep files


def bundled_sweeps() -> list[str]:
    """Names of the sweep files shipped with the package (``uvms-qp sweep NAME``)."""
    root = resources.files(_SWEEP_DATA).joinpath("data")
    return sorted(e.name.removesuffix(".toml") for e in root.iterdir()
                  if e.name.endswith(".toml"))


def resolve_sweep(source: str | Path) -> Path:
    """The file of a sweep given as a path or as a bundled sweep name.

    Raises:
        ConfigError: neither an existing file nor a bundled name (bundled names listed).
    """
    path = Path(source)
    if path.is_file():
        return path
    name = str(source)
    if path.suffix != ".toml" and "/" not in name and "\\" not in name:
        candidate = resources.files(_SWEEP_DATA).joinpath("data", f"{name}.toml")
        if candidate.is_file():
            return Path(str(candidate))
        raise ConfigError(f"unknown sweep {name!r}: not a file and not a bundled sweep; "
                          f"bundled sweeps: {', '.join(bundled_sweeps()) or '(none)'}")
    raise ConfigError(f"sweep file not found: {path}")


def load_sweep(source: str | Path) -> SweepSpec:
    """Read and check a sweep file (or a bundled sweep by name).

    Raises:
        ConfigError: any invalid field, with its path; the base scenario's own errors come back
            with the path ``scenario`` and the scenario file's field path.
    """
    path = resolve_sweep(source)
    return sweep_from_dict(read_toml(path, "sweep file"), source=path, name=path.stem)


# ----------------------------------------------------------------------------------------------
# Reading


def _check_runs(value: Any, path: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"expected a positive integer, got {describe(value)}", path)
    if not 1 <= value <= MAX_RUNS:
        raise ConfigError(f"expected a number of runs in [1, {MAX_RUNS}], got {value}", path)
    return value


def _base_scenario(top: Table, base: Path) -> tuple[str, Path, dict[str, Any], Scenario]:
    name = str(top.take_str("scenario", required=True))
    where = top.at("scenario")
    candidate = base / name
    try:
        path = resolve_scenario(candidate if candidate.is_file() else name)
        data = read_toml(path)
        scenario = scenario_from_dict(copy.deepcopy(data), source=path, name=path.stem)
    except ConfigError as exc:
        raise ConfigError(str(exc), where) from exc
    return name, path, data, scenario


def _scalar(table: Table, key: str, *, low: float | None = None, high: float | None = None,
            what: str, unit: str, strict_low: bool = False) -> Variable | None:
    raw = table.raw(key)
    if raw is None:
        return None
    where = table.at(key)
    dist = read_distribution(raw, where)
    check_support(dist, where, low=low, high=high, what=f"{what} [{unit}]",
                  strict_low=strict_low)
    return Variable(where, dist, 1, unit)


def _read_plant_parameters(table: Table | None, plant: str) -> list[Variable]:
    if table is None:
        return []
    if plant != "dynamic":
        raise ConfigError("plant parameters vary the dynamic plant; set plant = \"dynamic\"",
                          table.path)
    out: list[Variable] = []
    for key in list(table.data):
        where = table.at(key)
        if key == PARAMETER_SET:
            dist = read_distribution(table.raw(key), where, strings=True)
            sets = dynamics.plant_parameter_sets()
            for name in _options(dist):
                if name not in sets:
                    raise ConfigError(f"unknown parameter set {name!r}; bundled sets: "
                                      f"{', '.join(sets)}{did_you_mean(str(name), sets)}",
                                      where)
            out.append(Variable(where, dist, 1, "name"))
            continue
        if key not in PLANT_PARAMETERS:
            known = ", ".join([PARAMETER_SET, *PLANT_PARAMETERS])
            raise ConfigError(f"unknown plant parameter {key!r}; known: {known}"
                              f"{did_you_mean(key, list(PLANT_PARAMETERS))}", where)
        dist = read_distribution(table.raw(key), where)
        lo, _ = dist.support
        if not 1.0 + lo > 0.0:
            reach = "is unbounded (add within = [low, high])" if math.isinf(lo) \
                else f"reaches a factor 1 + ({lo:g}) = {1.0 + lo:g}"
            raise ConfigError(f"{PLANT_PARAMETERS[key]} is scaled by 1 + x, which must stay "
                              f"positive, but the spread {dist.describe()} {reach}", where)
        out.append(Variable(where, dist, 1, "relative"))
    table.finish()
    return out


def _options(dist: Distribution) -> tuple[Any, ...]:
    """Every value a choice or a fixed value can take."""
    return dist.options if isinstance(dist, Choice) else (getattr(dist, "value", None),)


def plant_factors(parameters: dict[str, Any]) -> dict[str, float]:
    """The relative factors ``1 + x`` a run drew for the plant's parameters, by path."""
    prefix = "plant_parameters."
    return {name[len(prefix):]: 1.0 + float(value) for name, value in parameters.items()
            if name.startswith(prefix) and name != prefix + PARAMETER_SET}


def _check_plant_extremes(scenario: Scenario, variables: list[Variable]) -> None:
    """Scale the plant's parameters by each spread's extreme factors, as the runs may.

    Every parameter set a run may use is scaled by each relative factor at both ends of its
    spread, so that the plant's own checks (a positive mass and volume, positive definite
    matrices) refuse the spread before any run.

    Raises:
        ConfigError: at the spread's path, with the plant's reason.
    """
    chosen = next((v for v in variables if v.name.endswith("." + PARAMETER_SET)), None)
    names: list[Any] = list(_options(chosen.dist)) if chosen is not None else [None]
    for name in names:
        base = (scenario.plant.parameters if name is None
                else dynamics.plant_parameters(str(name)))
        for variable in variables:
            if variable.unit != "relative":
                continue
            path = variable.name.removeprefix("plant_parameters.")
            for end in variable.dist.support:
                if not math.isfinite(end):
                    continue
                try:
                    base.scaled({path: 1.0 + end})
                except UvmsQpError as exc:
                    where = f" of the set {name!r}" if name is not None else ""
                    raise ConfigError(f"at the factor 1 + ({end:g}){where}: {exc}",
                                      variable.name) from exc


def _read_current(table: Table | None, scenario: Scenario) -> list[Variable]:
    if table is None:
        return []
    direction = _scalar(table, "direction", what="a current direction", unit="rad")
    out = [v for v in (
        direction,
        _scalar(table, "speed", low=0.0, what="a current speed", unit="m/s"),
        _scalar(table, "drift", low=0.0, high=1.0, what="a current drift fraction", unit="-"),
    ) if v is not None]
    table.finish()
    if scenario.current is None and direction is None:
        raise ConfigError("the base scenario has no [current] to take the direction from; "
                          "give direction", table.path)
    return out


def _read_sensors(table: Table | None, plant: str) -> list[Variable]:
    if table is None:
        return []
    out = []
    for key, (what, unit, dynamic) in SENSOR_KEYS.items():
        variable = _scalar(table, key, low=0.0, what=what, unit=unit)
        if variable is None:
            continue
        if dynamic and plant != "dynamic":
            raise ConfigError("the kinematic plant has no measured velocity (the command is "
                              "the velocity); set plant = \"dynamic\"", table.at(key))
        out.append(variable)
    table.finish()
    return out


def _read_initial(table: Table | None, model: Model) -> list[Variable]:
    if table is None:
        return []
    kind = model.vehicle_kind
    counts = {
        "position": {"spatial": 3, "planar": 2}.get(kind, 0),
        "attitude": {"spatial": 3, "planar": 1}.get(kind, 0),
        "joints": int(model.n_joints),
    }
    out = []
    for key, unit in INITIAL_KEYS.items():
        raw = table.raw(key)
        if raw is None:
            continue
        where = table.at(key)
        if counts[key] == 0:
            raise ConfigError(f"model {model.name!r} has no {key} to perturb (its vehicle is "
                              f"{kind})", where)
        out.append(Variable(where, read_distribution(raw, where), counts[key], unit))
    table.finish()
    return out


def _pickup_events(data: dict[str, Any]) -> list[int]:
    """Indices of the scenario's events that set a payload task's force (the pick-ups)."""
    events = data.get("events") or []
    return [i for i, e in enumerate(events)
            if isinstance(e, dict) and isinstance(e.get("update"), dict)
            and "force" in e["update"]]


def _plant_payload(data: dict[str, Any]) -> dict[str, Any] | None:
    """The scenario's ``[plant.payload]`` table (the payload a dynamic plant's tool takes)."""
    plant = data.get("plant")
    payload = plant.get("payload") if isinstance(plant, dict) else None
    return payload if isinstance(payload, dict) else None


def _read_payload(table: Table | None, data: dict[str, Any], name: str) -> list[Variable]:
    if table is None:
        return []
    mass = _scalar(table, "mass", low=0.0, what="a payload mass", unit="kg")
    volume = _scalar(table, "volume", low=0.0, what="a payload volume", unit="m^3")
    table.finish()
    if mass is None:
        raise ConfigError("missing required field 'mass'", table.path)
    if not _pickup_events(data) and _plant_payload(data) is None:
        raise ConfigError(f"the scenario {name!r} picks up no payload (no event sets a payload "
                          "task's force, no [plant.payload])", table.path)
    if volume is not None:
        net = mass.dist.support[0] - WATER_DENSITY * volume.dist.support[1]
        if net < 0.0:
            raise ConfigError(f"the payload's weight in water (m - {WATER_DENSITY:g} V) g "
                              f"reaches {net * GRAVITY:g} N: a payload lighter than the water "
                              "it displaces does not weigh on the tool", table.at("volume"))
    return [v for v in (mass, volume) if v is not None]


def _read_success(table: Table | None, names: set[str]) -> list[Criterion]:
    if table is None:
        return []
    out = []
    for key in list(table.data):
        where = table.at(key)
        if key not in names:
            close = did_you_mean(key, sorted(names))
            raise ConfigError(f"unknown metric {key!r}: the runs report no such metric{close} "
                              "(docs/sweeps.md lists them)", where)
        bounds = Table(table.raw(key), where, ("min", "max"))
        low = bounds.take_number("min")
        high = bounds.take_number("max")
        bounds.finish()
        if low is None and high is None:
            raise ConfigError("expected min, max or both", where)
        if low is not None and high is not None and low > high:
            raise ConfigError(f"expected min <= max, got {low:g} > {high:g}", where)
        out.append(Criterion(key, low, high))
    table.finish()
    return out


def sweep_from_dict(data: dict[str, Any], *, source: Path | None = None,
                    name: str = "sweep") -> SweepSpec:
    """Read and check parsed TOML data into a :class:`SweepSpec` (see ``docs/sweeps.md``).

    Args:
        data: Parsed TOML (top-level table).
        source: The sweep file (the base scenario's path is relative to its folder).
        name: Default sweep name (the file stem).

    Raises:
        ConfigError: any invalid field, with its path.
    """
    top = Table(data, "", _TOP_KEYS)
    sweep_name = top.take_str("name", name) or name
    description = top.take_str("description", "") or ""
    base = source.parent if source is not None else Path.cwd()
    scenario_name, path, scenario_data, scenario = _base_scenario(top, base)
    plant = str(top.take_str("plant", "kinematic", choices=PLANTS))
    runs = _check_runs(top.raw("runs", required=True), top.at("runs"))
    seed = top.raw("seed", required=True)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"expected a non-negative integer, got {seed!r}", top.at("seed"))
    duration = top.take_number("duration", None, positive=True)
    if duration is not None:
        scenario = scenario.with_duration(duration, top.at("duration"))
    scenario = scenario.with_plant(plant, top.at("plant"))  # the sweep's plant decides
    variables = [
        *_read_plant_parameters(top.take_table("plant_parameters"), plant),
        *_read_current(top.take_table("current"), scenario),
        *_read_sensors(top.take_table("sensors"), plant),
        *_read_initial(top.take_table("initial"), scenario.model),
        *_read_payload(top.take_table("payload"), scenario_data, scenario.name),
    ]
    success = top.take_table("success")
    top.finish()
    if plant == "dynamic":
        _check_plant_extremes(scenario, variables)
    pilot = dataclasses.replace(scenario, phases=tuple(
        Phase(p.name, 0.0, 2.0 * scenario.dt) for p in scenario.phases))
    criteria = _read_success(success, metric_names(pilot))
    return SweepSpec(
        name=sweep_name, description=description, scenario=scenario_name, scenario_path=path,
        scenario_data=scenario_data, plant=plant, runs=runs, seed=int(seed),
        duration=duration, variables=tuple(variables), criteria=tuple(criteria), source=source,
    )
