"""Vehicle attitude: drive roll and/or pitch toward a set point (level by default)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ..model.selection import compact_index
from ._common import (
    _TWO_PI,
    EtaRows,
    eta_axes,
    parse_axes,
    vehicle_pose_jacobian,
    wrap_angles_in_place,
)
from .task import ErrorTask

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_ACTUATOR = {"phi": "p", "theta": "q"}


class VehicleAttitudeTask(ErrorTask):
    r"""Drive the vehicle roll ``phi`` and/or pitch ``theta`` toward ``(roll, pitch)`` [rad].

    Rows ``J_eta,S zeta = K wrap(eta_d - eta)_S`` on ``S`` within ``{phi, theta}`` (rows of the
    vehicle-pose Jacobian, Euler-angle rates). Only for vehicles that actuate the matching body
    rates (``p`` for roll, ``q`` for pitch): binding to a vehicle with passive roll/pitch is an
    error (those angles are then governed by the vehicle's restoring moments, see
    ``003_229789978cc4b235.txt``, and kept small through the payload-moment task instead).

    Args:
        axes: ``["phi", "theta"]`` (default) or one of them.
        roll: Roll set point [rad] (default 0, level).
        pitch: Pitch set point [rad] (default 0, level).
        gain: Gain K [1/s], scalar or per axis.
        weight: Weight within the level.
        name: Task name (default ``"vehicle_attitude"``).
    """

    type_name = "vehicle_attitude"
    error_unit = "rad"
    rate_unit = "rad/s"

    def __init__(
        self,
        *,
        axes: list[str] | None = None,
        roll: float = 0.0,
        pitch: float = 0.0,
        gain: float | list[float] = 1.0,
        weight: float = 1.0,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self.axes = parse_axes(axes if axes is not None else ["phi", "theta"], ("phi", "theta"),
                               f"{self.name}.axes")
        self.roll = as_scalar(roll, f"{self.name}.roll")
        self.pitch = as_scalar(pitch, f"{self.name}.pitch")
        self._idx: Any = np.zeros(0, dtype=int)
        self._all: list[int] = []
        self._target = np.zeros(0)
        self._eta_pos: list[int] = []
        self._pairs: list[tuple[float, int]] = []
        self._rows: EtaRows | None = None

    def _bind(self, model: Model) -> int:
        known = eta_axes(model)
        if model.vehicle_kind != "spatial":
            raise InputError(f"{self.name}: model {model.name!r} has no roll/pitch "
                             f"({model.vehicle_kind} vehicle)")
        for a in self.axes:
            if _ACTUATOR[a] not in model.actuated:
                raise InputError(f"{self.name}: model {model.name!r} does not actuate "
                                 f"{_ACTUATOR[a]!r} (actuated: {', '.join(model.actuated)}), so "
                                 f"{a} cannot be a task")
        self._idx = compact_index([known.index(a) for a in self.axes])
        self._all = list(range(len(self.axes)))
        self._target = np.array([self.roll if a == "phi" else self.pitch for a in self.axes])
        self._eta_pos = [known.index(a) for a in self.axes]
        self._rows = EtaRows(model, self._eta_pos)
        self._set_pairs()
        return len(self.axes)

    def _set_pairs(self) -> None:
        """``(set point [rad], index into eta)`` per row, for the plain-float error."""
        self._pairs = list(zip(self._target.tolist(), self._eta_pos, strict=True))

    def compute_error(self, state: State, t: float) -> FloatArray:
        """``wrap(angle_d - angle)`` on the selected axes [rad]."""
        e = self._target - state.eta[self._idx]
        wrap_angles_in_place(e, self._all)
        return e

    def compute_jacobian(self, state: State, t: float) -> FloatArray:
        """Rows of the vehicle-pose Jacobian for roll/pitch."""
        return vehicle_pose_jacobian(state)[self._idx]

    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write ``J_eta,S zeta = K wrap(eta_d - eta)_S``.

        The error in plain floats (the operations of :meth:`compute_error` and
        :func:`~uvms_qp.tasks._common.wrap_angle` per angle); the rows are written from the
        state's plain-float ``J_eta`` entries.
        """
        if not self._fused:
            super().fill(state, t, A, lower, upper)
            return
        eta = state.eta_floats()
        self._rows.write(state, A)  # type: ignore[union-attr]
        self._set_sides_floats([(a - eta[i] + math.pi) % _TWO_PI - math.pi
                                for a, i in self._pairs], lower, upper)

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "roll", "pitch")

    def _apply_update(self, key: str, value: Any) -> None:
        if key in ("roll", "pitch"):
            setattr(self, key, as_scalar(value, f"{self.name}.{key}"))
            if self.model is not None:
                self._target = np.array([self.roll if a == "phi" else self.pitch
                                         for a in self.axes])
                self._set_pairs()
        else:
            super()._apply_update(key, value)
