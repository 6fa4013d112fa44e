"""Variants of the bundled paper scenarios for the papers' tests.

The tests change a scenario's step or duration, or apply its ``[scheme_options]`` table, by
editing the file's parsed TOML and building the scenario with
:func:`uvms_qp.sim.scenario.scenario_from_dict`.
"""

from __future__ import annotations

import tomllib
from typing import Any

from uvms_qp.schemes import SCHEME_TYPES
from uvms_qp.sim.comparison import (
    UNTRACKED_METRICS,
    Comparison,
    SchemeRun,
    _Recorder,
    extra_metrics,
)
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import Scenario, resolve_scenario, scenario_from_dict

#: Tables timed in seconds, dropped when a variant shortens the run.
TIMED = ("phases", "events")


def scenario_data(name: str) -> dict[str, Any]:
    """A fresh copy of the parsed TOML of bundled scenario ``name``."""
    return tomllib.loads(resolve_scenario(name).read_text())


def variant(name: str, **changes: Any) -> Scenario:
    """Bundled scenario ``name`` with top-level keys replaced (e.g. ``dt``, ``duration``).

    A shorter ``duration`` drops the phases and events (they may lie past its end).
    """
    data = scenario_data(name)
    if "duration" in changes and changes["duration"] < data["duration"]:
        for key in TIMED:
            data.pop(key, None)
    data.update(changes)
    return scenario_from_dict(data, name=f"{name}_variant")


def scheme_options(name: str) -> dict[str, dict[str, Any]]:
    """The ``[scheme_options]`` table of bundled scenario ``name`` (scheme -> keyword arguments)."""
    return scenario_data(name)["scheme_options"]


def compare_with_scheme_options(name: str) -> Comparison:
    """Every scheme of bundled scenario ``name`` (``hqp`` first), each built from its table.

    For scenarios whose schemes take nothing else from the scenario but the tool trajectory
    (the table's keyword arguments are the scheme's only ones).
    """
    data = scenario_data(name)
    table = data.pop("scheme_options")
    runs = []
    for scheme_name in scenario_from_dict(data, name=name).schemes:
        scenario = scenario_from_dict(data, name=name)
        if scheme_name == "hqp":
            scheme = scenario.make_controller()
        else:
            cls = SCHEME_TYPES[scheme_name]
            scheme = cls(**table.get(scheme_name, {})).bind(scenario.model, scenario.dt)
            if cls.needs_trajectory:
                [trajectory] = scenario.trajectories.values()
                scheme.track(trajectory)
        recorder = _Recorder(scheme)
        result = simulate(scenario, recorder, scheme_name=scheme_name)
        metrics = dict(result.metrics())
        metrics.update(extra_metrics(result, scenario.model))
        if not getattr(scheme, "needs_trajectory", True):
            for key in UNTRACKED_METRICS:
                metrics.pop(key, None)
        runs.append(SchemeRun(scheme_name, result, recorder.arrays(), metrics))
    return Comparison(data["name"], data.get("description", ""), runs)
