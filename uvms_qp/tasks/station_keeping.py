"""Station keeping: hold the vehicle pose (any subset of its coordinates)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_vector
from ..errors import InputError
from ..model.selection import compact_index
from ._common import (
    _TWO_PI,
    ANGLE_AXES,
    EtaRows,
    eta_axes,
    parse_axes,
    pose_units,
    vehicle_pose_jacobian,
    wrap_angles_in_place,
)
from .task import ErrorTask

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_ALL = ("x", "y", "z", "phi", "theta", "psi")
_ACTUATOR = {"phi": "p", "theta": "q"}


class StationKeepingTask(ErrorTask):
    r"""Hold the vehicle pose ``eta`` on selected coordinates at a set point.

    Rows ``J_eta,S zeta = K (eta_d - eta)_S`` over the selected coordinates ``S`` (angles wrapped to
    ``[-pi, pi)``), with ``J_eta`` the vehicle-pose Jacobian (``eta_dot = J_eta zeta``, NED, Z-Y-X
    Euler angles). Error [m, rad], rows [m/s, rad/s].

    The set point is ``target`` (values for the selected coordinates, in order), or, when None:
    ``hold="activation"`` (default) the pose at the first evaluation after construction or
    :meth:`reset`; ``hold="current"`` the pose at every tick, so the rows ask for zero vehicle
    motion, as in ``000_7b5f597fe4e36aa4.txt``, Section 3 ("the current URV position value is
    entered as the desired position values for the next step").

    Args:
        axes: Coordinates to hold, from ``x, y, z, phi, theta, psi`` (planar ``x, y, psi``);
            default ``x, y, z, psi`` (planar ``x, y, psi``). Roll/pitch only if actuated.
        target: Set point for the selected coordinates [m, rad], or None (see ``hold``).
        hold: ``"activation"`` or ``"current"`` when no target is given.
        blend: Name of a :class:`~uvms_qp.tasks.ManipulabilityTask` in mode ``"shaping"`` of the
            same stack: the demand is scaled by ``1 - k(w)`` (``000_7b5f597fe4e36aa4.txt,
            Eq. (21)``: station keeping gives way to singularity avoidance as ``w`` drops).
        gain: Gain K [1/s], scalar or per coordinate.
        weight: Weight within the level.
        name: Task name (default ``"station_keeping"``).
    """

    type_name = "station_keeping"
    error_unit = "m, rad"
    rate_unit = "m/s, rad/s"

    def __init__(
        self,
        *,
        axes: list[str] | None = None,
        target: list[float] | None = None,
        hold: Literal["activation", "current"] = "activation",
        blend: str | None = None,
        gain: float | list[float] = 1.0,
        weight: float = 1.0,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self._axes_arg = None if axes is None else parse_axes(axes, _ALL, f"{self.name}.axes")
        if hold not in ("activation", "current"):
            raise InputError(f"{self.name}.hold: expected 'activation' or 'current', got {hold!r}")
        self.hold = hold
        if blend is not None and (not isinstance(blend, str) or not blend):
            raise InputError(f"{self.name}.blend: expected a task name, got {blend!r}")
        self.blend = blend
        self._blend_task: Any = None
        self._target_arg = None if target is None else as_vector(target, f"{self.name}.target")
        self.axes: list[str] = []
        self._idx: Any = np.zeros(0, dtype=int)
        self._angle_pos: list[int] = []
        self._eta_pos: list[int] = []
        self._rows: EtaRows | None = None
        self._target: FloatArray | None = None
        self._target_list: list[float] | None = None

    def _bind(self, model: Model) -> int:
        known = eta_axes(model)
        if not known:
            raise InputError(f"{self.name}: model {model.name!r} has a fixed base; station keeping "
                             "needs a vehicle")
        if self._axes_arg is None:
            axes = ["x", "y", "psi"] if model.vehicle_kind == "planar" else ["x", "y", "z", "psi"]
        else:
            axes = self._axes_arg
        for a in axes:
            if a not in known:
                raise InputError(f"{self.name}.axes: {a!r} is not a coordinate of the "
                                 f"{model.vehicle_kind} vehicle; known: {', '.join(known)}")
            if a in _ACTUATOR and _ACTUATOR[a] not in model.actuated:
                raise InputError(f"{self.name}.axes: {a!r} is passive on model {model.name!r} "
                                 f"(actuated: {', '.join(model.actuated)})")
        if self._target_arg is not None and self._target_arg.shape[0] != len(axes):
            raise InputError(f"{self.name}.target: expected {len(axes)} values for axes "
                             f"{axes}, got {self._target_arg.shape[0]}")
        self.axes = list(axes)
        self._eta_pos = [known.index(a) for a in axes]
        self._idx = compact_index(self._eta_pos)
        self._angle_pos = [i for i, a in enumerate(axes) if a in ANGLE_AXES]
        self._rows = EtaRows(model, self._eta_pos)
        self._hold(self._target_arg)
        self.error_unit, self.rate_unit = pose_units(axes)
        return len(axes)

    def _hold(self, value: FloatArray | None) -> None:
        """Set the held values (a copy, also kept as plain floats for :meth:`fill`), or None."""
        self._target = None if value is None else value.copy()
        self._target_list = None if value is None else value.tolist()

    def link(self, tasks: dict[str, Any]) -> None:
        """Find the manipulability task named by ``blend``."""
        if self.blend is None:
            return
        other = tasks.get(self.blend)
        if other is None:
            raise InputError(f"{self.name}.blend: no task named {self.blend!r}; known tasks: "
                             f"{', '.join(tasks)}")
        if getattr(other, "type_name", "") != "manipulability" or other.mode != "shaping":
            raise InputError(f"{self.name}.blend: {self.blend!r} is not a manipulability task "
                             "in mode 'shaping'")
        self._blend_task = other

    def reset(self) -> None:
        """Forget the activation pose (a new one is taken at the next evaluation)."""
        self._hold(self._target_arg)

    def set_target(self, target: Any) -> None:
        """Set the held values for the selected coordinates [m, rad]."""
        value = as_vector(target, f"{self.name}.target", len(self.axes) or None)
        self._target_arg = value
        self._hold(value)

    @property
    def held_pose(self) -> FloatArray | None:
        """The current set point on the selected coordinates, or None before activation."""
        return self._target

    def compute_error(self, state: State, t: float) -> FloatArray:
        """``(eta_d - eta)`` on the selected coordinates, angles wrapped [m, rad]."""
        eta = state.eta[self._idx]
        if self._target is None:
            if self.hold == "current":
                return np.zeros(len(self.axes))
            self._hold(eta)
        e = self._target - eta
        wrap_angles_in_place(e, self._angle_pos)
        if self._blend_task is not None:
            e *= 1.0 - self._blend_task.shaping_factor(state)
        return e

    def compute_jacobian(self, state: State, t: float) -> FloatArray:
        """Rows of the vehicle-pose Jacobian ``J_eta`` for the selected coordinates."""
        return vehicle_pose_jacobian(state)[self._idx]

    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write ``J_eta,S zeta = K (eta_d - eta)_S`` (no feed-forward).

        The operations of :meth:`compute_error` per coordinate in plain floats (one to six
        values); the rows are written from the state's plain-float ``J_eta`` entries.
        """
        if not self._fused:
            super().fill(state, t, A, lower, upper)
            return
        eta = state.eta_floats()
        target = self._target_list
        if target is None and self.hold == "activation":
            self._hold(np.array([eta[i] for i in self._eta_pos]))
            target = self._target_list
        if target is None:  # hold="current": the set point is the pose itself
            e = [0.0] * len(self._eta_pos)
        else:
            e = [x - eta[i] for x, i in zip(target, self._eta_pos, strict=True)]
            for i in self._angle_pos:
                e[i] = (e[i] + math.pi) % _TWO_PI - math.pi
            if self._blend_task is not None:
                scale = 1.0 - self._blend_task.shaping_factor(state)
                e = [x * scale for x in e]
        self._rows.write(state, A)  # type: ignore[union-attr]
        self._set_sides_floats(e, lower, upper)

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "target")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "target":
            self.set_target(value)
        else:
            super()._apply_update(key, value)
