"""Manipulability of the arm (Yoshikawa's measure) as an objective, a floor or a shaped task."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ._common import TWIST_AXES, check_frame, parse_axes
from .task import Task

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


def _cross_cols(a: FloatArray, b: FloatArray) -> FloatArray:
    """Column-wise cross product of two (3, n) arrays."""
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]))


def manipulability_and_gradient(J6: FloatArray, rows: Any = None) -> tuple[float, FloatArray]:
    r"""Yoshikawa's measure of a serial arm Jacobian and its exact gradient over the joints.

    ``w = sqrt(det(J_S J_S^T))`` (``sqrt(det(J_S^T J_S))`` when ``J_S`` has more rows than columns),
    ``000_7b5f597fe4e36aa4.txt, Eq. (18)``, with ``J_S`` the selected rows of the twist Jacobian
    ``J6 = [V; W]`` (6, n) of the arm (columns in chain order, revolute or prismatic joints, any
    fixed reference frame). Its gradient (Eq. (19)) is
    ``dw/dq_i = w trace(dJ_S/dq_i J_S^+)``, evaluated with the exact column derivatives of a
    serial-chain geometric Jacobian:

        dJ_j/dq_i = [w_i x v_j; w_i x w_j]  (i <= j),     [w_j x v_i; 0]  (i > j),

    which turn the trace into ``dw/dq_i = w (w_i . sum_{j>=i} c_j + v_i . sum_{j<i} d_j)`` with
    ``c_j = v_j x P_v,j + w_j x P_w,j``, ``d_j = P_v,j x w_j`` and ``P = (J_S^+)^T`` padded to six
    rows. Units: ``w`` in the product of the row units (e.g. m^3 for 3 position rows); gradient
    in those units per rad.

    Args:
        J6: Twist Jacobian (6, n) of the frame, linear rows first.
        rows: Indices of the rows of ``J6`` to use (default: the 3 linear rows).

    Returns:
        ``(w, grad)`` with ``grad`` of shape (n,).
    """
    sel = np.arange(3) if rows is None else np.asarray(rows)
    Js = J6[sel]
    k, n = Js.shape
    G = Js @ Js.T if k <= n else Js.T @ Js
    det = float(np.linalg.det(G)) if G.shape[0] > 0 else 1.0
    w = math.sqrt(det) if det > 0.0 else 0.0
    if w < 1e-10 * max(1.0, float(np.abs(G).max(initial=0.0))) ** (0.5 * G.shape[0]):
        P = np.linalg.pinv(Js).T
    elif k <= n:
        P = np.linalg.solve(G, Js)
    else:
        P = Js @ np.linalg.inv(G)
    P6 = np.zeros((6, n))
    P6[sel] = P
    V, W = J6[:3], J6[3:]
    c = _cross_cols(V, P6[:3]) + _cross_cols(W, P6[3:])
    d = _cross_cols(P6[:3], W)
    suffix = np.cumsum(c[:, ::-1], axis=1)[:, ::-1]  # sum_{j>=i} c_j
    prefix = np.zeros_like(d)
    prefix[:, 1:] = np.cumsum(d, axis=1)[:, :-1]  # sum_{j<i} d_j
    grad = w * (np.einsum("ij,ij->j", W, suffix) + np.einsum("ij,ij->j", V, prefix))
    return w, grad


def shaping_function(w: float, threshold: float) -> float:
    r"""Shaping function ``k(w)`` blending station keeping and singularity avoidance.

    ``000_7b5f597fe4e36aa4.txt``, Section 4.3 (Eq. (21) and its Figure 4): ``k = 0`` when
    ``w >= threshold``, ``k = 1`` when ``w < threshold / 2``, and in between the smooth (C1)
    blend ``k = (1 + cos(pi (w - threshold/2) / (threshold/2))) / 2``. (The paper gives the
    function as a figure; this is our documented choice with the stated end points.)
    """
    half = 0.5 * threshold
    if w >= threshold:
        return 0.0
    if w < half:
        return 1.0
    return 0.5 * (1.0 + math.cos(math.pi * (w - half) / half))


class ManipulabilityTask(Task):
    r"""Keep the arm dexterous using Yoshikawa's manipulability ``w`` of the arm Jacobian.

    ``w = sqrt(det(J_S J_S^T))`` of the selected rows ``S`` of the arm's Jacobian of ``frame`` in
    the arm-base axes (joint columns only; ``000_7b5f597fe4e36aa4.txt, Eq. (18)``; in paper 000
    the measure of the collective Jacobian ``[J_p; J_s]`` reduces to this one since ``J_s``
    selects the vehicle coordinates). ``grad w`` (Eq. (19)) is exact (see
    :func:`manipulability_and_gradient`). Modes:

    * ``"ascend"``: rows ``qdot = lambda grad w`` over the arm joint rates (n_joints rows,
      [rad/s]): the gradient-projection objective of Eq. (4) with ``h = w`` (in a hierarchy the
      level below the tracking task reproduces Eq. (4)).
    * ``"floor"``: one inequality row ``grad w . qdot >= gain (minimum - w)`` ([w]/s), the
      first-order barrier that keeps ``w >= minimum``: with ``gain = 1/dt`` it is exactly
      ``w + dt grad w . qdot >= minimum``; a smaller gain approaches the floor gradually.
    * ``"shaping"``: rows ``qdot = k(w) (1 - sign(w_dot)) / 2 lambda grad w`` (Eq. (21)):
      :func:`shaping_function` ``k`` with the threshold ``rho_bar``, and the sign switch that
      only intervenes while ``w`` is not increasing (``sign(w_dot) = -1`` for ``w_dot <= 0``);
      ``w_dot`` is the finite difference of ``w`` between evaluations (0 at the first one).
      Place it in the same level as a :class:`StationKeepingTask`: the level's demand then
      reads ``[vehicle: station keeping; arm: k s lambda grad w]`` as in Eq. (21).

    Args:
        mode: ``"ascend"``, ``"floor"`` or ``"shaping"``.
        frame: Frame whose arm Jacobian is measured (default ``"tool"``).
        axes: Rows of the twist used, from ``x, y, z, rx, ry, rz`` (default ``x, y, z``; planar
            models ``x, y``).
        gain: ``lambda`` [rad/s per unit of w] for ascend/shaping; the barrier gain [1/s] for floor.
        minimum: Floor value of ``w`` (mode ``"floor"``).
        threshold: ``rho_bar`` of the shaping function (mode ``"shaping"``).
        weight: Weight within the level.
        name: Task name (default ``"manipulability"``).
    """

    type_name = "manipulability"
    error_unit = "m^k"
    rate_unit = "rad/s | m^k/s"

    def __init__(
        self,
        *,
        mode: Literal["ascend", "floor", "shaping"] = "floor",
        frame: str = "tool",
        axes: list[str] | None = None,
        gain: float = 1.0,
        minimum: float | None = None,
        threshold: float | None = None,
        weight: float = 1.0,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name, weight=weight)
        if mode not in ("ascend", "floor", "shaping"):
            raise InputError(f"{self.name}.mode: expected 'ascend', 'floor' or 'shaping', got "
                             f"{mode!r}")
        if not isinstance(frame, str) or not frame:
            raise InputError(f"{self.name}.frame: expected a frame name, got {frame!r}")
        self.mode = mode
        self.frame = frame
        self._axes_arg = None if axes is None else parse_axes(axes, TWIST_AXES,
                                                              f"{self.name}.axes")
        self.gain = as_scalar(gain, f"{self.name}.gain", positive=True)
        self.minimum = None if minimum is None else as_scalar(minimum, f"{self.name}.minimum",
                                                              nonnegative=True)
        self.threshold = None if threshold is None else as_scalar(
            threshold, f"{self.name}.threshold", positive=True)
        if mode == "floor" and self.minimum is None:
            raise InputError(f"{self.name}.minimum: required in mode 'floor'")
        if mode == "shaping" and self.threshold is None:
            raise InputError(f"{self.name}.threshold: required in mode 'shaping'")
        self.axes: list[str] = []
        self._sel = np.arange(3)
        self._nvh = 0
        self._prev: tuple[float, float] | None = None
        self._w_dot = 0.0
        self.value = float("nan")
        self.shaping = 0.0

    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        if model.n_joints == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        if self._axes_arg is not None:
            axes = self._axes_arg
        else:
            axes = ["x", "y"] if model.vehicle_kind == "planar" else ["x", "y", "z"]
        self.axes = list(axes)
        self._sel = np.array([TWIST_AXES.index(a) for a in axes], dtype=int)
        self._nvh = model.n_vehicle
        return 1 if self.mode == "floor" else model.n_joints

    def reset(self) -> None:
        """Forget the previous value used for ``w_dot``."""
        self._prev = None
        self._w_dot = 0.0

    def compute_value(self, state: State) -> tuple[float, FloatArray]:
        """``(w, grad w)`` at ``state`` (gradient over the arm joints, (n_joints,))."""
        return manipulability_and_gradient(state.arm_jacobian(self.frame, rows="twist"),
                                           self._sel)

    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write the rows of the selected mode (see the class docstring)."""
        w, g = self.compute_value(state)
        self.value = w
        self._last_error = np.array([w])
        A[:] = 0.0
        nvh = self._nvh
        if self.mode == "floor":
            A[0, nvh:] = g
            lower[0] = self.gain * (self.minimum - w)  # type: ignore[operator]
            upper[0] = np.inf
            return
        n = g.shape[0]
        A[np.arange(n), nvh + np.arange(n)] = 1.0
        scale = self.gain
        if self.mode == "shaping":
            if self._prev is not None and t > self._prev[0]:
                self._w_dot = (w - self._prev[1]) / (t - self._prev[0])
            self._prev = (t, w)
            switch = 0.0 if self._w_dot > 0.0 else 1.0
            self.shaping = shaping_function(w, self.threshold)  # type: ignore[arg-type]
            scale *= self.shaping * switch
        np.multiply(scale, g, out=lower)
        upper[:] = lower

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain", "minimum", "threshold")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "gain":
            self.gain = as_scalar(value, f"{self.name}.gain", positive=True)
        elif key == "minimum":
            self.minimum = as_scalar(value, f"{self.name}.minimum", nonnegative=True)
        elif key == "threshold":
            self.threshold = as_scalar(value, f"{self.name}.threshold", positive=True)
        else:
            super()._apply_update(key, value)
