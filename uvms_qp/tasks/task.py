"""Abstract task: a block of rows ``lower <= A zeta <= upper`` over the decision vector.

A task is built from keyword arguments (so a scenario loader can build it from a table), bound to a
model once (:meth:`Task.bind` checks frames, joints and dimensions and fixes the row count), then
evaluated every control tick on a :class:`~uvms_qp.model.State`. Each task class writes exactly one
evaluation:

* error-regulating tasks (:class:`ErrorTask`) implement :meth:`ErrorTask.error_rows`, returning
  the Jacobian ``J`` of the regulated quantity ``x`` over zeta (``x_dot = J zeta``), the error
  ``e = x_d - x`` and the feed-forward rate ``x_dot_d``; the base writes the closed-loop
  inverse-kinematics rows

      J zeta = x_dot_d + K e,

  the closed-loop form of Soylu et al. (2007), Eq. (16);
* other tasks (set-based rows, objectives) implement :meth:`Task.evaluate` ``-> (J, lower,
  upper)``.

The rest is defined once here: :meth:`Task.fill` writes the rows into caller-owned buffers (what
the controller calls every tick: ``A`` and the ``(2, dim)`` sides, in as few numpy calls as the
rows allow; a ``J`` that does not change is returned as the same read-only array every time and
written into a given buffer once), :meth:`Task.rows` returns fresh :class:`~uvms_qp.rows.Rows`,
and ``compute_error`` / ``compute_jacobian`` / ``compute_feedforward`` are views of
:meth:`ErrorTask.error_rows`.

Two run-time properties are common to every task:

* the activation ``a`` in [0, 1] (:attr:`Task.activation`): 1 is a task in the stack, 0 a task
  out of it (its rows are left free), and in between the controller blends the commands with
  and without the task, ``a zeta_with + (1 - a) zeta_without``, so inserting or removing a task
  does not step the command (the scalar case of the continuous activation of Mansard, Khatib
  and Kheddar, IEEE Trans. Robotics 2009). ``update(activation=...)`` ramps it to the new value
  over :attr:`Task.ramp` seconds with a smoothstep ``3 s^2 - 2 s^3`` (zero slope at both ends);
* the period check (:meth:`Task.check_period`): a task whose rows drive a quantity with a gain
  ``K`` [1/s] moves it, while the rows hold, as ``d_{k+1} = (1 - K dt) d_k``; it settles without
  overshoot only for ``K dt <= 1``. Set-based rows (a floor, a margin, a bound) that overshoot
  switch on and off every tick, so the controller refuses them at bind time, where dt is known.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar, final

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError, ShapeError
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


#: Default duration of an activation ramp [s] (:attr:`Task.ramp`).
DEFAULT_RAMP = 1.0


def as_activation(value: Any, name: str) -> float:
    """Validate an activation: a number in [0, 1]."""
    a = as_scalar(value, name, nonnegative=True)
    if a > 1.0:
        raise InputError(f"{name}: expected an activation in [0, 1], got {a:g}")
    return a


def check_barrier_gain(gain: float, dt: float, name: str, row: str) -> None:
    """Refuse a set-based row whose gain overshoots at period ``dt``: ``gain * dt > 1``.

    The row ``h_dot >= gain (h_min - h)`` (or its mirror) holds the distance to the bound
    ``d = h - h_min`` at ``d_{k+1} = (1 - gain dt) d_k`` while it binds: monotone for
    ``gain dt <= 1``, alternating around the bound (the row switching on and off every tick)
    above, divergent from 2.

    Raises:
        InputError: ``gain * dt > 1`` (the message gives the largest gain for this period).
    """
    if gain * dt > 1.0 + 1e-12:
        raise InputError(
            f"{name}: gain * dt = {gain:g} * {dt:g} = {gain * dt:.4g} > 1: the {row} would "
            f"overshoot its bound and switch on and off every tick (the distance to the bound "
            f"evolves as d_(k+1) = (1 - gain dt) d_k while the row binds); use gain <= "
            f"{1.0 / dt:.6g} [1/s] = 1 / dt")


def as_gain(value: Any, name: str = "gain") -> float | FloatArray:
    """Validate a gain [1/s]: a positive number or a list of positive numbers (one per row)."""
    if isinstance(value, list | tuple | np.ndarray):
        gains = as_vector(value, name)
        if np.any(gains < 0.0):
            raise InputError(f"{name}: expected non-negative gains, got {gains.tolist()}")
        return gains
    return as_scalar(value, name, nonnegative=True)


def _fits(side: Any, rows: int) -> bool:
    """True for a side of ``rows`` values or one value (a number, or an array of shape ())."""
    shape = getattr(side, "shape", None)
    if shape is not None:
        return bool(shape == (rows,) or shape == ())
    if isinstance(side, int | float):
        return True
    try:
        return len(side) == rows
    except TypeError:
        return False


def _shape_of(value: Any) -> str:
    """``(r, c)`` of an array, ``None``, or the type of anything else (for error messages)."""
    if value is None:
        return "None"
    shape = getattr(value, "shape", None)
    if shape is None:
        try:
            shape = np.shape(value)
        except (ValueError, TypeError):
            return type(value).__name__
    return str(tuple(shape))


class Task(ABC):
    """Base class of every task.

    Subclasses set the class attributes ``type_name`` (the scenario registry key), ``error_unit``
    (unit of the task error or objective, e.g. ``"m"``) and ``rate_unit`` (unit of the rows, e.g.
    ``"m/s"``), implement :meth:`_bind` (validation against the model; returns the row count) and
    :meth:`evaluate` (or :meth:`ErrorTask.error_rows`). The class units describe every
    configuration of the task; a task whose rows depend on its mode or axes narrows them on the
    instance in :meth:`_bind` (a position-only end-effector task reports ``"m/s"``), and the
    bound instance's units are the ones reported.

    Attributes:
        name: Unique name of the task inside a stack.
        weight: Positive weight of the task's rows relative to the other tasks of its level
            (weights only act within a level; levels are strict priorities).
        model: The bound model, or None before :meth:`bind`.
        dim: Number of rows (known after :meth:`bind`).
        last_error: The task error (error tasks) or objective value at the last evaluation
            [error_unit], a new array every evaluation; None before the first one. A task may
            set it to a sequence of floats (e.g. ``(w,)``): it becomes an array when read.
        row_weights: Per-row weights (dim,), task weight included; a new array whenever they
            change (so a consumer re-reads them only then).
        activation: The activation in [0, 1] at the last evaluation (see the module
            docstring); ``update(activation=...)`` ramps it.
        ramp: Duration of an activation ramp from 0 to 1 [s] (0: a step); a partial ramp takes
            the same fraction of it.
        owner: What evaluates the task every tick (the stack assembler of the last controller
            built on it), or None: a task serves one controller.
    """

    type_name: ClassVar[str] = "task"
    error_unit: str = ""
    rate_unit: str = ""

    def __init__(self, *, name: str | None = None, weight: float = 1.0,
                 activation: float = 1.0) -> None:
        self.name = check_task_name(name, self.type_name)
        self.weight = as_scalar(weight, f"{self.name}.weight", positive=True)
        self.model: Model | None = None
        self.owner: Any = None
        self._period: float | None = None  # the control period of the last set_period [s]
        self.dim = 0
        self.row_weights: FloatArray = np.zeros(0)
        self._error: Any = None  # last_error as set (a sequence becomes an array when read)
        self._written: tuple[Any, Any] = (None, None)  # (buffer, J) of the latest fill
        self.activation = as_activation(activation, f"{self.name}.activation")
        self.ramp = DEFAULT_RAMP
        self._initial_activation = self.activation
        # a ramp: (from, to, start time or None until the next evaluation starts it)
        self._ramping: tuple[float, float, float | None] | None = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """Keep the methods the base classes mark final (``fill``, ``rows``, ...) final.

        A task implements :meth:`evaluate` or :meth:`ErrorTask.error_rows`; everything built on
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

    @property
    def last_error(self) -> FloatArray | None:
        """See the class attributes."""
        e = self._error
        if e is not None and type(e) is not np.ndarray:
            e = self._error = np.array(e, dtype=np.float64)
        return e

    @last_error.setter
    def last_error(self, value: Any) -> None:
        self._error = value

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
        self.row_weights = np.full(self.dim, self.weight)
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

    # ----------------------------------------------------------------------------------- evaluate
    @abstractmethod
    def evaluate(self, state: State, t: float) -> tuple[FloatArray, Any, Any]:
        """The rows at ``(state, t)``: ``(J, lower, upper)``.

        ``J`` is ``(dim, nv)``; ``lower`` and ``upper`` are ``(dim,)`` arrays, lists or numbers
        (one value for every row), the same object for equality rows. The arrays may be
        read-only views of the state or of the task: copy them before modifying; rows that do
        not change are best returned as the same read-only array every time (:meth:`fill`
        writes them once). Sets :attr:`last_error`.
        """

    @final
    def fill(self, state: State, t: float, A: FloatArray, sides: FloatArray) -> None:
        """Write the rows at ``(state, t)`` into ``A`` (dim, nv) and ``sides`` (2, dim).

        ``sides`` holds the lower sides, then the upper ones. The buffers may hold stale values:
        every entry is written, except that ``A`` is not written again when it received this
        very ``J`` array (read-only) at the previous fill. Advances an activation ramp to ``t``.

        Raises:
            ShapeError: rows that do not fit ``A`` and ``sides`` (naming the task).
        """
        if self._ramping is not None:
            self.advance_activation(t)
        J, lo, hi = self.evaluate(state, t)
        try:  # (numpy would broadcast a row or a side of one value into every row)
            if J is not self._written[1] or A is not self._written[0]:
                if J.shape != A.shape:
                    raise ValueError
                A[...] = J
                self._written = (A, J)
            rows = A.shape[0]
            if hi is lo:  # equality rows: one write of both sides
                if not _fits(lo, rows):
                    raise ValueError
                sides[...] = lo
            else:
                if not (_fits(lo, rows) and _fits(hi, rows)):
                    raise ValueError
                sides[0] = lo
                sides[1] = hi
        except (ValueError, TypeError, AttributeError):
            raise self._shape_error("evaluate", A, J=J, lower=lo, upper=hi) from None

    def _shape_error(self, method: str, A: FloatArray, **returned: Any) -> ShapeError:
        """The error for rows of ``method`` that do not fit the task's (dim, nv) slot."""
        dim, nv = A.shape
        got = ", ".join(f"{k} {_shape_of(v)}" for k, v in returned.items())
        return ShapeError(f"task {self.name!r}: {type(self).__name__}.{method} returned {got}; "
                          f"expected J ({dim}, {nv}) and ({dim},) vectors (or numbers) for the "
                          f"other parts ({dim} rows, as bind returned)")

    @final
    def rows(self, state: State, t: float = 0.0) -> Rows:
        """Rows ``lower <= A zeta <= upper`` at ``state`` and time ``t`` [s] (fresh arrays)."""
        model = self._require_bound()
        A = np.empty((self.dim, model.nv))
        sides = np.empty((2, self.dim))
        self.fill(state, t, A, sides)
        return Rows(A, sides[0], sides[1], self.row_weights.copy(), self.name)

    def residual(self, state: State, zeta: Any, t: float = 0.0) -> float:
        """Norm of the row violation at ``zeta`` [rate_unit]: distance of ``A zeta`` to its band."""
        model = self._require_bound()
        x = as_vector(zeta, "zeta", model.nv)
        return float(np.linalg.norm(self.rows(state, t).violation(x)))

    def error_norm(self) -> float:
        """Norm of :attr:`last_error` [error_unit]; NaN before the first evaluation."""
        e = self.last_error
        return float("nan") if e is None else math.sqrt(e @ e)

    # ----------------------------------------------------------------------------------- run time
    def reset(self) -> None:
        """Forget run-time memory (activation pose, previous values); called by Controller.reset.

        The activation returns to its value at construction. Subclasses with memory of their
        own extend :meth:`_reset`.
        """
        self.activation = self._initial_activation
        self._ramping = None
        self._reset()

    def _reset(self) -> None:  # noqa: B027 - optional hook
        """Forget the subclass's run-time memory."""

    def check_period(self, dt: float) -> None:  # noqa: B027 - optional hook
        """Check the task against the control period ``dt`` [s] (see :meth:`set_period`).

        Tasks with set-based rows refuse a gain with ``gain * dt > 1``
        (:func:`check_barrier_gain`), error tasks one with ``gain * dt >= 2``
        (:meth:`ErrorTask.check_period`).

        Raises:
            InputError: the task's rows would not settle at this period.
        """

    @final
    def set_period(self, dt: float) -> None:
        """Check the task against the control period ``dt`` [s] and keep ``dt``.

        Every later :meth:`update` is checked against it too (called by the controller).

        Raises:
            InputError: the task's rows would not settle at this period.
        """
        self.check_period(dt)
        self._period = dt

    def advance_activation(self, t: float) -> float:
        """The activation at time ``t`` [s]: a pending ramp starts at the first call.

        A ramp up from 0 first forgets the task's run-time memory (:meth:`_reset`): a task
        entering the stack takes its activation pose then, not at the start of the run.

        ``a(t) = a_0 + (a_1 - a_0) (3 s^2 - 2 s^3)``, ``s = (t - t_0) / (ramp |a_1 - a_0|)``
        clipped to [0, 1]. Sets :attr:`activation`.
        """
        ramping = self._ramping
        if ramping is None:
            return self.activation
        a0, a1, start = ramping
        if start is None:
            start = t
            self._ramping = (a0, a1, t)
            if a0 == 0.0:  # a task entering the stack starts afresh (its activation pose now)
                self._reset()
        span = self.ramp * abs(a1 - a0)
        s = 1.0 if span <= 0.0 else min(max((t - start) / span, 0.0), 1.0)
        self.activation = a0 + (a1 - a0) * s * s * (3.0 - 2.0 * s)
        if s >= 1.0:
            self.activation = a1
            self._ramping = None
        return self.activation

    def update(self, **params: Any) -> None:
        """Change parameters at run time (validated), e.g. ``payload.update(force=20.0)``.

        Subclasses list the parameters they accept in :attr:`updatable`. All or nothing: a
        rejected value leaves the task as it was.

        Raises:
            InputError: an unknown parameter, an invalid value, or one with which the task's
                rows would not settle at the controller's period (:meth:`set_period`).
        """
        allowed = self.updatable()
        for key in params:
            if key not in allowed:
                raise InputError(
                    f"{self.name}.update: unknown parameter {key!r}; known: {', '.join(allowed)}"
                )
        before = dict(vars(self))
        try:
            for key, value in params.items():
                self._apply_update(key, value)
            if self._period is not None:  # e.g. a gain that would not settle at this period
                self.check_period(self._period)
        except Exception:
            vars(self).clear()  # all or nothing: the task as it was
            vars(self).update(before)
            raise

    def updatable(self) -> tuple[str, ...]:
        """Names of the parameters :meth:`update` accepts."""
        return ("weight", "activation", "ramp")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "activation":
            target = as_activation(value, f"{self.name}.activation")
            self._ramping = (self.activation, target, None)  # starts at the next evaluation
        elif key == "ramp":
            self.ramp = as_scalar(value, f"{self.name}.ramp", nonnegative=True)
        elif key == "weight":
            self.weight = as_scalar(value, f"{self.name}.weight", positive=True)
            if self.model is not None:
                self.row_weights = np.full(self.dim, self.weight)
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

    Rows: ``J zeta = x_dot_d + K e`` (Soylu et al. (2007), Eq. (16)), where ``J`` is the
    Jacobian of ``x`` over zeta and ``x_dot_d`` the feed-forward rate of the target. Subclasses
    implement :meth:`error_rows` only.

    Attributes:
        gain: Scalar gain or per-row gains [1/s].
    """

    def __init__(self, *, name: str | None = None, weight: float = 1.0,
                 gain: float | list[float] = 1.0, activation: float = 1.0) -> None:
        super().__init__(name=name, weight=weight, activation=activation)
        self.gain: float | FloatArray = as_gain(gain, f"{self.name}.gain")
        self._gains = np.zeros(0)  # one gain per row (set at bind)

    def bind(self, model: Model) -> Task:
        """Bind (see :meth:`Task.bind`) and check the gain length against the row count."""
        super().bind(model)
        if isinstance(self.gain, np.ndarray) and self.gain.shape[0] != self.dim:
            dim = self.dim
            self.model, self.dim = None, 0
            raise InputError(f"{self.name}.gain: expected {dim} gains (one per row), "
                             f"got {self.gain.shape[0]}")
        self._gains = np.broadcast_to(self.gain, (self.dim,)).copy()
        return self

    def check_period(self, dt: float) -> None:
        """Refuse a gain with ``gain * dt >= 2`` (the largest of per-row gains).

        The rows ``J zeta = x_dot_d + K e`` move the error by ``e_(k+1) = (1 - K dt) e_k`` per
        period (feed-forward exact, no bound active): monotone for ``K dt <= 1``, overshooting
        the target every period with a decaying alternation between 1 and 2, and never settling
        from 2 (the command reversing every tick, growing until the box clips it). Gains above
        ``1 / dt`` are allowed (closed-form schemes of the papers are compared there) but
        overshoot.

        Raises:
            InputError: ``gain * dt >= 2`` (the message gives the gains for this period).
        """
        gain = float(np.max(self.gain))
        if gain * dt >= 2.0 * (1.0 - 1e-12):
            raise InputError(
                f"{self.name}.gain: gain * dt = {gain:g} * {dt:g} = {gain * dt:.4g} >= 2: the "
                "error would never settle (it evolves as e_(k+1) = (1 - gain dt) e_k, reversing "
                f"every period); use gain < {2.0 / dt:.6g} [1/s] = 2 / dt, and gain <= "
                f"{1.0 / dt:.6g} = 1 / dt to reach the target without overshoot")

    @abstractmethod
    def error_rows(self, state: State, t: float) -> tuple[FloatArray, FloatArray,
                                                          FloatArray | None]:
        """``(J, e, ff)`` at ``(state, t)``.

        ``J`` (dim, nv): Jacobian of the regulated quantity, ``x_dot = J zeta`` (may be a
        read-only view of the state's arrays); ``e`` (dim,): the error ``x_d - x``
        [error_unit], a new array (it becomes :attr:`last_error`); ``ff`` (dim,): the
        feed-forward rate ``x_dot_d`` [rate_unit], or None for zero.
        """

    @final  # type: ignore[misc]  # the error tasks' one fill, final below ErrorTask
    def fill(self, state: State, t: float, A: FloatArray, sides: FloatArray) -> None:
        """Write ``J zeta = x_dot_d + K e`` (equality rows) into ``A`` and ``sides`` (2, dim).

        Raises:
            ShapeError: ``J``, ``e`` or ``ff`` that do not fit the task's rows (naming it).
        """
        if self._ramping is not None:
            self.advance_activation(t)
        J, e, ff = self.error_rows(state, t)
        try:  # (numpy would broadcast a row or an error of one value into every row)
            shape = A.shape
            if J is not self._written[1] or A is not self._written[0]:
                if J.shape != shape:
                    raise ValueError
                A[...] = J
                self._written = (A, J)
            if e.shape != shape[:1] or (ff is not None and ff.shape != shape[:1]):
                raise ValueError
            side = e * self._gains
            if ff is not None:
                side += ff
            sides[...] = side  # both sides at once
        except (ValueError, TypeError, AttributeError):
            raise self._shape_error("error_rows", A, J=J, e=e, ff=ff) from None
        self._error = e

    @final
    def evaluate(self, state: State, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(J, lower, upper)`` with ``lower = upper = x_dot_d + K e`` (fresh arrays)."""
        model = self._require_bound()
        A = np.empty((self.dim, model.nv))
        sides = np.empty((2, self.dim))
        self.fill(state, t, A, sides)
        return A, sides[0], sides[1]

    @final
    def compute_error(self, state: State, t: float) -> FloatArray:
        """The error ``e = x_d - x`` (dim,) [error_unit] of :meth:`error_rows`."""
        return self.error_rows(state, t)[1]

    @final
    def compute_jacobian(self, state: State, t: float) -> FloatArray:
        """The Jacobian ``J`` (dim, nv) of :meth:`error_rows`."""
        return self.error_rows(state, t)[0]

    @final
    def compute_feedforward(self, state: State, t: float) -> FloatArray | None:
        """The feed-forward rate ``x_dot_d`` (dim,) [rate_unit] of :meth:`error_rows`, or None."""
        return self.error_rows(state, t)[2]

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
            if self.model is not None:
                self._gains = np.broadcast_to(gain, (self.dim,)).copy()
        else:
            super()._apply_update(key, value)
