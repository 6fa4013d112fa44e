"""Error-regulating tasks: ``J zeta = x_dot_d + K e`` from ``error_rows`` (:class:`ErrorTask`)."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, Any, final

import numpy as np

from .._validation import FloatArray
from ..errors import InputError
from ._checks import as_gain
from .slot import TaskSlot
from .task import Task

if TYPE_CHECKING:  # pragma: no cover
    from ..model import State


class ErrorTask(Task):
    """A task regulating an error ``e = x_d - x`` with gain ``K`` [1/s].

    Rows: ``J zeta = x_dot_d + K e`` (Soylu et al. (2007), Eq. (16)), where ``J`` is the
    Jacobian of ``x`` over zeta and ``x_dot_d`` the feed-forward rate of the target. Subclasses
    implement :meth:`error_rows` only.

    Attributes:
        gain: Scalar gain or per-row gains [1/s].
    """

    def __init__(self, *, name: str | None = None, weight: float = 1.0,
                 gain: float | list[float] = 1.0) -> None:
        super().__init__(name=name, weight=weight)
        self.gain: float | FloatArray = self._check("gain", gain)
        self._gains = np.zeros(0)  # one gain per row (set at bind)

    def _check_dim(self, dim: int) -> None:
        """Per-row gains: one per row."""
        if isinstance(self.gain, np.ndarray) and self.gain.shape[0] != dim:
            raise InputError(f"{self.name}.gain: expected {dim} gains (one per row), "
                             f"got {self.gain.shape[0]}")

    def _derive(self) -> None:
        super()._derive()
        self._gains = np.broadcast_to(self.gain, (self.dim,)).copy()

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
    def error_rows(self, state: State, t: float, slot: TaskSlot
                   ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """``(J, e, ff)`` at ``(state, t)`` with the task's memory ``slot``.

        ``J`` (dim, nv): Jacobian of the regulated quantity, ``x_dot = J zeta`` (may be a
        read-only view of the state's arrays); ``e`` (dim,): the error ``x_d - x``
        [error_unit], a new array (it becomes ``slot.error``); ``ff`` (dim,): the
        feed-forward rate ``x_dot_d`` [rate_unit], or None for zero.
        """

    @final  # type: ignore[misc]  # the error tasks' one fill, final below ErrorTask
    def fill(self, state: State, t: float, A: FloatArray, sides: FloatArray,
             slot: TaskSlot) -> None:
        """Write ``J zeta = x_dot_d + K e`` (equality rows) into ``A`` and ``sides`` (2, dim).

        Raises:
            ShapeError: ``J``, ``e`` or ``ff`` that do not fit the task's rows (naming it).
        """
        J, e, ff = self.error_rows(state, t, slot)
        try:  # (numpy would broadcast a row or an error of one value into every row)
            shape = A.shape
            written = slot.written
            if J is not written[1] or A is not written[0]:
                if J.shape != shape:
                    raise ValueError
                A[...] = J
                slot.written = (A, J)
            if e.shape != shape[:1] or (ff is not None and ff.shape != shape[:1]):
                raise ValueError
            side = e * self._gains
            if ff is not None:
                side += ff
            sides[...] = side  # both sides at once
        except (ValueError, TypeError, AttributeError):
            raise self._shape_error("error_rows", A, J=J, e=e, ff=ff) from None
        slot.error = e

    @final
    def evaluate(self, state: State, t: float, slot: TaskSlot
                 ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(J, lower, upper)`` with ``lower = upper = x_dot_d + K e`` (fresh arrays)."""
        model = self._require_bound()
        A = np.empty((self.dim, model.nv))
        sides = np.empty((2, self.dim))
        self.fill(state, t, A, sides, slot)
        return A, sides[0], sides[1]

    @final
    def compute_error(self, state: State, t: float = 0.0,
                      slot: TaskSlot | None = None) -> FloatArray:
        """The error ``e = x_d - x`` (dim,) [error_unit] of :meth:`error_rows`.

        ``slot``: the memory to evaluate with (default a new one: a held target is the one of
        ``state``).
        """
        return self.error_rows(state, t, self.new_slot() if slot is None else slot)[1]

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain")

    def _check(self, key: str, value: Any) -> Any:
        if key == "gain":
            gain = as_gain(value, f"{self.name}.gain")
            if isinstance(gain, np.ndarray) and self.model is not None \
                    and gain.shape[0] != self.dim:
                raise InputError(f"{self.name}.gain: expected {self.dim} gains, got "
                                 f"{gain.shape[0]}")
            return gain
        return super()._check(key, value)
