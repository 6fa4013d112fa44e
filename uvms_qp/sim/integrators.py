"""Time integration of the commanded rates on the model's configuration manifold.

The controller's command ``zeta = [actuated vehicle body rates; joint rates]`` (m/s, rad/s) is held
over one control period ``dt`` [s] (zero-order hold, as on a real vehicle) and integrated with
``model.integrate(q, zeta, dt)``: the exponential map of the vehicle's body twist on SE(3) (or
SE(2)) and a sum for the joints. With the command held, that update is exact; it is the explicit
Euler scheme of the papers (Soylu et al. (2007), Section 3; dos Santos et al. (2006),
Euler step 0.1 s) applied to the closed loop.

``method="rk4"`` integrates the closed loop as a continuous-time system instead: the rates are
re-evaluated at the classic Runge-Kutta stages (``rates(q, t)``, i.e. three extra controller
solves per step) and their weighted mean ``(k1 + 2 k2 + 2 k3 + k4) / 6`` is applied through the
exponential map (a tangent-space average, exact to first order on the group).

Two effects the kinematic model does not command are added after the update (first-order operator
splitting):

- Passive roll and pitch (vehicles that do not actuate ``p``/``q``): ``passive="hold"`` keeps them
  where they are (``model.integrate`` gives passive DOFs zero rate); ``passive="restore"`` models
  the hydrostatic restoring moment of a bottom-heavy vehicle as a first-order decay toward level,
  ``d(phi)/dt = -phi / tau`` and ``d(theta)/dt = -theta / tau``, applied exactly:
  ``phi <- phi exp(-dt / tau)``.
- A current drift: the vehicle position moves by ``v_d dt`` with ``v_d`` the world drift velocity
  of :class:`~uvms_qp.sim.current.ConstantCurrent` (zero unless its ``drift`` is set).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Literal

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from .current import ConstantCurrent

Method = Literal["euler", "rk4"]
Passive = Literal["hold", "restore"]
RateFunction = Callable[[FloatArray, float], FloatArray]


class Integrator:
    """Advance a configuration by one control period.

    Args:
        model: The :class:`~uvms_qp.model.Model` whose ``integrate``, ``split`` and
            ``configuration`` are used.
        method: ``"euler"`` (zero-order hold, default) or ``"rk4"`` (closed loop re-evaluated).
        passive: ``"hold"`` or ``"restore"`` for passive roll/pitch (see the module docstring).
        restore_time_constant: Time constant tau of the restoring model [s] (> 0).
        current: Optional current whose drift displaces the vehicle.
    """

    def __init__(
        self,
        model: Any,
        method: Method = "euler",
        passive: Passive = "hold",
        restore_time_constant: float = 2.0,
        current: ConstantCurrent | None = None,
    ) -> None:
        if method not in ("euler", "rk4"):
            raise InputError(f"method: expected 'euler' or 'rk4', got {method!r}")
        if passive not in ("hold", "restore"):
            raise InputError(f"passive: expected 'hold' or 'restore', got {passive!r}")
        self.model = model
        self.method: Method = method
        self.passive: Passive = passive
        self.restore_time_constant = as_scalar(
            restore_time_constant, "restore_time_constant", positive=True
        )
        self.current = current
        kind = getattr(model, "vehicle_kind", "fixed")
        actuated = tuple(getattr(model, "actuated", ()))
        # indices in eta of passive roll/pitch (spatial vehicles only)
        self._passive_angles = (
            [i for i, dof in ((3, "p"), (4, "q")) if dof not in actuated]
            if kind == "spatial"
            else []
        )
        self._restore = passive == "restore" and bool(self._passive_angles)
        drift = None if current is None else current.drift_velocity()
        self._drift: FloatArray | None = None
        if drift is not None and np.any(drift != 0.0) and kind != "fixed":
            self._drift = drift if kind == "spatial" else drift[:2]

    @property
    def passive_angles(self) -> tuple[str, ...]:
        """The passive attitude angles (``"phi"``, ``"theta"``) that ``passive`` acts on.

        Empty for a planar or fixed vehicle, or one that actuates roll and pitch.
        """
        return tuple(("phi", "theta")[i - 3] for i in self._passive_angles)

    def step(
        self,
        q: FloatArray,
        zeta: FloatArray,
        dt: float,
        t: float = 0.0,
        rates: RateFunction | None = None,
    ) -> FloatArray:
        """Return the configuration after one period ``dt`` [s] under the command ``zeta``.

        Args:
            q: Configuration (nq,) at time ``t``.
            zeta: Command computed at ``(q, t)`` (nv,) [m/s, rad/s].
            dt: Control period [s].
            t: Current time [s] (used by ``rk4`` stages).
            rates: ``rates(q, t) -> zeta``, required by ``rk4``.
        """
        model = self.model
        if self.method == "rk4":
            if rates is None:
                raise InputError("rates: the rk4 integrator needs a rate function rates(q, t)")
            half = 0.5 * dt
            k2 = rates(model.integrate(q, zeta, half), t + half)
            k3 = rates(model.integrate(q, k2, half), t + half)
            k4 = rates(model.integrate(q, k3, dt), t + dt)
            zeta = (zeta + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
        q_next = model.integrate(q, zeta, dt)
        if self._restore or self._drift is not None:
            q_next = self._disturb(q_next, dt)
        return q_next

    def _disturb(self, q: FloatArray, dt: float) -> FloatArray:
        eta, joints = self.model.split(q)
        eta = np.array(eta, dtype=np.float64)
        if self._drift is not None:
            eta[: self._drift.shape[0]] += self._drift * dt
        if self._restore:
            decay = math.exp(-dt / self.restore_time_constant)
            for i in self._passive_angles:
                eta[i] *= decay
        return np.asarray(self.model.configuration(eta, joints), dtype=np.float64)
