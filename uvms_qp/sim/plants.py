"""The plant a closed-loop run drives: what happens to the vehicle and the arm between two ticks.

Every control period the runner hands the controller's command ``zeta`` to a plant, which
advances the true state by ``dt`` and says what it became:

- :class:`KinematicPlant` realises the command exactly: ``zeta`` is integrated on the
  configuration manifold by the scenario's :class:`~uvms_qp.sim.integrators.Integrator` (the
  kinematic simulation of the papers; no hydrodynamics);
- :class:`~uvms_qp.sim.dynamic_plant.DynamicPlant` is a floating UVMS: ``zeta`` is a velocity
  reference that a vehicle velocity loop, the thrusters and the arm's joint servos track, under
  rigid-body and hydrodynamic forces (:mod:`uvms_qp.dynamics`).

A plant keeps its own state (``q`` and, for a dynamic plant, the velocity); ``start(q0)``
begins a run from rest at ``q0``. ``series()`` returns what the plant recorded beyond the
configuration (``None`` for the kinematic plant).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from .._validation import FloatArray
from .integrators import Integrator

#: ``rates(q, t) -> zeta``: the controller evaluated at another configuration (for ``rk4``).
RateFunction = Callable[[FloatArray, float], FloatArray]


class Plant(Protocol):
    """What the runner needs of a plant."""

    #: ``"kinematic"`` or ``"dynamic"``.
    kind: str

    def start(self, q0: FloatArray) -> None:
        """Begin a run at rest at configuration ``q0`` (nq,)."""

    @property
    def q(self) -> FloatArray:
        """The true configuration (nq,)."""

    @property
    def body_velocity(self) -> FloatArray | None:
        """The true vehicle body velocity ``nu`` (6,) [m/s, rad/s], None when not simulated."""

    def advance(self, zeta: FloatArray, t: float, rates: RateFunction) -> FloatArray:
        """Apply ``zeta`` (nv,) from time ``t`` [s] for one control period; the new true q."""

    def series(self, steps: int) -> Any:
        """What the plant recorded over the first ``steps`` control periods (None: nothing)."""

    def settings(self, spec: Any) -> dict[str, Any]:
        """What the run's record says of the plant (``results.json``: ``plant_settings``).

        ``spec`` is the scenario's :class:`~uvms_qp.sim.plant_config.PlantSpec`.
        """


class RunState:
    """The true configuration a plant keeps between ``start`` and the end of a run."""

    def __init__(self) -> None:
        self._q: FloatArray | None = None

    @property
    def q(self) -> FloatArray:
        """The true configuration (nq,)."""
        if self._q is None:
            raise RuntimeError("the plant has not been started")
        return self._q


class KinematicPlant(RunState):
    """The command realised exactly, integrated by ``integrator`` over ``dt`` [s]."""

    kind = "kinematic"

    def __init__(self, integrator: Integrator, dt: float) -> None:
        super().__init__()
        self.integrator = integrator
        self.dt = dt

    def start(self, q0: FloatArray) -> None:
        """Begin a run at ``q0``."""
        self._q = q0

    @property
    def body_velocity(self) -> FloatArray | None:
        """None: the kinematic plant has no velocity state (the command is the velocity)."""
        return None

    def advance(self, zeta: FloatArray, t: float, rates: RateFunction) -> FloatArray:
        """``integrator.step`` of the held command."""
        self._q = self.integrator.step(self.q, zeta, self.dt, t, rates)
        return self._q

    def series(self, steps: int) -> None:
        """Nothing beyond the configuration."""
        return None

    def settings(self, spec: Any) -> dict[str, Any]:
        """The scenario's plant table as given (nothing of it drives an exact plant)."""
        return dict(spec.settings())
