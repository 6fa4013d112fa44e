"""Current alignment: turn the vehicle heading toward the direction of the water current."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from ._common import _TWO_PI, EtaRows, eta_axes, vehicle_pose_jacobian
from .task import ErrorTask

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class CurrentAlignmentTask(ErrorTask):
    r"""Align the vehicle heading ``psi`` with the current direction (``001_0fa6eac0390842e0.txt``).

    Paper 001 imposes the vehicle rates so that the vehicle stays aligned with the ocean current
    (its simulation: current at 0.78 rad), which saves energy. As a task its priority is the
    user's choice. One row:

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

    def __init__(
        self,
        *,
        heading: float | None = None,
        direction: list[float] | None = None,
        offset: float = 0.0,
        gain: float = 1.0,
        weight: float = 1.0,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self.offset = as_scalar(offset, f"{self.name}.offset")
        self.heading: float | None = None
        if heading is not None and direction is not None:
            raise InputError(f"{self.name}: give heading or direction, not both")
        if heading is not None:
            self._apply_update("heading", heading)
        if direction is not None:
            self._apply_update("direction", direction)
        self._row = 0
        self._rows: EtaRows | None = None

    def _bind(self, model: Model) -> int:
        axes = eta_axes(model)
        if "psi" not in axes:
            raise InputError(f"{self.name}: model {model.name!r} has no vehicle heading")
        if "r" not in model.actuated:
            raise InputError(f"{self.name}: model {model.name!r} does not actuate yaw rate r")
        self._row = axes.index("psi")
        self._rows = EtaRows(model, [self._row])
        return 1

    def compute_error(self, state: State, t: float) -> FloatArray:
        """``wrap(psi_c + offset - psi)`` [rad]."""
        if self.heading is None:
            self._missing_heading()
        e = (self.heading + self.offset - float(state.eta[self._row]) + math.pi) % (2 * math.pi)
        return np.array((e - math.pi,))

    def _missing_heading(self) -> NoReturn:
        raise InputError(f"task {self.name!r}: current heading never set; pass heading= or "
                         "direction=, or call update(heading=...)")

    def compute_jacobian(self, state: State, t: float) -> FloatArray:
        """Yaw row of the vehicle-pose Jacobian (1, nv)."""
        return vehicle_pose_jacobian(state)[self._row: self._row + 1]

    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write ``J_psi zeta = K wrap(psi_c + offset - psi)``.

        The operations of :meth:`compute_error` in plain floats; the row is written from the
        state's plain-float ``J_eta`` entries.
        """
        if not self._fused:
            super().fill(state, t, A, lower, upper)
            return
        heading = self.heading
        if heading is None:
            self._missing_heading()
        e = (heading + self.offset - state.eta_floats()[self._row] + math.pi) % _TWO_PI
        self._rows.write(state, A)  # type: ignore[union-attr]
        self._set_sides_floats([e - math.pi], lower, upper)

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "heading", "direction", "offset")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "heading":
            self.heading = as_scalar(value, f"{self.name}.heading")
        elif key == "direction":
            v = as_vector(value, f"{self.name}.direction")
            if v.shape[0] not in (2, 3):
                raise InputError(f"{self.name}.direction: expected 2 or 3 values, got {v.shape[0]}")
            if math.hypot(v[0], v[1]) < 1e-12:
                raise InputError(f"{self.name}.direction: horizontal part is zero, no heading")
            self.heading = math.atan2(v[1], v[0])
        elif key == "offset":
            self.offset = as_scalar(value, f"{self.name}.offset")
        else:
            super()._apply_update(key, value)
