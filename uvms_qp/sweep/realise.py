"""One run's scenario: the base scenario with the values the run drew.

The values a file-level quantity takes (initial state, current, payload) are written into a copy
of the base scenario's parsed TOML, which is then loaded like any scenario file: the run's
scenario is checked like one, and is what a user would get by writing those numbers into the
file. The rest is applied to the loaded scenario: the measured pose's noise and delay
(:mod:`uvms_qp.sweep.measurement`).

- ``initial.position`` / ``initial.attitude`` / ``initial.joints``: offsets added to the base
  scenario's initial vehicle position [m], attitude angles [rad] and joint angles [rad] (a joint
  pushed beyond a limit is put on the limit);
- ``current.direction`` [rad], ``current.speed`` [m/s], ``current.drift``: the ``[current]``
  table's keys (the others keep the base scenario's values); a task heading to the current
  follows the new direction;
- ``payload.mass`` [kg] and ``payload.volume`` [m^3]: every pick-up event (an event that sets a
  payload task's ``force``) sets the payload's weight in water ``(m - rho V) g`` [N] instead.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..sim.scenario import Scenario, scenario_from_dict
from .measurement import PoseNoise
from .sampling import sensor_seed
from .spec import GRAVITY, WATER_DENSITY, SweepSpec

#: Base scenarios loaded in this process, by sweep digest (a worker loads each once).
_BASES: dict[str, Scenario] = {}


@dataclass(frozen=True)
class RunSetup:
    """What a run needs beyond the spec: its scenario and its measurement.

    Attributes:
        scenario: The run's scenario.
        noise: Noise and delay of the measured pose, or None when the controller sees the truth.
    """

    scenario: Scenario
    noise: PoseNoise | None


def base_scenario(spec: SweepSpec) -> Scenario:
    """The sweep's base scenario (loaded once per process)."""
    key = spec.digest()
    if key not in _BASES:
        _BASES[key] = scenario_from_dict(copy.deepcopy(spec.scenario_data),
                                         source=spec.scenario_path,
                                         name=spec.scenario_path.stem)
    return _BASES[key]


def _values(parameters: dict[str, Any], prefix: str) -> dict[str, Any]:
    return {name[len(prefix) + 1:]: value for name, value in parameters.items()
            if name.startswith(prefix + ".")}


def _initial(data: dict[str, Any], base: Scenario, offsets: dict[str, Any]) -> None:
    if not offsets:
        return
    model = base.model
    eta0, joints0 = model.split(base.q0)
    eta = np.array(eta0, dtype=np.float64)
    joints = np.array(joints0, dtype=np.float64)
    spatial = model.vehicle_kind == "spatial"
    if "position" in offsets:
        eta[: 3 if spatial else 2] += offsets["position"]
    if "attitude" in offsets:
        if spatial:
            eta[3:6] += offsets["attitude"]
        else:
            eta[2] += offsets["attitude"][0]
    if "joints" in offsets:
        joints = np.clip(joints + np.asarray(offsets["joints"]), model.joint_lower,
                         model.joint_upper)
    table = dict(data.get("initial") or {})
    if model.eta_size:
        table["eta"] = eta.tolist()
    table["joints"] = joints.tolist()
    data["initial"] = table


def _current(data: dict[str, Any], values: dict[str, Any]) -> None:
    if values:
        data["current"] = {**(data.get("current") or {}), **values}


def _payload(data: dict[str, Any], values: dict[str, Any]) -> None:
    if not values:
        return
    weight = (values["mass"] - WATER_DENSITY * values.get("volume", 0.0)) * GRAVITY
    for event in data.get("events") or []:
        if isinstance(event, dict) and isinstance(event.get("update"), dict) \
                and "force" in event["update"]:
            event["update"] = {**event["update"], "force": weight}


def _noise(values: dict[str, Any], seed: int) -> PoseNoise | None:
    noise = PoseNoise(**{key: float(v) for key, v in values.items()}, seed=sensor_seed(seed))
    return None if noise.exact else noise


def realise(spec: SweepSpec, parameters: dict[str, Any], seed: int) -> RunSetup:
    """The scenario and measurement of the run of seed ``seed`` that drew ``parameters``.

    Raises:
        ConfigError: the drawn values make an invalid scenario (e.g. an initial pose that the
            hard constraints cannot start from); the run is recorded with this error.
    """
    base = base_scenario(spec)
    data = copy.deepcopy(spec.scenario_data)
    _initial(data, base, _values(parameters, "initial"))
    _current(data, _values(parameters, "current"))
    _payload(data, _values(parameters, "payload"))
    scenario = scenario_from_dict(data, source=spec.scenario_path, name=base.name)
    if spec.duration is not None:
        scenario = scenario.with_duration(spec.duration)
    return RunSetup(scenario, _noise(_values(parameters, "sensors"), seed))
