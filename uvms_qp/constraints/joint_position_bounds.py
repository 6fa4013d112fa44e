"""Joint position limits turned into joint-rate bounds through the control period."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ..model.selection import check_joint_list, compact_index, joint_indices
from .constraint import Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class JointPositionBounds(Constraint):
    r"""Hard joint position limits as joint-rate bounds (box on the arm columns of zeta).

    With one explicit Euler step of length ``dt`` [s], ``q + dt qdot`` stays inside
    ``[q_min + margin, q_max - margin]`` when

        gain (q_min + margin - q) / dt  <=  qdot  <=  gain (q_max - margin - q) / dt,

    ``0 < gain <= 1`` the fraction of the remaining distance allowed in one step (1: the limit
    can be reached in one step; smaller values approach it geometrically). A joint already outside
    its band gets ``lower = min(lower, 0)``, ``upper = max(upper, 0)``: it may stay or return, never
    go further out, and the box always contains zero (so it never empties against rate bounds).
    Joints without finite limits are unconstrained. Bounds [rad/s].

    Args:
        gain: Fraction of the remaining distance per step, ``0 < gain <= 1``.
        margin: Distance kept inside the limits [rad] (>= 0).
        joints: Joint names (default: all arm joints with finite limits).
        name: Name (default ``"joint_position_bounds"``).
    """

    type_name = "joint_position_bounds"
    unit = "rad/s"
    has_box = True

    def __init__(self, *, gain: float = 1.0, margin: float = 0.0,
                 joints: list[str] | None = None, name: str | None = None) -> None:
        super().__init__(name=name)
        self.gain = as_scalar(gain, f"{self.name}.gain", positive=True)
        if self.gain > 1.0:
            raise InputError(f"{self.name}.gain: expected 0 < gain <= 1, got {self.gain}")
        self.margin = as_scalar(margin, f"{self.name}.margin", nonnegative=True)
        self.joints = check_joint_list(joints, f"{self.name}.joints")
        self._cols = np.zeros(0, dtype=int)
        self._idx: Any = None  # constrained joints (None: all of them)
        self._lo_list: list[float] = []
        self._hi_list: list[float] = []

    def _bind(self, model: Model) -> int:
        idx = joint_indices(model, self.joints, f"{self.name}.joints")
        lo = np.asarray(model.joint_lower, dtype=float)[idx] + self.margin
        hi = np.asarray(model.joint_upper, dtype=float)[idx] - self.margin
        finite = np.isfinite(lo) | np.isfinite(hi)
        if np.any(lo[finite] > hi[finite]):
            j = int(idx[finite][np.flatnonzero(lo[finite] > hi[finite])[0]])
            raise InputError(f"{self.name}.margin: {self.margin} rad leaves no room inside the "
                             f"limits of joint {model.joint_names[j]!r}")
        kept = idx[finite]
        self._idx = (None if kept.tolist() == list(range(model.n_joints))
                     else compact_index(kept))
        self._cols = compact_index(model.n_vehicle + idx[finite])
        self._lo_list, self._hi_list = lo[finite].tolist(), hi[finite].tolist()
        return 0

    def fill_box(self, state: State, dt: float, lower: FloatArray, upper: FloatArray) -> None:
        """Intersect the joint-rate bounds into the box.

        Per joint in plain floats (a handful of joints: cheaper than array calls), read from
        and written back to the box's columns in one call each.
        """
        k = self.gain / dt
        cols = self._cols
        q = state.joints if self._idx is None else state.joints[self._idx]
        new_lo = []
        new_hi = []
        for a, b, x, lo, hi in zip(self._lo_list, self._hi_list, q.tolist(),
                                   lower[cols].tolist(), upper[cols].tolist(), strict=True):
            v = (a - x) * k  # [rad/s]; a joint outside its band may stay or return
            if v > 0.0:
                v = 0.0
            new_lo.append(v if v > lo else lo)
            v = (b - x) * k
            if v < 0.0:
                v = 0.0
            new_hi.append(v if v < hi else hi)
        lower[cols] = new_lo
        upper[cols] = new_hi

    def update(self, **params: Any) -> None:
        """Accepts ``gain``."""
        for key, value in params.items():
            if key != "gain":
                raise InputError(f"{self.name}.update: unknown parameter {key!r}; known: gain")
            gain = as_scalar(value, f"{self.name}.gain", positive=True)
            if gain > 1.0:
                raise InputError(f"{self.name}.gain: expected 0 < gain <= 1, got {gain}")
            self.gain = gain
