"""uvms-qp: QP-based whole-body task-priority kinematic control of underwater vehicle-manipulators.

The decision vector is ``zeta = [actuated vehicle body rates; arm joint rates]`` (m/s, rad/s).
Public names are imported lazily so that ``import uvms_qp`` stays cheap.
"""

from __future__ import annotations

import importlib
from typing import Any

from .errors import (
    BoundsError,
    ConfigError,
    InputError,
    ModelError,
    ModelFileError,
    NonFiniteError,
    NoSolutionFound,
    ScenarioWarning,
    ShapeError,
    SolverError,
    UnknownFrameError,
    UnknownJointError,
    UnknownModelError,
    UnknownNameError,
    UnknownSolverError,
    UvmsQpError,
)

__version__ = "0.1.0"

# public name -> module that defines it (relative to this package)
_LAZY: dict[str, str] = {
    "Rows": ".rows",
    "solve_hierarchy": ".hqp",
    "HierarchyResult": ".hqp",
    "Status": ".hqp",
    "available_solvers": ".hqp",
    "Model": ".model",
    "State": ".model",
    "load_model": ".model",
    "bundled_models": ".model",
    "Stack": ".stack",
    "Level": ".stack",
    "Controller": ".controller",
    "StepResult": ".controller",
}

__all__ = [
    "BoundsError",
    "ConfigError",
    "InputError",
    "ModelError",
    "ModelFileError",
    "NoSolutionFound",
    "NonFiniteError",
    "ScenarioWarning",
    "ShapeError",
    "SolverError",
    "UnknownFrameError",
    "UnknownJointError",
    "UnknownModelError",
    "UnknownNameError",
    "UnknownSolverError",
    "UvmsQpError",
    "__version__",
    *sorted(_LAZY),
]


def __getattr__(name: str) -> Any:
    module_name = _LAZY.get(name)
    if module_name is None:
        raise AttributeError(f"module 'uvms_qp' has no attribute {name!r}")
    value = getattr(importlib.import_module(module_name, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
