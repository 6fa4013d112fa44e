"""Abstract task: a block of rows ``lower <= A zeta <= upper`` over the decision vector.

A task is a description. It is built from keyword arguments (so a scenario loader can build it
from a table), validated once per parameter (the same validator serves the constructor and
:meth:`Task.update`), bound to a model once (:meth:`Task.bind` checks frames, joints and
dimensions and fixes the row count), then evaluated every control tick on a
:class:`~uvms_qp.model.State` and a :class:`~uvms_qp.tasks.slot.TaskSlot`: the run-time memory
of the task in one controller (held targets, previous values, the last error), which the
controller owns. A task keeps no run-time state, so any number of controllers may evaluate it.

Each task class writes exactly one evaluation:

* error-regulating tasks (:class:`~uvms_qp.tasks.ErrorTask`) implement ``error_rows(state, t,
  slot)``, returning the Jacobian ``J`` of the regulated quantity ``x`` over zeta
  (``x_dot = J zeta``), the error ``e = x_d - x`` and the feed-forward rate ``x_dot_d``; the
  base writes the closed-loop inverse-kinematics rows ``J zeta = x_dot_d + K e``, the
  closed-loop form of Soylu et al. (2007), Eq. (16);
* other tasks (set-based rows, objectives) implement :meth:`Task.evaluate` ``-> (J, lower,
  upper)``.

The rest is defined once here: :meth:`Task.fill` writes the rows into caller-owned buffers (what
the controller calls every tick, in as few numpy calls as the rows allow; a ``J`` returned as
the same read-only array every time is written once) and :meth:`Task.rows` returns fresh
:class:`~uvms_qp.rows.Rows`.

Whether a task is in the stack (its activation, the ramps between) belongs to the stack
(:meth:`~uvms_qp.stack.Stack.set_activation`), as TSID's formulation owns a task's priority and
transitions while the task only computes.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar, final

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError, ShapeError
from ..rows import Rows
from ._checks import check_task_name, constructor_keywords, fits, shape_of
from .slot import TaskSlot

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

STACK_KEYS = ("activation", "ramp")  #: keys of a task's stack entry (``Stack.set_activation``)


class Task(ABC):
    """Base class of every task.

    Subclasses set the class attributes ``type_name`` (the scenario registry key), ``error_unit``
    (unit of the task error or objective, e.g. ``"m"``) and ``rate_unit`` (unit of the rows, e.g.
    ``"m/s"``), implement :meth:`_bind` (validation against the model; returns the row count) and
    :meth:`evaluate` (or ``ErrorTask.error_rows``). A task whose rows depend on its axes narrows
    the units on the instance in :meth:`_bind` (a position-only end-effector task reports
    ``"m/s"``), and the bound instance's units are the ones reported.

    Parameters that change at run time are listed by :meth:`updatable`; each has one validator,
    :meth:`_check`, used by the constructor and by :meth:`update`. A task class with run-time
    memory names its :class:`~uvms_qp.tasks.slot.TaskSlot` subclass in ``Slot``.

    Attributes:
        name: Unique name of the task inside a stack.
        weight: Positive weight of the task's rows relative to the other tasks of its level
            (weights only act within a level; levels are strict priorities).
        model: The bound model, or None before :meth:`bind`.
        dim: Number of rows (known after :meth:`bind`).
        row_weights: Per-row weights (dim,), task weight included; a new array after every
            :meth:`update` (so a consumer re-reads the weights, and checks the task against its
            control period again, only then).
    """

    type_name: ClassVar[str] = "task"
    error_unit: str = ""
    rate_unit: str = ""
    Slot: ClassVar[type[TaskSlot]] = TaskSlot
    #: True for a task whose row weights follow the state (written into ``slot.row_weights``).
    weights_per_tick: ClassVar[bool] = False

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        """Refuse an unknown keyword naming the accepted ones (before any validation)."""
        accepted = constructor_keywords(cls)
        unknown = sorted(set(kwargs) - accepted) if accepted is not None else []
        if unknown:
            key = unknown[0]
            hint = (f"; {key!r} belongs to the task's stack entry: stack.set_activation(name, ...)"
                    if key in STACK_KEYS else "")
            raise InputError(f"{cls.__name__}: unknown keyword {key!r}; accepted: "
                             f"{', '.join(sorted(accepted))}{hint}")  # type: ignore[arg-type]
        return super().__new__(cls)

    def __init__(self, *, name: str | None = None, weight: float = 1.0) -> None:
        self.name = check_task_name(name, self.type_name)
        self.weight = self._check("weight", weight)
        self.model: Model | None = None
        self.dim = 0
        self.row_weights: FloatArray = np.zeros(0)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Keep the methods the base classes mark final (``fill``, ``rows``, ...) final.

        A task implements :meth:`evaluate` or ``ErrorTask.error_rows``; everything built on
        them is written once, in the base classes.
        """
        super().__init_subclass__(**kwargs)
        sealed = {name for base in cls.__mro__[1:] for name, member in vars(base).items()
                  if getattr(member, "__final__", False)}
        overridden = sorted(name for name in sealed & cls.__dict__.keys()
                            if not getattr(cls.__dict__[name], "__final__", False))
        if overridden:
            raise TypeError(f"{cls.__name__} overrides {', '.join(overridden)}: a task class "
                            "implements evaluate (or error_rows for an ErrorTask) only")

    # ----------------------------------------------------------------------------------- binding
    def bind(self, model: Model) -> Task:
        """Validate the task against ``model`` and size its rows.

        Raises:
            UnknownFrameError, UnknownJointError, InputError: a frame, joint or axis the model
                does not have, or a parameter of the wrong length.
        """
        dim = int(self._bind(model))
        self._check_dim(dim)
        self.model = model
        self.dim = dim
        self._derive()
        return self

    @abstractmethod
    def _bind(self, model: Model) -> int:
        """Validate against ``model``, precompute indices; return the number of rows."""

    def _check_dim(self, dim: int) -> None:  # noqa: B027 - optional hook, before bind assigns
        """Check parameters whose length depends on the row count."""

    def _derive(self) -> None:
        """Recompute what follows from the parameters (after bind and after every update)."""
        self.row_weights = np.full(self.dim, self.weight)

    def link(self, tasks: dict[str, Task]) -> None:  # noqa: B027 - optional hook
        """Resolve references to other tasks of the same stack (called by ``Stack.bind``).

        A linked task's run-time values are read from its slot in the same controller
        (``slot.peers``).

        Args:
            tasks: Every task of the stack by name.
        """

    def _require_bound(self) -> Model:
        if self.model is None:
            raise InputError(f"task {self.name!r} is not bound to a model; call bind(model) first")
        return self.model

    @property
    def equality_rows(self) -> bool:
        """True when every row is an equality (tasks with inequality rows override this)."""
        return True

    def new_slot(self) -> TaskSlot:
        """A new run-time memory for this task (one per controller; see :mod:`.slot`)."""
        return self.Slot()

    # ----------------------------------------------------------------------------------- evaluate
    @abstractmethod
    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The rows at ``(state, t)``: ``(J, lower, upper)``, with the memory ``slot``.

        ``J`` is ``(dim, nv)``; ``lower`` and ``upper`` are ``(dim,)`` arrays, lists or numbers
        (one value for every row), the same object for equality rows. The arrays may be
        read-only views of the state or of the task: copy them before modifying; rows that do
        not change are best returned as the same read-only array every time (:meth:`fill`
        writes them once). Sets ``slot.error``.
        """

    @final
    def fill(self, state: State, t: float, A: FloatArray, sides: FloatArray,
             slot: TaskSlot) -> None:
        """Write the rows at ``(state, t)`` into ``A`` (dim, nv) and ``sides`` (2, dim).

        ``sides`` holds the lower sides, then the upper ones. The buffers may hold stale values:
        every entry is written, except that ``A`` is not written again when it received this
        very ``J`` array (read-only) at the previous fill with this ``slot``.

        Raises:
            ShapeError: rows that do not fit ``A`` and ``sides`` (naming the task).
        """
        J, lo, hi = self.evaluate(state, t, slot)
        try:  # (numpy would broadcast a row or a side of one value into every row)
            written = slot.written
            if J is not written[1] or A is not written[0]:
                if J.shape != A.shape:
                    raise ValueError
                A[...] = J
                slot.written = (A, J)
            rows = A.shape[0]
            if hi is lo:  # equality rows: one write of both sides
                if not fits(lo, rows):
                    raise ValueError
                sides[...] = lo
            else:
                if not (fits(lo, rows) and fits(hi, rows)):
                    raise ValueError
                sides[0] = lo
                sides[1] = hi
        except (ValueError, TypeError, AttributeError):
            raise self._shape_error("evaluate", A, J=J, lower=lo, upper=hi) from None

    def _shape_error(self, method: str, A: FloatArray, **returned: Any) -> ShapeError:
        """The error for rows of ``method`` that do not fit the task's (dim, nv) slot."""
        dim, nv = A.shape
        got = ", ".join(f"{k} {shape_of(v)}" for k, v in returned.items())
        return ShapeError(f"task {self.name!r}: {type(self).__name__}.{method} returned {got}; "
                          f"expected J ({dim}, {nv}) and ({dim},) vectors (or numbers) for the "
                          f"other parts ({dim} rows, as bind returned)")

    @final
    def rows(self, state: State, t: float = 0.0, slot: TaskSlot | None = None) -> Rows:
        """Rows ``lower <= A zeta <= upper`` at ``state`` and time ``t`` [s] (fresh arrays).

        ``slot`` is the memory to evaluate with (default: a new one, so a held target is the
        one of ``state``).
        """
        model = self._require_bound()
        A = np.empty((self.dim, model.nv))
        sides = np.empty((2, self.dim))
        slot = self.new_slot() if slot is None else slot
        self.fill(state, t, A, sides, slot)
        weights = slot.row_weights if self.weights_per_tick else self.row_weights
        return Rows(A, sides[0], sides[1], np.array(weights), self.name)

    def residual(self, state: State, zeta: Any, t: float = 0.0,
                 slot: TaskSlot | None = None) -> float:
        """Norm of the row violation at ``zeta`` [rate_unit]: distance of ``A zeta`` to its band."""
        model = self._require_bound()
        x = as_vector(zeta, "zeta", model.nv)
        return float(np.linalg.norm(self.rows(state, t, slot).violation(x)))

    # ------------------------------------------------------------------------------- parameters
    def check_period(self, dt: float) -> None:  # noqa: B027 - optional hook
        """Check the task against the control period ``dt`` [s].

        Called by the controller when it is built and after every :meth:`update`. Tasks with
        set-based rows refuse a gain with ``gain * dt > 1``
        (:func:`~uvms_qp.tasks._checks.check_barrier_gain`), error tasks one with
        ``gain * dt >= 2`` (``ErrorTask.check_period``).

        Raises:
            InputError: the task's rows would not settle at this period.
        """

    def update(self, **params: Any) -> None:
        """Change parameters at run time (validated), e.g. ``payload.update(force=20.0)``.

        Subclasses list the parameters they accept in :meth:`updatable`. Every value is
        validated before any is assigned, so a rejected one leaves the task as it was. A
        controller checks the task against its period at its next step
        (:meth:`check_period`).

        Raises:
            InputError: an unknown parameter or an invalid value.
        """
        allowed = self.updatable()
        for key in params:
            if key in STACK_KEYS:
                raise InputError(
                    f"{self.name}.update: {key!r} belongs to the task's stack entry; use "
                    f"stack.set_activation({self.name!r}, ...)")
            if key not in allowed:
                raise InputError(
                    f"{self.name}.update: unknown parameter {key!r}; known: {', '.join(allowed)}")
        values = self._checked(params)
        for key, value in values.items():
            setattr(self, key, value)
        self._derive()

    def updatable(self) -> tuple[str, ...]:
        """Names of the parameters :meth:`update` accepts."""
        return ("weight",)

    def _checked(self, params: dict[str, Any]) -> dict[str, Any]:
        """The validated attribute values of ``params`` (nothing is assigned here)."""
        return {key: self._check(key, value) for key, value in params.items()}

    def _check(self, key: str, value: Any) -> Any:
        """The one validator of parameter ``key``: the value to keep, or an InputError."""
        if key == "weight":
            return as_scalar(value, f"{self.name}.weight", positive=True)
        raise InputError(f"{self.name}: no parameter {key!r}")  # pragma: no cover

    def describe(self) -> str:
        """One line: name, type, rows, weight, units."""
        return (f"{self.name} ({self.type_name}): {self.dim} rows, weight {self.weight:g}, "
                f"error [{self.error_unit}], rows [{self.rate_unit}]")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, weight={self.weight:g})"

