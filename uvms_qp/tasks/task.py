"""Abstract task: a block of rows ``lower <= A zeta <= upper`` over the decision vector.

A task is built from keyword arguments (so a scenario loader can build it from a table), bound to a
model once (:meth:`Task.bind` checks frames, joints and dimensions and fixes the row count), then
evaluated every control tick on a :class:`~uvms_qp.model.State`:

* :meth:`Task.rows` returns a fresh :class:`~uvms_qp.rows.Rows` (for users and tests);
* :meth:`Task.fill` writes the same rows into caller-owned buffers (the controller's hot path, no
  allocation of the row block).

Error-regulating tasks (:class:`ErrorTask`) implement :meth:`ErrorTask.compute_error` ``e`` and
:meth:`ErrorTask.compute_jacobian` ``J`` (the Jacobian of the regulated quantity ``x`` over zeta,
``x_dot = J zeta``) and the base assembles the closed-loop inverse-kinematics rows

    J zeta = x_dot_d + K e,      e = x_d - x,

the closed-loop form of ``000_7b5f597fe4e36aa4.txt, Eq. (16)``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from ..rows import Rows

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


def check_task_name(name: Any, default: str) -> str:
    """Return a valid task name (non-empty string without surrounding spaces)."""
    if name is None:
        return default
    if not isinstance(name, str) or not name.strip() or name != name.strip():
        raise InputError(
            f"name: expected a non-empty string without surrounding spaces, got {name!r}")
    return name


def as_gain(value: Any, name: str = "gain") -> float | FloatArray:
    """Validate a gain [1/s]: a positive number or a list of positive numbers (one per row)."""
    if isinstance(value, list | tuple | np.ndarray):
        gains = as_vector(value, name)
        if np.any(gains < 0.0):
            raise InputError(f"{name}: expected non-negative gains, got {gains.tolist()}")
        return gains
    return as_scalar(value, name, nonnegative=True)


class Task(ABC):
    """Base class of every task.

    Subclasses set the class attributes ``type_name`` (the scenario registry key), ``error_unit``
    (unit of the task error or objective, e.g. ``"m"``) and ``rate_unit`` (unit of the rows, e.g.
    ``"m/s"``), implement :meth:`_bind` (validation against the model; returns the row count) and
    :meth:`fill`. The class units describe every configuration of the task; a task whose rows
    depend on its mode or axes narrows them on the instance in :meth:`_bind` (a position-only
    end-effector task reports ``"m/s"``), and the bound instance's units are the ones reported.

    Attributes:
        name: Unique name of the task inside a stack.
        weight: Positive weight of the task's rows relative to the other tasks of its level
            (weights only act within a level; levels are strict priorities).
        model: The bound model, or None before :meth:`bind`.
        dim: Number of rows (known after :meth:`bind`).
    """

    type_name: ClassVar[str] = "task"
    error_unit: str = ""
    rate_unit: str = ""

    def __init__(self, *, name: str | None = None, weight: float = 1.0) -> None:
        self.name = check_task_name(name, self.type_name)
        self.weight = as_scalar(weight, f"{self.name}.weight", positive=True)
        self.model: Model | None = None
        self.dim = 0
        self._row_weights: FloatArray = np.zeros(0)
        self.last_error: FloatArray | None = None

    # ----------------------------------------------------------------------------------- binding
    def bind(self, model: Model) -> Task:
        """Validate the task against ``model`` and size its rows.

        Raises:
            UnknownFrameError, UnknownJointError, InputError: a frame, joint or axis the model
                does not have, or a parameter of the wrong length.
        """
        dim = self._bind(model)
        self.model = model
        self.dim = int(dim)
        self._row_weights = np.full(self.dim, self.weight)
        self._update_row_weights()
        return self

    @abstractmethod
    def _bind(self, model: Model) -> int:
        """Validate against ``model``, precompute indices; return the number of rows."""

    def link(self, tasks: dict[str, Task]) -> None:  # noqa: B027 - optional hook
        """Resolve references to other tasks of the same stack (called by ``Stack.bind``).

        Args:
            tasks: Every task of the stack by name.
        """

    def _update_row_weights(self) -> None:  # noqa: B027 - optional hook
        """Hook for tasks with per-row weights (called after bind and after weight updates)."""

    @property
    def is_bound(self) -> bool:
        """True once :meth:`bind` succeeded."""
        return self.model is not None

    def _require_bound(self) -> Model:
        if self.model is None:
            raise InputError(f"task {self.name!r} is not bound to a model; call bind(model) first")
        return self.model

    @property
    def equality_rows(self) -> bool:
        """True when every row is an equality (tasks with inequality rows override this)."""
        return True

    @property
    def row_weights(self) -> FloatArray:
        """Per-row weights (dim,), task weight included."""
        return self._row_weights

    # ----------------------------------------------------------------------------------- evaluate
    @abstractmethod
    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write the rows at ``(state, t)`` into ``A`` (dim, nv), ``lower`` and ``upper`` (dim,).

        The buffers may hold stale values; every entry must be written.
        """

    def rows(self, state: State, t: float = 0.0) -> Rows:
        """Rows ``lower <= A zeta <= upper`` at ``state`` and time ``t`` [s] (fresh arrays)."""
        model = self._require_bound()
        A = np.zeros((self.dim, model.nv))
        lower = np.zeros(self.dim)
        upper = np.zeros(self.dim)
        self.fill(state, t, A, lower, upper)
        return Rows(A, lower, upper, self._row_weights.copy(), self.name)

    def residual(self, state: State, zeta: Any, t: float = 0.0) -> float:
        """Norm of the row violation at ``zeta`` [rate_unit]: distance of ``A zeta`` to its band."""
        model = self._require_bound()
        x = as_vector(zeta, "zeta", model.nv)
        return float(np.linalg.norm(self.rows(state, t).violation(x)))

    def error_norm(self) -> float:
        """Norm of the last task error or objective value computed by :meth:`fill` [error_unit].

        NaN before the first evaluation.
        """
        if self.last_error is None:
            return float("nan")
        return float(np.sqrt(self.last_error @ self.last_error))

    # ----------------------------------------------------------------------------------- run time
    def reset(self) -> None:  # noqa: B027 - optional hook
        """Forget run-time memory (activation pose, previous values); called by Controller.reset."""

    def update(self, **params: Any) -> None:
        """Change parameters at run time (validated), e.g. ``payload.update(force=20.0)``.

        Subclasses list the parameters they accept in :attr:`updatable`.

        Raises:
            InputError: an unknown parameter or an invalid value.
        """
        allowed = self.updatable()
        for key in params:
            if key not in allowed:
                raise InputError(
                    f"{self.name}.update: unknown parameter {key!r}; known: {', '.join(allowed)}"
                )
        for key, value in params.items():
            self._apply_update(key, value)

    def updatable(self) -> tuple[str, ...]:
        """Names of the parameters :meth:`update` accepts."""
        return ("weight",)

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "weight":
            self.weight = as_scalar(value, f"{self.name}.weight", positive=True)
            if self.model is not None:
                self._row_weights = np.full(self.dim, self.weight)
                self._update_row_weights()
        else:  # pragma: no cover - guarded by update()
            raise InputError(f"{self.name}.update: cannot update {key!r}")

    def describe(self) -> str:
        """One line: name, type, rows, weight, units."""
        return (f"{self.name} ({self.type_name}): {self.dim} rows, weight {self.weight:g}, "
                f"error [{self.error_unit}], rows [{self.rate_unit}]")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, weight={self.weight:g})"


class ErrorTask(Task):
    """A task regulating an error ``e = x_d - x`` with gain ``K`` [1/s].

    Rows: ``J zeta = x_dot_d + K e`` (``000_7b5f597fe4e36aa4.txt, Eq. (16)``), where ``J`` is the
    Jacobian of ``x`` over zeta and ``x_dot_d`` the feed-forward rate of the target.
    Subclasses implement :meth:`compute_error` and :meth:`compute_jacobian`, and may override
    :meth:`compute_feedforward`.

    Attributes:
        gain: Scalar gain or per-row gains [1/s].
    """

    def __init__(self, *, name: str | None = None, weight: float = 1.0,
                 gain: float | list[float] = 1.0) -> None:
        super().__init__(name=name, weight=weight)
        self.gain: float | FloatArray = as_gain(gain, f"{self.name}.gain")
        self._fused = False

    def _defines_compute_methods(self) -> bool:
        """True when every class with its own :meth:`fill` sees the instance's ``compute_*``.

        Checked at bind: a fused ``fill`` (the same operations as the ``compute_*`` methods of
        its class) is valid only if no subclass replaced one of them.
        """
        cls = type(self)
        names = ("compute_error", "compute_jacobian", "compute_feedforward")
        # every class below ErrorTask with its own fill must see the methods the instance has
        return all(getattr(cls, name) is getattr(owner, name)
                   for owner in cls.__mro__[: cls.__mro__.index(ErrorTask)]
                   if "fill" in owner.__dict__ for name in names)

    def bind(self, model: Model) -> Task:
        """Bind (see :meth:`Task.bind`) and check the gain length against the row count."""
        super().bind(model)
        # a fused fill reproduces its own class's compute_* methods; a subclass overriding any
        # of them gets the generic fill that calls them
        self._fused = self._defines_compute_methods()
        if isinstance(self.gain, np.ndarray) and self.gain.shape[0] != self.dim:
            dim = self.dim
            self.model, self.dim = None, 0
            raise InputError(f"{self.name}.gain: expected {dim} gains (one per row), "
                             f"got {self.gain.shape[0]}")
        return self

    @abstractmethod
    def compute_error(self, state: State, t: float) -> FloatArray:
        """Task error ``e = x_d - x`` (dim,) [error_unit]."""

    @abstractmethod
    def compute_jacobian(self, state: State, t: float) -> FloatArray:
        """Jacobian ``J`` (dim, nv) of the regulated quantity: ``x_dot = J zeta``."""

    def compute_feedforward(self, state: State, t: float) -> FloatArray | None:
        """Feed-forward target rate ``x_dot_d`` (dim,) [rate_unit], or None for zero.

        Called after :meth:`compute_error` at the same ``(state, t)``.
        """
        return None

    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write ``J zeta = x_dot_d + K e`` (equality rows).

        Subclasses may override this with a fused version of the three ``compute_*`` calls
        (same numbers, fewer temporaries); they finish with :meth:`_set_sides`.
        """
        e = self.compute_error(state, t)
        A[:] = self.compute_jacobian(state, t)
        self._set_sides(e, self.compute_feedforward(state, t), lower, upper)

    def _set_sides(self, e: FloatArray, ff: Any, lower: FloatArray, upper: FloatArray) -> None:
        """``lower = upper = K e + ff`` (``ff`` None for no feed-forward); keeps ``e``.

        ``e`` must be a fresh array: it is kept as the task's last error (a step result refers
        to it).
        """
        self.last_error = e
        np.multiply(self.gain, e, out=lower)
        if ff is not None:
            lower += ff
        upper[:] = lower

    def _set_sides_floats(self, e: list[float], lower: FloatArray, upper: FloatArray,
                          ff: list[float] | None = None) -> None:
        """:meth:`_set_sides` for an error (and feed-forward) given as plain floats.

        ``lower = upper = K e (+ ff)`` entry by entry (the same products and sums as the
        array version), written with one assignment per side; the kept error is a new array.
        """
        gain = self.gain  # per-row gains are checked against dim at bind and update
        if isinstance(gain, np.ndarray):
            sides = [k * x for k, x in zip(gain.tolist(), e, strict=False)]
        else:
            sides = [gain * x for x in e]
        if ff is not None:
            sides = [x + f for x, f in zip(sides, ff, strict=False)]
        lower[:] = sides
        upper[:] = lower
        self.last_error = np.array(e)

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "gain":
            gain = as_gain(value, f"{self.name}.gain")
            if (isinstance(gain, np.ndarray) and self.model is not None
                    and gain.shape[0] != self.dim):
                raise InputError(
                    f"{self.name}.gain: expected {self.dim} gains, got {gain.shape[0]}")
            self.gain = gain
        else:
            super()._apply_update(key, value)
