"""Bounds on how fast the command changes: ``|zeta_k - zeta_{k-1}| <= a_max dt`` per entry.

A vehicle's thrusters and an arm's actuators deliver a bounded acceleration: a command that jumps
from one rate bound to the other in one period cannot be followed. This constraint turns an
acceleration bound ``a_max`` [m/s^2, rad/s^2] into a box around the previous command,

    zeta_{k-1} - a_max dt  <=  zeta_k  <=  zeta_{k-1} + a_max dt,

intersected with the other hard bounds. The previous command is the one the controller sent: the
controller hands it to every constraint after each step (:meth:`Constraint.command_sent`).

Position safety first: the window yields to the other boxes (joint position limits, rate
bounds). It is clipped into their intersection, so when the two do not meet (a joint rate that
must drop faster than ``a_max`` allows to keep the joint inside its limits, a rate bound lowered
at run time) the command goes to the nearest point of the other boxes, and the acceleration bound
is the one that gives.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from .constraint import Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_LINEAR = ("u", "v", "w")
#: Time [s] in which the default bounds take an entry from rest to the model's rate limit.
DEFAULT_RAMP = 0.5


class _Window:
    """The previous command (a buffer (nv,)), or None for a free first step."""

    __slots__ = ("buffer", "previous")

    def __init__(self) -> None:
        self.buffer = np.zeros(0)
        self.previous: FloatArray | None = None


class CommandRateBounds(Constraint):
    r"""Hard bounds on the change of the command per period, ``|zeta_k - zeta_{k-1}| <= a dt``.

    The acceleration bound ``a`` of each entry of zeta comes, in order of precedence, from
    ``limits`` (one per entry of zeta), from ``joint`` (scalar or one per joint), ``linear``
    (u, v, w) and ``angular`` (p, q, r), and otherwise from the model's rate limit divided by
    ``ramp``: ``joint_rate_limit / ramp`` and ``vehicle_rate_limit / ramp``. Entries whose
    model rate limit is infinite (no published figure) stay free unless given.

    For ``bluerov2_heavy_alpha5`` the defaults (``ramp = 0.5 s``) are 1.0 rad/s^2 per arm joint
    (the Reach Alpha 5's published 0.5 rad/s) and 3.0 m/s^2 in surge (the BlueROV2 Heavy's
    published 1.5 m/s); neither vendor publishes an acceleration or a thrust figure, so the
    ramp time is the stated assumption. The other bundled models come from papers that give no
    rate limits: give the bounds explicitly.

    The first step after construction or :meth:`reset` starts from ``initial``: ``"rest"``
    (zero command, the default: a vehicle and arm at rest), ``"free"`` (no bound on the first
    step) or a command (one value per entry of zeta).

    Args:
        joint: Joint acceleration bound [rad/s^2, m/s^2 for prismatic joints], one value or one
            per joint.
        linear: Vehicle linear acceleration bound on u, v, w [m/s^2].
        angular: Vehicle angular acceleration bound on p, q, r [rad/s^2].
        limits: Bounds for every entry of zeta (vehicle then joints) [m/s^2, rad/s^2].
        ramp: Time from rest to the model's rate limit for the entries not given [s] (> 0).
        initial: The previous command of the first step: ``"rest"``, ``"free"`` or a command
            (nv,) [m/s, rad/s].
        name: Name (default ``"command_rate_bounds"``).
    """

    type_name = "command_rate_bounds"
    unit = "m/s^2, rad/s^2"
    has_box = True
    yields = True

    def __init__(
        self,
        *,
        joint: float | list[float] | None = None,
        linear: float | None = None,
        angular: float | None = None,
        limits: list[float] | None = None,
        ramp: float = DEFAULT_RAMP,
        initial: Literal["rest", "free"] | list[float] = "rest",
        name: str | None = None,
    ) -> None:
        super().__init__(name=name)
        self._joint_arg = None if joint is None else self._positive(
            as_vector(joint, f"{self.name}.joint", allow_inf=True), "joint")
        self.linear = None if linear is None else self._positive(
            as_scalar(linear, f"{self.name}.linear", allow_inf=True), "linear")
        self.angular = None if angular is None else self._positive(
            as_scalar(angular, f"{self.name}.angular", allow_inf=True), "angular")
        self._limits_arg = None if limits is None else self._positive(
            as_vector(limits, f"{self.name}.limits", allow_inf=True), "limits")
        self.ramp = as_scalar(ramp, f"{self.name}.ramp", positive=True)
        if isinstance(initial, str):
            if initial not in ("rest", "free"):
                raise InputError(f"{self.name}.initial: expected 'rest', 'free' or a command, "
                                 f"got {initial!r}")
            self._initial_arg: str | FloatArray = initial
        else:
            self._initial_arg = as_vector(initial, f"{self.name}.initial")
        self.limits = np.zeros(0)
        self._cols = np.zeros(0, dtype=np.intp)
        self._lim = np.zeros(0)
        self._own = _Window()

    def _positive(self, value: Any, key: str) -> Any:
        if np.any(np.asarray(value) <= 0.0):
            raise InputError(f"{self.name}.{key}: expected positive bounds (inf for none), "
                             f"got {np.asarray(value).tolist()}")
        return value

    def _bind(self, model: Model) -> int:
        nv, nvh, nj = model.nv, model.n_vehicle, model.n_joints
        if self._limits_arg is not None:
            if self._limits_arg.shape[0] != nv:
                raise InputError(f"{self.name}.limits: expected {nv} values "
                                 f"({', '.join(model.zeta_names)}), got "
                                 f"{self._limits_arg.shape[0]}")
            lim = self._limits_arg.copy()
        else:
            lim = np.concatenate((np.asarray(model.vehicle_rate_limit, dtype=float),
                                  np.asarray(model.joint_rate_limit, dtype=float))) / self.ramp
            for i, dof in enumerate(model.actuated):
                value = self.linear if dof in _LINEAR else self.angular
                if value is not None:
                    lim[i] = value
            if self._joint_arg is not None:
                if self._joint_arg.shape[0] not in (1, nj):
                    raise InputError(f"{self.name}.joint: expected one value or {nj} (one per "
                                     f"joint), got {self._joint_arg.shape[0]}")
                lim[nvh:] = self._joint_arg
        if not isinstance(self._initial_arg, str) and self._initial_arg.shape[0] != nv:
            raise InputError(f"{self.name}.initial: expected {nv} values "
                             f"({', '.join(model.zeta_names)}), got {self._initial_arg.shape[0]}")
        finite = np.isfinite(lim)
        self.limits = lim
        self._cols = np.flatnonzero(finite)
        self._lim = lim[finite]
        self.model = model  # reset() reads the size
        self.reset()
        return 0

    # ----------------------------------------------------------------------------- run-time hooks
    def memory(self) -> _Window:
        """A new memory of the previous command (one per controller), at ``initial``."""
        window = _Window()
        self.reset(window)
        return window

    def reset(self, memory: Any = None) -> None:
        """Start again from ``initial`` (the previous command of the next step)."""
        window: _Window = self._own if memory is None else memory
        if self.model is None:
            return
        window.buffer = np.zeros(self.model.nv)
        if isinstance(self._initial_arg, str):
            window.previous = None if self._initial_arg == "free" else window.buffer
        else:
            window.buffer[:] = self._initial_arg
            window.previous = window.buffer

    def command_sent(self, zeta: FloatArray, memory: Any = None) -> None:
        """Remember ``zeta`` (nv,) [m/s, rad/s], the command sent this period."""
        window: _Window = self._own if memory is None else memory
        window.buffer[:] = zeta
        window.previous = window.buffer

    @property
    def previous(self) -> FloatArray | None:
        """The previous command of the constraint's own memory (a copy), or None (free)."""
        previous = self._own.previous
        return None if previous is None else previous.copy()

    # ------------------------------------------------------------------------------------- box
    def fill_box(self, state: State, dt: float, lower: FloatArray, upper: FloatArray,
                 memory: Any = None) -> None:
        """Clip the window ``previous +/- a dt`` into the box and make it the box.

        Called after every other box: where the window misses the box, the box's nearest
        point is kept (position safety first); an already empty box stays empty. ``memory``:
        the controller's (default the constraint's own).
        """
        previous = (self._own if memory is None else memory).previous
        if previous is None:
            return
        cols = self._cols
        lo, hi = lower[cols], upper[cols]
        centre = previous[cols]
        step = self._lim * dt
        window_lo = np.minimum(np.maximum(centre - step, lo), hi)
        window_hi = np.minimum(np.maximum(centre + step, lo), hi)
        meets = lo <= hi
        lower[cols] = np.where(meets, window_lo, lo)
        upper[cols] = np.where(meets, window_hi, hi)

    def update(self, **params: Any) -> None:
        """Accepts ``linear``, ``angular``, ``joint`` (bounds of the current model)."""
        model = self._require_bound()
        for key, value in params.items():
            if key in ("linear", "angular"):
                bound = self._positive(as_scalar(value, f"{self.name}.{key}", allow_inf=True),
                                       key)
                for i, dof in enumerate(model.actuated):
                    if (dof in _LINEAR) == (key == "linear"):
                        self.limits[i] = bound
            elif key == "joint":
                bound = self._positive(as_vector(value, f"{self.name}.joint", allow_inf=True),
                                       key)
                if bound.shape[0] not in (1, model.n_joints):
                    raise InputError(f"{self.name}.joint: expected one value or "
                                     f"{model.n_joints}, got {bound.shape[0]}")
                self.limits[model.n_vehicle:] = bound
            else:
                raise InputError(f"{self.name}.update: unknown parameter {key!r}; known: "
                                 "angular, joint, linear")
        finite = np.isfinite(self.limits)
        self._cols = np.flatnonzero(finite)
        self._lim = self.limits[finite]
