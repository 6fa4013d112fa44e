"""Variants of the bundled paper scenarios for the papers' tests.

The tests change a scenario's step or duration, or read its ``[scheme_options]`` table, by
editing the file's parsed TOML and building the scenario with
:func:`uvms_qp.sim.scenario.scenario_from_dict`.
"""

from __future__ import annotations

import tomllib
from typing import Any

from uvms_qp.sim.scenario import Scenario, resolve_scenario, scenario_from_dict

#: Tables timed in seconds, dropped when a variant shortens the run.
TIMED = ("phases", "events")


def scenario_data(name: str) -> dict[str, Any]:
    """A fresh copy of the parsed TOML of bundled scenario ``name``."""
    return tomllib.loads(resolve_scenario(name).read_text())


def variant(name: str, **changes: Any) -> Scenario:
    """Bundled scenario ``name`` with top-level keys replaced (e.g. ``dt``, ``duration``).

    A shorter ``duration`` drops the phases and events (they may lie past its end), and the
    plant's payload, which is taken at a time.
    """
    data = scenario_data(name)
    if "duration" in changes and changes["duration"] < data["duration"]:
        for key in TIMED:
            data.pop(key, None)
        data.get("plant", {}).pop("payload", None)
    data.update(changes)
    return scenario_from_dict(data, name=f"{name}_variant")


def scheme_options(name: str) -> dict[str, dict[str, Any]]:
    """The ``[scheme_options]`` table of bundled scenario ``name`` (scheme -> keyword arguments)."""
    return scenario_data(name)["scheme_options"]
