"""The source papers' redundancy resolutions as controllers (same interface as the HQP controller).

Every scheme has ``step(state, t) -> StepResult`` and ``reset()``, so the simulator runs it like
:class:`~uvms_qp.controller.Controller`. ``SCHEME_TYPES`` maps the names a scenario lists in
``schemes = [...]`` to the classes; :func:`build_scheme` builds one for a loaded scenario, taking
from the scenario what the paper's set-up shares with the HQP stack (the tool trajectory, the
metric W, the current's heading, the payload force).

| name | paper, equation |
|---|---|
| ``soylu_sr_task_priority`` | 000, Eq. (16) |
| ``soylu_dexterous`` | 000, Eq. (21) |
| ``santos_kinematic_constraint`` | 001, Eq. (19)-(26) |
| ``santos_sr_task_priority`` | 001, Eq. (28) |
| ``nenchev_sc`` / ``nenchev_sc_self_motion`` | 002, Eq. (3) with b_sm = 0 / 1 |
| ``wang_pseudoinverse`` | 003, Eq. (6) |
| ``wang_fuzzy_gradient_projection`` | 003, Eq. (23), projector ``I - J_W^+ J`` |
| ``wang_fuzzy_gradient_projection_euclidean`` | 003, Eq. (23), projector ``I - J^+ J`` |
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ConfigError, UvmsQpError
from .nenchev import NenchevSingularityConsistent
from .santos import SantosKinematicConstraint, SantosTaskPriority
from .scheme import Scheme
from .soylu import SoyluDexterous, SoyluTaskPriority
from .wang import WangEuclideanProjection, WangFuzzyGradientProjection, WangPseudoinverse


class NenchevSelfMotion(NenchevSingularityConsistent):
    """Nenchev and Tsumaki's second run: end-point and self-motion with equal weight (b_sm = 1)."""

    type_name = "nenchev_sc_self_motion"

    def __init__(
        self,
        *,
        direction: tuple[float, float, float] = (1.0, 0.0, 0.0),
        b_ep: float = 1.0,
        b_sm: float = 1.0,
        d3: float = 1.0,
        d5: float = 1.0,
        shoulder_tolerance: float = 1e-9,
        name: str | None = None,
    ) -> None:
        super().__init__(direction=direction, b_ep=b_ep, b_sm=b_sm, d3=d3, d5=d5,
                         shoulder_tolerance=shoulder_tolerance, name=name)


SCHEME_TYPES: dict[str, type[Scheme]] = {
    cls.type_name: cls
    for cls in (
        SoyluTaskPriority,
        SoyluDexterous,
        SantosKinematicConstraint,
        SantosTaskPriority,
        NenchevSingularityConsistent,
        NenchevSelfMotion,
        WangPseudoinverse,
        WangFuzzyGradientProjection,
        WangEuclideanProjection,
    )
}
"""Scenario scheme name -> scheme class (``"hqp"`` is the scenario's own stack)."""


def _options(cls: type[Scheme], scenario: Any, stack: Any) -> dict[str, Any]:
    """Keyword arguments a scheme takes from the scenario it is compared in and its stack."""
    options: dict[str, Any] = {}
    if issubclass(cls, SoyluTaskPriority) and scenario.metric is not None:
        options["weights"] = [float(w) for w in np.asarray(scenario.metric)]
    if issubclass(cls, SantosTaskPriority) and scenario.current is not None:
        options["heading"] = float(scenario.current.heading)
    if issubclass(cls, WangFuzzyGradientProjection):
        for task in stack.tasks:
            if getattr(task, "type_name", "") == "payload_moment":
                options["force"] = float(task.force)
                break
    return options


def build_scheme(name: str, scenario: Any, path: str = "schemes", *, stack: Any = None) -> Scheme:
    """Build, bind and aim the scheme ``name`` for a scenario.

    The scheme's keyword arguments are what it shares with the scenario (the metric W, the
    current's heading, the payload force of the stack's payload task), overridden by the
    scenario's ``[scheme_options.<name>]``; its tool reference is the scenario's
    ``tracking_trajectory``.

    Args:
        name: Key of :data:`SCHEME_TYPES`.
        scenario: A :class:`~uvms_qp.sim.scenario.Scenario`.
        path: Field path used in error messages.
        stack: The run's stack, read for the payload force (default: a new one of the scenario).

    Raises:
        ConfigError: unknown scheme (the known ones are listed), a model the scheme cannot
            handle, or a scheme that needs a trajectory the scenario does not define.
    """
    cls = SCHEME_TYPES.get(name)
    if cls is None:
        known = ", ".join(["hqp", *sorted(SCHEME_TYPES)])
        raise ConfigError(f"unknown scheme {name!r}; known schemes: {known}", path)
    try:
        options = _options(cls, scenario, scenario.build_stack() if stack is None else stack)
        options.update(scenario.scheme_options.get(name, {}))
        scheme = cls(**options)
        scheme.bind(scenario.model, scenario.dt)
        if cls.needs_trajectory:
            if scenario.tracking_trajectory is None:
                raise ConfigError(
                    f"scheme {name!r} tracks the tool trajectory, but the scenario's tracking task "
                    "has none", path
                )
            scheme.track(scenario.tracking_trajectory)
    except ConfigError:
        raise
    except (UvmsQpError, ValueError) as exc:
        # the scheme's own messages start with its name: say it once
        message = str(exc).removeprefix(f"{name}: ").removeprefix(f"{name}.")
        raise ConfigError(f"scheme {name!r}: {message}", path) from exc
    return scheme


__all__ = [
    "SCHEME_TYPES",
    "NenchevSelfMotion",
    "NenchevSingularityConsistent",
    "SantosKinematicConstraint",
    "SantosTaskPriority",
    "Scheme",
    "SoyluDexterous",
    "SoyluTaskPriority",
    "WangEuclideanProjection",
    "WangFuzzyGradientProjection",
    "WangPseudoinverse",
    "build_scheme",
]
