"""Nenchev and Tsumaki: the singularity-consistent (SC) method for the 4-DOF arm.

The column-augmented Jacobian ``H = [J, -v_hat]`` of the PA-10-like positioning arm has a
two-dimensional kernel spanned by the self-motion field ``f_sm`` (no q4 rate, no path rate) and the
end-point field ``f_ep`` (no q3 rate, path rate ``S4``), both from signed minors
(Nenchev and Tsumaki, Section 2.1 and 3). The scheme commands "natural motion" (Eq. 3)::

    dq_bar = b_sm f_sm(q) + b_ep f_ep(q, v_hat),     zeta = dq_bar[:4],   p_dot = dq_bar[4]

with constant ``b``: no trajectory and no feedback (so no tool error; the diagnostics record
``line_deviation`` [m], the wrist centre's distance from the line through its start point along
``v_hat``). The wrist centre moves along ``v_hat`` at the rate ``p_dot`` (dimensionless "speed"
in m/s per unit b), which changes sign exactly at the extended/folded-arm singularity, so the arm
passes through it with bounded joint rates. The sign of a kernel vector is a convention: with the
printed fields (``f_ep5 = S4``) the paper's first run moves toward -x; ``b_ep = -1`` gives the
order of events its text describes (see docs/papers/002_nenchev.md). The
fields are evaluated by :func:`uvms_qp.analytic.sc_blend` from the joint angles; the model's own
Jacobian is the same matrix (checked in the tests).

The paper's scaling divides both fields by ``d3 d5 c`` (``c`` the shoulder term, zero at the
shoulder singularity). For motion in the arm plane (run 1) the singularity is removable: the
fields stay finite as ``c -> 0`` (e.g. ``f_ep = (0, 1, 0, c, S4)`` there). Only a step landing
within ``shoulder_tolerance`` of ``c = 0`` needs care (see :meth:`fields`); such steps are counted
in ``shoulder_clamped``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..analytic.singularity_consistent import (
    end_point_field,
    sc_arm_position,
    self_motion_field,
    shoulder_term,
)
from ..errors import InputError
from .scheme import Scheme

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class NenchevSingularityConsistent(Scheme):
    """SC natural motion of the 4-DOF positioning arm, Nenchev and Tsumaki, Eq. (3).

    Args:
        direction: Wrist-centre direction v_hat in the base (world) frame (paper: (1, 0, 0)).
        b_ep: End-point speed factor (paper: 1; -1 gives the order of events the paper's text
            describes for its first run) [1/s].
        b_sm: Self-motion speed factor (paper run 1: 0, run 2: 1) [1/s].
        d3: Upper-arm length [m] (paper: 1).
        d5: Forearm length [m] (paper: 1).
        shoulder_tolerance: Smallest |c| [m] used in the paper scaling near the shoulder
            singularity.
        name: Label in results.
    """

    type_name = "nenchev_sc"
    vehicle_kinds = ("fixed",)
    needs_trajectory = False

    def __init__(
        self,
        *,
        direction: Sequence[float] = (1.0, 0.0, 0.0),
        b_ep: float = 1.0,
        b_sm: float = 0.0,
        d3: float = 1.0,
        d5: float = 1.0,
        shoulder_tolerance: float = 1e-9,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name)
        v = as_vector(direction, "direction", 3)
        norm = float(np.linalg.norm(v))
        if norm == 0.0:
            raise InputError("direction: expected a non-zero vector")
        self.direction = v / norm
        self.b_ep = as_scalar(b_ep, "b_ep")
        self.b_sm = as_scalar(b_sm, "b_sm")
        self.d3 = as_scalar(d3, "d3", positive=True)
        self.d5 = as_scalar(d5, "d5", positive=True)
        self.shoulder_tolerance = as_scalar(shoulder_tolerance, "shoulder_tolerance", positive=True)
        self.path_length = 0.0
        self.shoulder_clamped = 0
        self._start: FloatArray | None = None

    def _bind(self, model: Model) -> None:
        if model.n_joints != 4:
            raise InputError(
                f"{self.name}: the SC fields are for the 4-DOF positioning arm; model "
                f"{model.name!r} has {model.n_joints} joints"
            )

    def reset(self) -> None:
        """Reset the path parameter, the shoulder counter and the line's start point."""
        super().reset()
        self.path_length = 0.0
        self.shoulder_clamped = 0
        self._start = None

    def fields(self, q: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Return ``(f_sm, f_ep)`` at joint angles ``q`` (paper scaling).

        Exactly at the shoulder singularity (``|c| < shoulder_tolerance``) the paper's closed forms
        are 0/0; the fields are then the mean of their values at ``q2 -/+ 1e3 * tol``, which is
        the limit when the singularity is removable (motion in the arm plane, run 1).
        """
        c = shoulder_term(q, self.d3, self.d5)
        if abs(c) >= self.shoulder_tolerance:
            return (
                self_motion_field(q, self.d3, self.d5),
                end_point_field(q, self.direction, self.d3, self.d5),
            )
        self.shoulder_clamped += 1
        step = np.zeros(4)
        step[1] = 1e3 * self.shoulder_tolerance
        f_sm = np.zeros(5)
        f_ep = np.zeros(5)
        for shifted in (q - step, q + step):
            f_sm += 0.5 * self_motion_field(shifted, self.d3, self.d5)
            f_ep += 0.5 * end_point_field(shifted, self.direction, self.d3, self.d5)
        return f_sm, f_ep

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        q = np.asarray(state.joints, dtype=np.float64)
        f_sm, f_ep = self.fields(q)
        dq_bar = self.b_sm * f_sm + self.b_ep * f_ep
        self.path_length += float(dq_bar[4]) * (self.dt or 0.0)
        wrist = sc_arm_position(q, self.d3, self.d5)
        if self._start is None:
            self._start = wrist
        offset = wrist - self._start
        self.info = {
            "line_deviation": float(np.linalg.norm(offset - (offset @ self.direction)
                                                   * self.direction)),
            "path_rate": float(dq_bar[4]),
            "path": self.path_length,
            "f_sm4": float(f_sm[3]),
            "f_sm5": float(f_sm[4]),
            "f_ep3": float(f_ep[2]),
            "f_ep5": float(f_ep[4]),
            "sin_q4": float(np.sin(q[3])),
            "shoulder_term": shoulder_term(q, self.d3, self.d5),
        }
        return dq_bar[:4].copy(), {}
