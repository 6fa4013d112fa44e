"""Kinematic simulation: trajectories, current, integration, scenarios, runs, metrics, plots.

Modules import lazily; the common names are re-exported here.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY: dict[str, str] = {
    "TrajectorySample": ".trajectories",
    "Trajectory": ".trajectories",
    "QuinticTrajectory": ".trajectories",
    "LineTrajectory": ".trajectories",
    "CircleTrajectory": ".trajectories",
    "WaypointTrajectory": ".trajectories",
    "FixedTarget": ".trajectories",
    "TRAJECTORY_TYPES": ".trajectories",
    "ConstantCurrent": ".current",
    "Integrator": ".integrators",
    "Scenario": ".scenario",
    "Event": ".scenario",
    "Phase": ".scenario",
    "load_scenario": ".scenario",
    "bundled_scenarios": ".scenario",
    "register_model_file": ".model_file",
    "simulate": ".runner",
    "SimulationResult": ".runner",
    "compute_metrics": ".metrics",
    "write_results": ".results",
    "plot_results": ".plots",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    module_name = _LAZY.get(name)
    if module_name is None:
        raise AttributeError(f"module 'uvms_qp.sim' has no attribute {name!r}")
    value = getattr(importlib.import_module(module_name, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
