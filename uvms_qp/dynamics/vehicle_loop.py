"""The vehicle's body-velocity loop: the dynamic layer under the kinematic controller.

The kinematic controller produces a body-velocity reference ``nu_ref`` for the vehicle; this loop
turns the error ``nu_ref - nu`` into the body wrench the thrusters are asked for, per DOF

    tau_j = kp_j e_j + ki_j I_j + g_j(q) + d_j(nu_ref - nu_c)  (actuated DOFs; 0 on passive ones)

with ``I_j`` the integral of ``e_j``, ``g(q)`` the restoring wrench (weight and buoyancy) fed
forward and, optionally, ``d(nu_r) = (D_l + D_q |nu_r|) nu_r`` the damping at the reference
velocity relative to the water fed forward: the plant's damping acts on the velocity relative to
the water, ``nu_c`` the water's twist in the body frame when the loop is told the current, zero
when it is not (then the integral must find the rest; the two-layer scheme validated at sea by
Simetti et al.,
"Floating underwater manipulation: developed control methodology and experimental validation
within the TRIDENT project", J. Field Robotics 31(3), 2014; Antonelli, "Underwater Robots",
Springer, 2014, Chapter 6).

Anti-windup, two measures: (1) conditional integration: DOF ``j`` does not integrate while the
previous allocation left part of its demand unmet in the direction its error pushes (the
thrusters are saturated there and more integral would only wind up); (2) the integral term
``ki_j I_j`` is clamped to the largest wrench the thrusters can give that DOF.

Frames and units: FRD body frame, ``nu = [u, v, w, p, q, r]`` [m/s, rad/s], wrenches
``[X, Y, Z, K, M, N]`` [N, N m]; gains ``kp`` [N s/m, N m s/rad], ``ki`` [N/m, N m/rad].
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._validation import FloatArray, as_array, as_scalar, as_vector
from ..errors import InputError, ShapeError
from ..model.vehicle import NU_NAMES

#: Default closed-loop natural frequency of every axis [rad/s] and damping ratio (see
#: :func:`pole_placement_gains` and ``docs/dynamics.md``).
DEFAULT_BANDWIDTH = 4.0
DEFAULT_DAMPING_RATIO = 1.0

#: An unmet wrench component below this is round-off of the allocation, not saturation [N, N m].
UNMET_TOLERANCE = 1e-3

Restoring = Callable[[Any], Any]


def pole_placement_gains(inertia: Any, linear_damping: Any, *,
                         bandwidth: Any = DEFAULT_BANDWIDTH,
                         damping_ratio: Any = DEFAULT_DAMPING_RATIO
                         ) -> tuple[FloatArray, FloatArray]:
    """PI gains that place each axis's closed-loop poles, per DOF.

    Each axis linearised about rest, decoupled: ``m_j nu_j' = -d_j nu_j + tau_j`` with ``m_j``
    the rigid-body plus added inertia and ``d_j`` the linear damping. With
    ``tau_j = kp_j e_j + ki_j int e_j`` the closed loop's characteristic polynomial is
    ``m_j s^2 + (d_j + kp_j) s + ki_j``; matching ``m_j (s^2 + 2 zeta w s + w^2)`` gives

        kp_j = 2 zeta w m_j - d_j,      ki_j = w^2 m_j.

    Args:
        inertia: Rigid-body plus added inertia per DOF (6,) [kg, kg m^2] (a (6, 6) matrix: its
            diagonal), > 0.
        linear_damping: Linear damping per DOF (6,) [N s/m, N m s/rad] (magnitudes), >= 0.
        bandwidth: Natural frequency ``w`` [rad/s], one or per DOF (6,), > 0.
        damping_ratio: ``zeta``, one or per DOF (6,), > 0.

    Returns:
        ``(kp, ki)``, each (6,).

    Raises:
        InputError: a value of the wrong shape or sign, or a damping so large that ``kp`` would
            be negative (the message names the DOF; lower the damping or raise the bandwidth).
    """
    m = _diagonal(inertia, "inertia")
    if not m.min() > 0.0:
        raise InputError(f"inertia: expected positive entries, got {m.tolist()}")
    d = as_vector(linear_damping, "linear_damping", 6)
    if d.min() < 0.0:
        raise InputError(f"linear_damping: expected magnitudes >= 0, got {d.tolist()}")
    w = _per_dof(bandwidth, "bandwidth")
    zeta = _per_dof(damping_ratio, "damping_ratio")
    kp = 2.0 * zeta * w * m - d
    bad = np.flatnonzero(kp < 0.0)
    if bad.size:
        j = int(bad[0])
        raise InputError(f"bandwidth: {w[j]:g} rad/s on DOF {NU_NAMES[j]} is slower than its "
                         f"open loop (damping {d[j]:g} > 2 zeta w m = {d[j] + kp[j]:g}): "
                         "raise the bandwidth")
    return kp, w * w * m


def _diagonal(value: Any, name: str, size: int = 6) -> FloatArray:
    """A (size,) vector, or the diagonal of a (size, size) matrix."""
    array = as_array(value, name)
    if array.ndim == 2:
        if array.shape != (size, size):
            raise ShapeError(f"{name}: expected ({size},) or ({size}, {size}), got shape "
                             f"{array.shape}")
        array = np.diag(array).copy()
    return as_vector(array, name, size)


def _per_dof(value: Any, name: str) -> FloatArray:
    if np.ndim(value) == 0:
        return np.full(6, as_scalar(value, name, positive=True))
    return as_vector(value, name, 6, positive=True)


class VelocityLoop:
    """PI body-velocity loop with feed-forward and anti-windup; output: the demanded wrench.

    Args:
        kp: Proportional gains per DOF (6,) [N s/m, N m s/rad], >= 0.
        ki: Integral gains per DOF (6,) [N/m, N m/rad], >= 0.
        dt: Loop period [s] (the servo rate, e.g. 0.01 s at 100 Hz), > 0.
        actuated: DOFs the loop controls (``nu`` names, default all six); the others receive
            no wrench (a 4-DOF vehicle leaves roll and pitch to its restoring moments).
        restoring: ``restoring(q) -> (6,)``: the wrench that holds the vehicle against its weight
            and buoyancy at configuration ``q`` (Fossen's ``g(eta)``, the sign that cancels the
            restoring forces) [N, N m], fed forward; None: none.
        linear_damping: ``D_l`` per DOF (6,), magnitudes; with ``quadratic_damping`` feeds
            forward ``(D_l + D_q |nu_r|) nu_r`` at the reference relative to the water,
            ``nu_r = nu_ref - nu_c`` (:meth:`step`'s ``water``). None for both: no damping
            feed-forward.
        quadratic_damping: ``D_q`` per DOF (6,), magnitudes (default zeros when ``D_l`` given).
        integral_limit: Bound on ``|ki_j I_j|`` per DOF (6,) [N, N m], > 0 (``inf``: none);
            typically the largest wrench the thrusters can give each DOF
            (``max(-layout.wrench_lower, layout.wrench_upper)``).

    Raises:
        InputError: gains, limits or damping of the wrong shape or sign, an unknown DOF, a
            non-callable ``restoring`` (the message names the argument and the DOF).
    """

    def __init__(self, kp: Any, ki: Any, *, dt: float, actuated: Sequence[str] | None = None,
                 restoring: Restoring | None = None, linear_damping: Any = None,
                 quadratic_damping: Any = None, integral_limit: Any = None) -> None:
        self.dt = as_scalar(dt, "dt", positive=True)
        dofs = NU_NAMES if actuated is None else tuple(actuated)
        for d in dofs:
            if d not in NU_NAMES:
                raise InputError(f"actuated: unknown DOF {d!r}; known DOFs: "
                                 f"{', '.join(NU_NAMES)}")
        self.actuated: tuple[str, ...] = tuple(d for d in NU_NAMES if d in dofs)
        self._mask = np.array([d in self.actuated for d in NU_NAMES], dtype=float)
        if integral_limit is None:
            limit = np.full(6, math.inf)
        else:
            limit = as_vector(integral_limit, "integral_limit", 6, allow_inf=True)
            if not limit.min() > 0.0:
                j = int(np.argmin(limit))
                raise InputError(f"integral_limit: expected positive bounds, got {limit[j]:g} "
                                 f"on DOF {NU_NAMES[j]}")
        self._integral_limit = limit.copy()
        self._bound = np.zeros(6)  # on |I|: ki |I| within the integral limit
        self._kp = np.zeros(6)
        self._ki = np.zeros(6)
        self.set_gains(kp, ki)
        if restoring is not None and not callable(restoring):
            raise InputError(f"restoring: expected a callable restoring(q) -> (6,), got "
                             f"{type(restoring).__name__}")
        self.restoring = restoring
        if linear_damping is None and quadratic_damping is not None:
            raise InputError("quadratic_damping: given without linear_damping (pass zeros)")
        self._damping: tuple[FloatArray, FloatArray] | None = None
        if linear_damping is not None:
            dl = as_vector(linear_damping, "linear_damping", 6).copy()
            dq = (np.zeros(6) if quadratic_damping is None
                  else as_vector(quadratic_damping, "quadratic_damping", 6).copy())
            for name, array in (("linear_damping", dl), ("quadratic_damping", dq)):
                if array.min() < 0.0:
                    j = int(np.argmin(array))
                    raise InputError(f"{name}: expected magnitudes >= 0, got {array[j]:g} on "
                                     f"DOF {NU_NAMES[j]}")
            self._damping = (dl * self._mask, dq * self._mask)
        self._integral = np.zeros(6)
        self._error = np.zeros(6)

    @classmethod
    def for_body(cls, mass: float, inertia: Any, added_mass: Any, linear_damping: Any, *,
                 dt: float, quadratic_damping: Any = None, actuated: Sequence[str] | None = None,
                 restoring: Restoring | None = None, layout: Any = None,
                 bandwidth: Any = DEFAULT_BANDWIDTH,
                 damping_ratio: Any = DEFAULT_DAMPING_RATIO,
                 damping_feedforward: bool = True, kp: Any = None,
                 ki: Any = None) -> VelocityLoop:
        """A loop with gains placed on a vehicle's body parameters (the defaults' recipe).

        Args:
            mass: Vehicle mass [kg].
            inertia: Rotational inertia about the body axes (3,) or (3, 3) [kg m^2] (its
                diagonal is used).
            added_mass: Added mass (6, 6) or its diagonal (6,) [kg, kg m^2] (magnitudes).
            linear_damping: ``D_l`` (6,) (magnitudes) for the gains and the feed-forward.
            dt: Loop period [s].
            quadratic_damping: ``D_q`` (6,) for the feed-forward (default zeros).
            actuated: Controlled DOFs (default: the layout's, else all six).
            restoring: ``restoring(q) -> (6,)`` fed forward (see the class).
            layout: A :class:`~uvms_qp.dynamics.ThrusterLayout`: bounds the integral terms by the
                largest wrench per DOF it can give.
            bandwidth: Closed-loop natural frequency [rad/s] (one or (6,)).
            damping_ratio: Closed-loop damping ratio (one or (6,)).
            damping_feedforward: Feed the damping at the reference (relative to the water
                when :meth:`step` is told it) forward.
            kp: Proportional gains (6,) to use instead of the placed ones (None: placed).
            ki: Integral gains (6,) to use instead of the placed ones (None: placed). With both
                given, no gain is placed (a vehicle the recipe does not suit still gets a loop).

        Raises:
            InputError: the placement fails for a DOF (its own damping faster than the
                bandwidth: give ``kp`` and ``ki``), or a bad argument (named).
        """
        if kp is None or ki is None:
            rotational = _diagonal(inertia, "inertia", 3)
            rigid = np.array([*([as_scalar(mass, "mass", positive=True)] * 3), *rotational])
            total = rigid + np.abs(_diagonal(added_mass, "added_mass"))
            placed = pole_placement_gains(total, linear_damping, bandwidth=bandwidth,
                                          damping_ratio=damping_ratio)
            kp = placed[0] if kp is None else kp
            ki = placed[1] if ki is None else ki
        limit = None
        if layout is not None:
            limit = np.maximum(-np.asarray(layout.wrench_lower), np.asarray(layout.wrench_upper))
            limit = np.where(limit > 0.0, limit, math.inf)
            if actuated is None:
                actuated = layout.actuated
        return cls(kp, ki, dt=dt, actuated=actuated, restoring=restoring,
                   linear_damping=linear_damping if damping_feedforward else None,
                   quadratic_damping=quadratic_damping if damping_feedforward else None,
                   integral_limit=limit)

    # --- gains and state --------------------------------------------------------------------

    @property
    def kp(self) -> FloatArray:
        """Proportional gains (6,) (a copy)."""
        return self._kp.copy()

    @property
    def ki(self) -> FloatArray:
        """Integral gains (6,) (a copy)."""
        return self._ki.copy()

    def set_gains(self, kp: Any, ki: Any) -> None:
        """Replace both gain vectors (6,) (all or nothing); the integral is kept.

        Raises:
            InputError: a gain that is negative, NaN or inf (the message names the DOF).
        """
        new = []
        for name, value in (("kp", kp), ("ki", ki)):
            gains = as_vector(value, name, 6)
            if gains.min() < 0.0:
                j = int(np.argmin(gains))
                raise InputError(f"{name}: expected gains >= 0, got {gains[j]:g} on DOF "
                                 f"{NU_NAMES[j]}")
            new.append(gains)
        self._kp[:] = new[0]
        self._ki[:] = new[1]
        positive = self._ki > 0.0  # where ki = 0, I stays 0
        self._bound[:] = 0.0
        self._bound[positive] = self._integral_limit[positive] / self._ki[positive]

    @property
    def integral(self) -> FloatArray:
        """The integral of the velocity error per DOF [m, rad] (6,) (a copy)."""
        return self._integral.copy()

    @property
    def last_error(self) -> FloatArray:
        """The latest velocity error ``nu_ref - nu`` (6,), 0 on passive DOFs (a copy)."""
        return self._error.copy()

    def reset(self) -> None:
        """Clear the integral and the last error."""
        self._integral[:] = 0.0
        self._error[:] = 0.0

    # --- the step ---------------------------------------------------------------------------

    def step(self, nu_ref: Any, nu: Any, q: Any = None, unmet: Any = None,
             water: Any = None) -> FloatArray:
        """The body wrench to demand this period [N, N m] (6,), zero on passive DOFs.

        Args:
            nu_ref: Reference body velocity (6,) [m/s, rad/s] (from the kinematic layer; its
                passive entries are ignored).
            nu: Measured body velocity (6,).
            q: Configuration passed to ``restoring`` (required when it is set).
            unmet: The unmet wrench of the previous allocation (6,) [N, N m]
                (:attr:`Allocation.unmet`); None: nothing unmet. A DOF whose unmet component
                (beyond :data:`UNMET_TOLERANCE`) has the sign of its error does not integrate.
            water: The water's twist in the body frame (FRD) ``nu_c`` (6,) [m/s, rad/s]
                (:meth:`~uvms_qp.dynamics.FloatingPlant.water_velocity`): the damping is fed
                forward at ``nu_ref - nu_c``; None: the loop is not told the current (still
                water assumed, ``nu_c = 0``).

        Raises:
            ShapeError, NonFiniteError: a vector that is not 6 finite numbers (named).
            InputError: ``q`` missing while ``restoring`` is set, or ``restoring`` returned
                something other than 6 finite numbers.
        """
        reference = as_vector(nu_ref, "nu_ref", 6)
        measured = as_vector(nu, "nu", 6)
        mask = self._mask
        error = (reference - measured) * mask
        self._error = error
        advance = error * self.dt
        if unmet is not None:
            short = as_vector(unmet, "unmet", 6)
            held = (np.abs(short) > UNMET_TOLERANCE) & (short * error > 0.0)
            advance[held] = 0.0
        integral = self._integral
        integral += advance
        # the integral term ki I within the integral limit (DOFs with ki = 0 keep I = 0)
        bound = self._bound
        np.minimum(integral, bound, out=integral)
        np.maximum(integral, -bound, out=integral)
        wrench = self._kp * error + self._ki * integral
        if self.restoring is not None:
            if q is None:
                raise InputError("q: required to feed the restoring wrench forward")
            g = as_vector(self.restoring(q), "restoring(q)", 6)
            wrench += g * mask
        if self._damping is not None:
            dl, dq = self._damping  # zero on passive DOFs
            relative = reference if water is None else reference - as_vector(water, "water", 6)
            wrench += (dl + dq * np.abs(relative)) * relative
        return wrench
