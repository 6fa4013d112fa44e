"""Abstract closed-form scheme: the papers' redundancy resolutions as controllers.

A scheme is built from keyword arguments (so a scenario file can name it), bound to a model and a
control period once (:meth:`Scheme.bind`), given a reference trajectory for the tool
(:meth:`Scheme.track`, when the scheme tracks one), then stepped every tick exactly like the HQP
:class:`~uvms_qp.controller.Controller`::

    result = scheme.step(state, t)     # result.zeta [m/s, rad/s], result.status, result.summary()

:meth:`Scheme.reset` clears any memory between ticks (previous vehicle pose, previous rates), so a
scheme can be re-run from a new initial state. Subclasses implement :meth:`Scheme._bind` (model
checks) and :meth:`Scheme._compute` (the scheme's formula); the base times the step, checks that
``zeta`` is finite and packs the :class:`~uvms_qp.controller.StepResult`.

Every scheme also records the scalar quantities that its paper plots (shaping function, fuzzy
weights, ...) in :attr:`Scheme.info` after each step, so comparisons can plot them.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .._validation import FloatArray, as_scalar, as_time
from ..controller import StepResult, not_a_state
from ..errors import InputError, NonFiniteError
from ..hqp import Status

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


def check_scheme_name(name: Any, default: str) -> str:
    """Return a valid scheme name (a non-empty string without surrounding spaces)."""
    if name is None:
        return default
    if not isinstance(name, str) or not name.strip() or name != name.strip():
        raise InputError(
            f"name: expected a non-empty string without surrounding spaces, got {name!r}"
        )
    return name


class Scheme(ABC):
    """Base class of the closed-form paper schemes.

    Subclasses set ``type_name`` (the scenario key), ``vehicle_kinds`` (model kinds accepted) and
    ``needs_trajectory``; they implement :meth:`_bind` and :meth:`_compute`.

    Attributes:
        name: Label of the scheme in results and tables.
        model: The bound model (None before :meth:`bind`).
        dt: Control period [s] (None before :meth:`bind`).
        trajectory: Tool reference (anything with ``sample(t)``), or None.
        info: Scalars recorded at the last step (name -> value), e.g. ``{"k": 0.3}``.
    """

    type_name: ClassVar[str] = "scheme"
    #: Recorded as the "solver" of a run (closed-form schemes solve no optimisation problem).
    solver_name: ClassVar[str] = "closed-form"
    vehicle_kinds: ClassVar[tuple[str, ...]] = ("planar", "spatial", "fixed")
    needs_trajectory: ClassVar[bool] = True

    def __init__(self, *, name: str | None = None) -> None:
        self.name = check_scheme_name(name, self.type_name)
        self.model: Model | None = None
        self.dt: float | None = None
        self.trajectory: Any = None
        self.info: dict[str, float] = {}

    # -- set-up ---------------------------------------------------------------------------------

    def bind(self, model: Model, dt: float) -> Scheme:
        """Check the scheme against ``model``, store the control period and reset; returns self.

        Raises:
            InputError: a model kind the scheme does not handle, a non-positive ``dt``, or a
                model that lacks what the scheme needs (named in the message).
        """
        kind = getattr(model, "vehicle_kind", None)
        if kind not in self.vehicle_kinds:
            kinds = " or ".join(repr(k) for k in self.vehicle_kinds)
            of_type = "" if self.name == self.type_name else f" (scheme type {self.type_name!r})"
            raise InputError(
                f"{self.name}{of_type}: needs a model with vehicle kind {kinds}, got {kind!r} "
                f"(model {getattr(model, 'name', '?')!r})"
            )
        self.dt = as_scalar(dt, f"{self.name}.dt", positive=True)
        self.model = model
        self._bind(model)
        self.reset()
        return self

    def track(self, trajectory: Any) -> None:
        """Set the tool reference: any object with ``sample(t)`` returning position/velocity."""
        if not callable(getattr(trajectory, "sample", None)):
            raise InputError(f"{self.name}: trajectory must have a sample(t) method")
        self.trajectory = trajectory

    def reset(self) -> None:
        """Forget the memory kept between steps (overridden by schemes that keep some)."""
        self.info = {}

    # -- stepping -------------------------------------------------------------------------------

    def step(self, state: State, t: float) -> StepResult:
        """Compute the rates ``zeta`` for ``state`` at time ``t`` [s].

        Raises:
            InputError: the scheme is not bound, its trajectory was never set, ``state`` is
                not a State (e.g. a configuration array), or ``t`` is not a real number.
            NonFiniteError: the formula produced NaN or inf (never silently passed on), or ``t``
                is NaN or inf.
        """
        t = as_time(t)
        if self.model is None:
            raise InputError(f"{self.name}: call bind(model, dt) before step()")
        if not hasattr(state, "model"):
            raise not_a_state(state)
        if self.needs_trajectory and self.trajectory is None:
            raise InputError(f"{self.name}: no trajectory set; call track(trajectory) first")
        start = time.perf_counter()
        zeta, residuals = self._compute(state, t)
        elapsed = time.perf_counter() - start
        if not np.all(np.isfinite(zeta)):
            raise NonFiniteError(f"{self.name}: the scheme produced non-finite rates at t = {t}")
        return _make_result(self.name, zeta, residuals, elapsed, t)

    @abstractmethod
    def _bind(self, model: Model) -> None:
        """Validate the model and cache what the scheme needs (indices, weights...)."""

    @abstractmethod
    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        """Return ``(zeta, residuals)``; residuals map a task name to ``(norm, unit)``."""


def _make_result(
    name: str, zeta: FloatArray, residuals: dict[str, tuple[float, str]], step_time: float,
    t: float,
) -> StepResult:
    """Pack a closed-form step into the controller's result type.

    No hierarchy solve (``hierarchy`` is None), status ``optimal``, an unbounded box (a
    closed-form scheme knows no hard bounds); ``task_residuals`` and ``task_errors`` report the
    scheme's own task error norms with their units, all in one level.
    """
    z = np.asarray(zeta, dtype=np.float64)
    n = z.shape[0]
    return StepResult(
        z, Status.OPTIMAL, None, t, step_time, name, "closed-form", np.full(n, -np.inf),
        np.full(n, np.inf), level_names=(tuple(residuals),) if residuals else (),
        task_residuals=dict(residuals), task_errors=dict(residuals))
