"""Vehicle attitude: drive roll and/or pitch toward a set point (level by default)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ..model.selection import compact_index
from ._common import parse_axes, wrap_angle
from .error_task import ErrorTask
from .slot import TaskSlot

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_ACTUATOR = {"phi": "p", "theta": "q"}


class VehicleAttitudeTask(ErrorTask):
    r"""Drive the vehicle roll ``phi`` and/or pitch ``theta`` toward ``(roll, pitch)`` [rad].

    Rows ``J_eta,S zeta = K wrap(eta_d - eta)_S`` on ``S`` within ``{phi, theta}`` (rows of the
    vehicle-pose Jacobian, Euler-angle rates). Only for vehicles that actuate the matching body
    rates (``p`` for roll, ``q`` for pitch): binding to a vehicle with passive roll/pitch is an
    error (those angles are then governed by the vehicle's restoring moments, see
    Wang et al. (2017), and are kept small through the payload-moment task instead).

    Args:
        axes: ``["phi", "theta"]`` (default) or one of them.
        roll: Roll set point [rad] (default 0, level).
        pitch: Pitch set point [rad] (default 0, level); both change with
            :meth:`set_target`.
        gain: Gain K [1/s], scalar or per axis.
        weight: Weight within the level.
        name: Task name (default ``"vehicle_attitude"``).
    """

    type_name = "vehicle_attitude"
    error_unit = "rad"
    rate_unit = "rad/s"

    def __init__(self, *, axes: list[str] | None = None, roll: float = 0.0, pitch: float = 0.0,
                 gain: float | list[float] = 1.0, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self.axes = parse_axes(axes if axes is not None else ["phi", "theta"], ("phi", "theta"),
                               f"{self.name}.axes")
        self.roll = self._check("roll", roll)
        self.pitch = self._check("pitch", pitch)
        self._idx: Any = slice(0, 0)
        self._target = np.zeros(0)

    def _bind(self, model: Model) -> int:
        if model.vehicle_kind != "spatial":
            raise InputError(f"{self.name}: model {model.name!r} has no roll/pitch "
                             f"({model.vehicle_kind} vehicle)")
        for a in self.axes:
            if _ACTUATOR[a] not in model.actuated:
                raise InputError(f"{self.name}: model {model.name!r} does not actuate "
                                 f"{_ACTUATOR[a]!r} (actuated: {', '.join(model.actuated)}), so "
                                 f"{a} cannot be a task")
        self._idx = compact_index([model.eta_names.index(a) for a in self.axes])
        return len(self.axes)

    def _derive(self) -> None:
        super()._derive()
        self._target = np.array([self.roll if a == "phi" else self.pitch for a in self.axes])

    def set_target(self, *, roll: float | None = None, pitch: float | None = None) -> None:
        """Set the roll and/or pitch set point [rad] (scenario keys ``roll``, ``pitch``).

        Raises:
            InputError: no value, or one that is not a finite number.
        """
        given = {k: v for k, v in (("roll", roll), ("pitch", pitch)) if v is not None}
        if not given:
            raise InputError(f"{self.name}.set_target: give roll= and/or pitch= [rad]")
        self.update(**given)

    def error_rows(self, state: State, t: float, slot: TaskSlot
                   ) -> tuple[FloatArray, FloatArray, None]:
        """``(J_eta,S, wrap(angle_d - angle)_S, None)`` on roll/pitch [rad]."""
        idx = self._idx
        e = self._target - state.eta[idx]
        for i in range(e.shape[0]):
            e[i] = wrap_angle(e.item(i))
        return state.vehicle_pose_jacobian()[idx], e, None

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "roll", "pitch")

    def _check(self, key: str, value: Any) -> Any:
        if key in ("roll", "pitch"):
            return as_scalar(value, f"{self.name}.{key}")
        return super()._check(key, value)
