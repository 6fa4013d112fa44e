"""Comparisons of bundled scenarios whose schemes take options from a ``[scheme_options]`` table.

:func:`compare_with_scheme_options` runs like :func:`uvms_qp.sim.comparison.compare`, with the
table applied in Python: it is removed from the scenario data, and each listed scheme is built
from the keyword arguments it takes from the scenario overridden by its table.
"""

from __future__ import annotations

import tomllib
from typing import Any

from uvms_qp.schemes import SCHEME_TYPES, _options, _scenario_trajectory
from uvms_qp.sim.comparison import (
    UNTRACKED_METRICS,
    Comparison,
    SchemeRun,
    _Recorder,
    extra_metrics,
)
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import resolve_scenario, scenario_from_dict


def scheme_options(name: str) -> dict[str, dict[str, Any]]:
    """The ``[scheme_options]`` table of a bundled scenario (scheme name -> keyword arguments)."""
    return tomllib.loads(resolve_scenario(name).read_text())["scheme_options"]


def compare_with_scheme_options(name: str) -> Comparison:
    """Run every scheme of bundled scenario ``name`` (``hqp`` first) with its table's options."""
    path = resolve_scenario(name)
    data = tomllib.loads(path.read_text())
    table = data.pop("scheme_options")
    base = scenario_from_dict(data, source=path, name=path.stem)
    runs = []
    for scheme_name in base.schemes:
        scenario = base.rebuild()
        if scheme_name == "hqp":
            scheme = scenario.make_controller()
        else:
            cls = SCHEME_TYPES[scheme_name]
            scheme = cls(**{**_options(cls, scenario), **table.get(scheme_name, {})})
            scheme.bind(scenario.model, scenario.dt)
            if cls.needs_trajectory:
                scheme.track(_scenario_trajectory(scenario))
        recorder = _Recorder(scheme)
        result = simulate(scenario, recorder, scheme_name=scheme_name)
        metrics = dict(result.metrics())
        metrics.update(extra_metrics(result, scenario.model))
        if not getattr(scheme, "needs_trajectory", True):
            for key in UNTRACKED_METRICS:
                metrics.pop(key, None)
        runs.append(SchemeRun(scheme_name, result, recorder.arrays(), metrics))
    return Comparison(base.name, base.description, runs)
