"""Manipulability of the arm (Yoshikawa's measure): an objective, a floor, or a shaped objective.

One class per kind of rows: ascend, floor, shaping (blended with station keeping).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .._validation import FloatArray, as_scalar
from ..analytic.manipulability import shaping_function
from ..errors import InputError
from ._checks import check_barrier_gain, check_frame_name
from ._common import TWIST_AXES, check_choice, check_frame, parse_axes
from .manipulability_measure import default_axes, measure
from .manipulability_measure import default_rows as default_rows  # re-exported
from .manipulability_measure import manipulability_and_gradient as manipulability_and_gradient
from .slot import TaskSlot
from .task import Task

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class _Measured(TaskSlot):
    """The measure ``(w, grad w)`` of the state last evaluated (read by a linked task too)."""

    __slots__ = ("serial", "value")

    def clear(self) -> None:
        super().clear()
        self.serial = -1
        self.value: tuple[float, list[float]] = (math.nan, [])


class ManipulabilityTask(Task):
    r"""Keep the arm dexterous using Yoshikawa's manipulability ``w`` of the arm Jacobian.

    ``w = sqrt(det(J_S J_S^T))`` of the selected rows ``S`` of the arm's Jacobian of ``frame`` in
    the arm-base axes (joint columns only; Soylu et al. (2007), Eq. (18); in that paper
    the measure of the collective Jacobian ``[J_p; J_s]`` reduces to this one since ``J_s``
    selects the vehicle coordinates). ``grad w`` (Eq. (19)) is exact (see
    :func:`~uvms_qp.tasks.manipulability_and_gradient`). ``ManipulabilityTask(mode=...)`` builds
    the class of the mode (the scenario key ``mode``): ``"ascend"``
    (:class:`ManipulabilityAscendTask`), ``"floor"`` (:class:`ManipulabilityFloorTask`, the
    default) or ``"shaping"`` (:class:`ManipulabilityShapingTask`). Objective value: ``w``.

    Args:
        mode: ``"ascend"``, ``"floor"`` or ``"shaping"`` (selects the class).
        frame: Frame whose arm Jacobian is measured (default ``"tool"``).
        axes: Rows of the twist used, from ``x, y, z, rx, ry, rz`` (default ``x, y, z``; planar
            models ``x, y``).
        gain: ``lambda`` [rad/s per unit of w] (ascend, shaping) or the barrier gain [1/s]
            (floor).
        weight: Weight within the level.
        name: Task name (default ``"manipulability"``).
    """

    type_name = "manipulability"
    error_unit = "m^k"
    rate_unit = "rad/s"
    mode: ClassVar[str] = ""
    Slot = _Measured

    def __new__(cls, *args: Any, mode: str | None = None, **kwargs: Any) -> Any:
        """The class of ``mode`` when built as ``ManipulabilityTask(mode=...)``."""
        if cls is ManipulabilityTask:
            cls = cls.for_mode(mode, kwargs.get("name"))
        return super().__new__(cls, *args, mode=mode, **kwargs)

    @classmethod
    def for_mode(cls, mode: str | None, name: str | None = None) -> type[ManipulabilityTask]:
        """The class of ``mode`` (None: ``"floor"``).

        Raises:
            InputError: an unknown mode (the known ones are listed).
        """
        label = f"{name or cls.type_name}.mode"
        return MODES[check_choice("floor" if mode is None else mode, tuple(MODES), label)]

    def __init__(self, *, mode: str | None = None, frame: str = "tool",
                 axes: list[str] | None = None, gain: float = 1.0, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(name=name, weight=weight)
        if mode is not None:
            check_choice(mode, (self.mode,), f"{self.name}.mode")
        self.frame = check_frame_name(frame, f"{self.name}.frame")
        self._axes_arg = None if axes is None else parse_axes(axes, TWIST_AXES,
                                                              f"{self.name}.axes")
        self.gain = self._check("gain", gain)
        self.axes: list[str] = []
        self._rows: list[int] | None = None
        self._select = np.zeros((0, 0))

    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        if model.n_joints == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        axes = self._axes_arg if self._axes_arg is not None else default_axes(model)
        self.axes = list(axes)
        rows = [TWIST_AXES.index(a) for a in axes]
        self._rows = None if rows == [0, 1, 2] else rows
        k = sum(a in ("x", "y", "z") for a in axes)  # linear rows: [m] each, angular: [1]
        self.error_unit = "1" if k == 0 else "m" if k == 1 else f"m^{k}"
        n = model.n_joints
        self._select = np.zeros((n, model.nv))  # rows qdot = ... over the joint rates
        self._select[np.arange(n), model.n_vehicle + np.arange(n)] = 1.0
        self._select.setflags(write=False)
        return n

    def compute_value(self, state: State) -> tuple[float, FloatArray]:
        """``(w, grad w)`` at ``state`` (gradient over the arm joints, (n_joints,))."""
        w, grad = self._value(state, None)
        return w, np.array(grad)

    def _value(self, state: State, slot: TaskSlot | None) -> tuple[float, list[float]]:
        """``(w, grad w)`` in plain floats, computed once per state in a slot.

        A task linked to this one (a blended :class:`StationKeepingTask`) reads the same
        numbers in the same tick.
        """
        if slot is None:
            return measure(state.arm_jacobian(self.frame), self._rows)
        if slot.serial != state.serial:  # type: ignore[attr-defined]
            slot.value = measure(state.arm_jacobian(self.frame), self._rows)  # type: ignore[attr-defined]
            slot.serial = state.serial  # type: ignore[attr-defined]
        return slot.value  # type: ignore[attr-defined, no-any-return]

    def updatable(self) -> tuple[str, ...]:  # noqa: D102
        return (*super().updatable(), "gain")

    def _check(self, key: str, value: Any) -> Any:
        if key == "gain":
            return as_scalar(value, f"{self.name}.gain", positive=True)
        return super()._check(key, value)


class ManipulabilityAscendTask(ManipulabilityTask):
    r"""Rows ``qdot = lambda grad w`` over the arm joint rates (n_joints rows, [rad/s]).

    The gradient-projection objective of Soylu et al. (2007), Eq. (4) with ``h = w`` (in a
    hierarchy the level below the tracking task reproduces Eq. (4)).
    """

    mode = "ascend"

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The rows ``qdot = lambda grad w``."""
        w, g = self._value(state, slot)
        slot.error = (w,)
        scale = self.gain
        sides = [scale * x for x in g]
        return self._select, sides, sides


class ManipulabilityFloorTask(ManipulabilityTask):
    r"""One inequality row ``grad w . qdot >= gain (minimum - w)`` ([w]/s).

    The first-order barrier that keeps ``w >= minimum``: with ``gain = 1/dt`` it is exactly
    ``w + dt grad w . qdot >= minimum``; a smaller gain approaches the floor gradually. Below
    the floor, the demand is capped at ``gain |grad w|^2 / w``: near a maximum of ``w`` (a floor
    the arm cannot reach) the gradient vanishes and the uncapped row would ask for
    ``gain (minimum - w) / |grad w|`` rad/s, which the box clips and which crosses the maximum
    in one period, so that the command would bang between its bounds. With the cap the joints
    move at most ``gain dt |grad w| / w <= |grad w| / w`` rad per period along the gradient,
    about the distance to the maximum (where ``w`` has a curvature of about ``w`` per rad^2,
    exactly so for a product of sines such as a planar 2R arm's ``l1 l2 |sin q2|``): ``w``
    rises to its maximum without crossing it (the damping criterion of
    :mod:`uvms_qp.hqp.damping` for a single row, in relative units of ``w``).

    Args:
        minimum: Floor value of ``w`` (required).
        gain: The barrier gain [1/s] (``gain * dt <= 1``).
        mode, frame, axes, weight, name: See :class:`ManipulabilityTask`.
    """

    mode = "floor"

    def __init__(self, *, mode: str | None = None, frame: str = "tool",
                 axes: list[str] | None = None, gain: float = 1.0,
                 minimum: float | None = None, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(mode=mode, frame=frame, axes=axes, gain=gain, weight=weight, name=name)
        if minimum is None:
            raise InputError(f"{self.name}.minimum: required in mode 'floor'")
        self.minimum = self._check("minimum", minimum)
        self._zeros: list[float] = []  # vehicle columns of the row

    @property
    def equality_rows(self) -> bool:
        """False: an inequality row."""
        return False

    def check_period(self, dt: float) -> None:
        """Refuse ``gain * dt > 1`` (see :func:`~uvms_qp.tasks._checks.check_barrier_gain`)."""
        check_barrier_gain(self.gain, dt, f"{self.name}.gain", "floor row")

    def _bind(self, model: Model) -> int:
        super()._bind(model)
        self.rate_unit = f"{self.error_unit}/s"
        self._zeros = [0.0] * model.n_vehicle
        return 1

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The floor row (see the class docstring)."""
        w, g = self._value(state, slot)
        slot.error = (w,)
        short = self.minimum - w
        if short > 0.0 and w > 0.0:
            # near a maximum of w (an unreachable floor) the gradient vanishes: ask at most
            # what a step of |grad w| / w [rad] along it gives (class docstring)
            reach = math.fsum(v * v for v in g) / w
            if reach < short:
                short = reach
        return np.array([self._zeros + g]), self.gain * short, np.inf

    def updatable(self) -> tuple[str, ...]:  # noqa: D102
        return (*super().updatable(), "minimum")

    def _check(self, key: str, value: Any) -> Any:
        if key == "minimum":
            return as_scalar(value, f"{self.name}.minimum", nonnegative=True)
        return super()._check(key, value)


class _Shaped(_Measured):
    """The shaping task's previous ``(t, w)``, its rate estimate and shaping factor."""

    __slots__ = ("previous", "rate", "shaping")

    def clear(self) -> None:
        super().clear()
        self.previous: tuple[float, float] | None = None
        self.rate = 0.0
        self.shaping = 0.0


class ManipulabilityShapingTask(ManipulabilityTask):
    r"""Rows ``qdot = k(w) (1 - sign(w_dot)) / 2 lambda grad w`` (Soylu et al. (2007), Eq. (21)).

    :func:`~uvms_qp.analytic.shaping_function` ``k`` with the threshold ``rho_bar``, and the
    sign switch that only intervenes while ``w`` is not increasing (``sign(w_dot) = -1`` for
    ``w_dot <= 0``); ``w_dot`` is the finite difference of ``w`` between evaluations (0 at the
    first one, kept in the slot). Place it in the same level as a
    ``StationKeepingTask(blend=<this task's name>)``, whose demand is then scaled by ``1 - k``:
    the level asks ``[vehicle: (1 - k) K_s e_s; arm: k s lambda grad w]``, the secondary term of
    Eq. (21).

    Args:
        threshold: ``rho_bar`` of the shaping function (required).
        gain: ``lambda`` [rad/s per unit of w].
        mode, frame, axes, weight, name: See :class:`ManipulabilityTask`.
    """

    mode = "shaping"
    Slot = _Shaped

    def __init__(self, *, mode: str | None = None, frame: str = "tool",
                 axes: list[str] | None = None, gain: float = 1.0,
                 threshold: float | None = None, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(mode=mode, frame=frame, axes=axes, gain=gain, weight=weight, name=name)
        if threshold is None:
            raise InputError(f"{self.name}.threshold: required in mode 'shaping'")
        self.threshold = self._check("threshold", threshold)

    def shaping_factor(self, state: State, slot: TaskSlot | None = None) -> float:
        """``k(w)`` of :func:`~uvms_qp.analytic.shaping_function` at ``state``."""
        return float(shaping_function(self._value(state, slot)[0], self.threshold))

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The shaped gradient rows (``w_dot`` from the slot's previous value)."""
        w, g = self._value(state, slot)
        slot.error = (w,)
        memory: _Shaped = slot  # type: ignore[assignment]
        previous = memory.previous
        if previous is not None and t > previous[0]:
            memory.rate = (w - previous[1]) / (t - previous[0])
        memory.previous = (t, w)
        switch = 0.0 if memory.rate > 0.0 else 1.0
        memory.shaping = shaping_function(w, self.threshold)
        scale = self.gain * (memory.shaping * switch)
        sides = [scale * x for x in g]
        return self._select, sides, sides

    def updatable(self) -> tuple[str, ...]:  # noqa: D102
        return (*super().updatable(), "threshold")

    def _check(self, key: str, value: Any) -> Any:
        if key == "threshold":
            return as_scalar(value, f"{self.name}.threshold", positive=True)
        return super()._check(key, value)


#: The class of each ``mode`` of :class:`ManipulabilityTask`.
MODES: dict[str, type[ManipulabilityTask]] = {cls.mode: cls for cls in (
    ManipulabilityAscendTask, ManipulabilityFloorTask, ManipulabilityShapingTask)}
