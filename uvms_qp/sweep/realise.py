"""One run's scenario: the base scenario with the values the run drew.

The values a file-level quantity takes (the plant, the initial state, the current, the sensors,
the payload) are written into a copy of the base scenario's parsed TOML, which is then loaded
like any scenario file: the run's scenario is checked like one, and is what a user would get by
writing those numbers into the file. The plant parameters' relative factors, which a scenario
file does not express, are applied to the loaded scenario's parameter set
(:meth:`uvms_qp.dynamics.PlantParameters.scaled`).

- ``plant``: the ``[plant]`` table's ``type`` (the sweep's plant, whatever the scenario's);
  ``plant_parameters.set``: its ``parameters`` (a bundled set, instead of the scenario's);

- ``initial.position`` / ``initial.attitude`` / ``initial.joints``: offsets added to the base
  scenario's initial vehicle position [m], attitude angles [rad] and joint angles [rad] (a joint
  pushed beyond a limit is put on the limit);
- ``current.direction`` [rad], ``current.speed`` [m/s], ``current.drift``: the ``[current]``
  table's keys (the others keep the base scenario's values); a task heading to the current
  follows the new direction;
- ``sensors.*``: the ``[sensors]`` table (:class:`~uvms_qp.sim.sensors.Sensors`), its ``seed``
  drawn from the run's seed;
- ``payload.mass`` [kg] and ``payload.volume`` [m^3]: every pick-up event (an event that sets a
  payload task's ``force``) sets the payload's weight in water ``(m - rho V) g`` [N] instead, and
  the ``[plant.payload]`` table (the payload a dynamic plant's tool takes) these mass and volume.
"""

from __future__ import annotations

import copy
import dataclasses
import warnings
from typing import Any

import numpy as np

from ..errors import ScenarioWarning
from ..sim.scenario import Scenario, scenario_from_dict
from .sampling import sensor_seed
from .spec import GRAVITY, PARAMETER_SET, WATER_DENSITY, SweepSpec, plant_factors

#: Base scenarios loaded in this process, by sweep digest (a worker loads each once).
_BASES: dict[str, Scenario] = {}


def base_scenario(spec: SweepSpec) -> Scenario:
    """The sweep's base scenario (loaded once per process)."""
    key = spec.digest()
    if key not in _BASES:
        with warnings.catch_warnings():  # shown once, when the sweep file was read
            warnings.simplefilter("ignore", ScenarioWarning)
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
    plant = data.get("plant")
    if isinstance(plant, dict) and isinstance(plant.get("payload"), dict):
        payload = {**plant["payload"], "mass": values["mass"]}
        if "volume" in values:
            payload["volume"] = values["volume"]
        data["plant"] = {**plant, "payload": payload}


def _sensors(data: dict[str, Any], values: dict[str, Any], seed: int) -> None:
    if values:
        data["sensors"] = {**(data.get("sensors") or {}), **values, "seed": sensor_seed(seed)}


def _plant(data: dict[str, Any], spec: SweepSpec, values: dict[str, Any]) -> None:
    if spec.plant != "dynamic" and not isinstance(data.get("plant"), dict):
        return
    table = {**(data.get("plant") or {}), "type": spec.plant}  # the sweep's plant decides
    if PARAMETER_SET in values:
        table.pop("file", None)
        table["parameters"] = values[PARAMETER_SET]
    data["plant"] = table


def realise(spec: SweepSpec, parameters: dict[str, Any], seed: int) -> Scenario:
    """The scenario of the run of seed ``seed`` that drew ``parameters``.

    Raises:
        ConfigError: the drawn values make an invalid scenario (e.g. an initial pose that the
            hard constraints cannot start from); the run is recorded with this error.
    """
    base = base_scenario(spec)
    data = copy.deepcopy(spec.scenario_data)
    _plant(data, spec, _values(parameters, "plant_parameters"))
    _initial(data, base, _values(parameters, "initial"))
    _current(data, _values(parameters, "current"))
    _sensors(data, _values(parameters, "sensors"), seed)
    _payload(data, _values(parameters, "payload"))
    with warnings.catch_warnings():
        # the base scenario's warnings were shown when the sweep file was read; a perturbed
        # start away from the tool's path is what the sweep asks for, not a mistake to flag
        warnings.simplefilter("ignore", ScenarioWarning)
        scenario = scenario_from_dict(data, source=spec.scenario_path, name=base.name)
    if spec.duration is not None:
        scenario = scenario.with_duration(spec.duration)
    factors = plant_factors(parameters)
    if factors:
        plant = dataclasses.replace(scenario.plant,
                                    parameters=scenario.plant.parameters.scaled(factors))
        scenario = dataclasses.replace(scenario, plant=plant)
    return scenario
