"""Current alignment: turn the vehicle heading toward the direction of the water current."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from .error_task import ErrorTask
from .slot import TaskSlot

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


_TWO_PI = 2.0 * math.pi


class CurrentAlignmentTask(ErrorTask):
    r"""Align the vehicle heading ``psi`` with the current direction (dos Santos et al. (2006)).

    dos Santos et al. (2006) impose the vehicle rates so that the vehicle stays aligned with the
    ocean current (their simulation: current at 0.78 rad), which saves energy. As a task its
    priority is the user's choice. One row:

        J_psi zeta = K wrap(psi_c + offset - psi),

    with ``J_psi`` the yaw row of the vehicle-pose Jacobian (``psi_dot = J_psi zeta``), the error
    wrapped to ``[-pi, pi)`` [rad] and the row in [rad/s].

    Args:
        heading: Current direction ``psi_c`` [rad] in the world x-y plane (from x toward y).
        direction: Alternatively the current velocity (2 or 3 values, world frame) [m/s]; its
            horizontal direction gives ``psi_c = atan2(v_y, v_x)``.
        offset: Added to the current direction [rad] (``pi`` faces into the current).
        gain: Gain K [1/s].
        weight: Weight within the level.
        name: Task name (default ``"current_alignment"``).
    """

    type_name = "current_alignment"
    error_unit = "rad"
    rate_unit = "rad/s"

    def __init__(self, *, heading: float | None = None, direction: list[float] | None = None,
                 offset: float = 0.0, gain: float = 1.0, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self.offset = self._check("offset", offset)
        self.heading: float | None = None
        if heading is not None or direction is not None:
            self.heading = self._target(heading, direction)["heading"]
        self._row: slice = slice(0, 0)

    def _bind(self, model: Model) -> int:
        if "psi" not in model.eta_names:
            raise InputError(f"{self.name}: model {model.name!r} has no vehicle heading")
        if "r" not in model.actuated:
            raise InputError(f"{self.name}: model {model.name!r} does not actuate yaw rate r")
        row = model.eta_names.index("psi")
        self._row = slice(row, row + 1)
        return 1

    def set_target(self, *, heading: float | None = None,
                   direction: list[float] | None = None) -> None:
        """Set the current direction: ``heading`` [rad] or the current's velocity ``direction``.

        The scenario keys are the same (``update = { heading = 0.78 }``).

        Raises:
            InputError: neither or both given, a direction without a horizontal part.
        """
        self.heading = self._target(heading, direction)["heading"]

    def _target(self, heading: Any, direction: Any) -> dict[str, float]:
        """The heading [rad] of ``heading`` or ``direction`` (exactly one given)."""
        if (heading is None) == (direction is None):
            raise InputError(f"{self.name}: give heading or direction"
                             + (", not both" if heading is not None else ""))
        key, value = ("heading", heading) if heading is not None else ("direction", direction)
        return {"heading": self._check(key, value)}

    def error_rows(self, state: State, t: float, slot: TaskSlot
                   ) -> tuple[FloatArray, FloatArray, None]:
        """``(J_psi, wrap(psi_c + offset - psi), None)``: the yaw row of ``J_eta`` (1, nv)."""
        heading = self.heading
        if heading is None:
            raise InputError(f"task {self.name!r}: current heading never set; pass heading= or "
                             "direction=, or call set_target(heading=...)")
        row = self._row
        e = (heading + self.offset - state.eta.item(row.start) + math.pi) % _TWO_PI - math.pi
        return state.vehicle_pose_jacobian()[row], np.array((e,)), None

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "heading", "direction", "offset")

    def _checked(self, params: dict[str, Any]) -> dict[str, Any]:
        values = {k: self._check(k, v) for k, v in params.items()
                  if k not in ("heading", "direction")}
        if "heading" in params or "direction" in params:
            values.update(self._target(params.get("heading"), params.get("direction")))
        return values

    def _check(self, key: str, value: Any) -> Any:
        if key in ("heading", "offset"):
            return as_scalar(value, f"{self.name}.{key}")
        if key == "direction":
            v = as_vector(value, f"{self.name}.direction")
            if v.shape[0] not in (2, 3):
                raise InputError(f"{self.name}.direction: expected 2 or 3 values, got {v.shape[0]}")
            if math.hypot(v[0], v[1]) < 1e-12:
                raise InputError(f"{self.name}.direction: horizontal part is zero, no heading")
            return math.atan2(v[1], v[0])
        return super()._check(key, value)
