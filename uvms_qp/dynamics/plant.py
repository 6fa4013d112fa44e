"""The floating plant: the whole UVMS in water, Fossen's model extended to the arm's chain.

Generalized velocity ``v = [nu; qd]``: the vehicle's body twist ``nu = [u, v, w, p, q, r]`` (FRD
body axes, at the vehicle frame origin; Pinocchio's free-flyer velocity) and the arm's joint rates.
With ``J_i`` the body-frame Jacobian of body ``i`` (the vehicle, then each link in its joint frame)
and ``V_i = J_i v`` its twist, the equations of motion are (``docs/dynamics.md``)::

    M(q) vdot + h(q, v, t) = [tau_v; tau_q]
    M(q) = M_RB(q) + sum_i J_i^T MA_i J_i
    h    = C_RB(q, v) v + g_W(q) + g_B(q, t)
           + sum_i J_i^T [ MA_i (Jdot_i v - d/dt nu_c,i) + nu_r,i x* (MA_i nu_r,i)
                           + (D_l,i + D_q,i |nu_r,i|) nu_r,i ]

- ``M_RB``, ``C_RB v`` and the weight's ``g_W`` of the whole chain: Pinocchio (CRBA, RNEA) with
  each body's mass at its centre of gravity and gravity ``+g`` along world z (NED).
- Added mass ``MA_i`` (6x6 at the body origin) enters the mass matrix exactly; its bias is
  Kirchhoff's ``MA nu_r_dot + nu_r x* MA nu_r`` on the velocity relative to the water (Fossen
  (2011), Chapter 6 and Theorem 3.2: ``C_A(nu_r) nu_r`` written with the spatial force cross
  product ``[v; w] x* [f; n] = [w x f; v x f + w x n]``).
- ``nu_c,i = [R_i^T V_c; 0]``: the uniform current seen in body ``i``; its body-frame derivative
  ``R_i^T dV_c/dt - w_i x R_i^T V_c``; ``nu_r,i = V_i - nu_c,i``.
- ``g_B``: buoyancy ``rho g V_i`` up at each centre of buoyancy, plus the pressure gradient of an
  accelerating current, ``rho V_i dV_c/dt`` (Froude-Krylov), at the same point.
- Damping, diagonal at each body origin, on the relative velocity.

Inputs: the vehicle wrench ``tau_v`` (body FRD, at the body origin [N, N m]; what thrusters
produce) and the arm's joint velocity references. The joints are motion-driven by first-order
velocity servos, ``qdd = (reference - qd) / tau_servo``, so the unknowns are the vehicle's six
accelerations: ``M_vv nu_dot = tau_v - h_v - M_vq qdd``; the joint rows give the torques the
servos must produce.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray
from scipy.linalg import lapack

from .._validation import as_scalar, as_time, as_vector
from ..errors import InputError, ModelError, PlantDataError, SimulationDiverged
from ..model import Model
from .bundled import default_plant_parameters, plant_parameters
from .current import Current, as_current
from .parameters import BodyParameters, PlantParameters

FloatArray = NDArray[np.float64]

#: Default physics step [s] (``docs/dynamics.md``, section "Integrator": accuracy and cost).
DEFAULT_STEP = 0.005
#: Sanity bounds on the state: vehicle linear speed per axis [m/s] (13x the BlueROV2's top speed),
#: vehicle angular rate per axis [rad/s], joint rate [rad/s] (100x the Alpha 5's limit). A step
#: that ends beyond them (or non-finite) raises :class:`~uvms_qp.errors.SimulationDiverged`.
DEFAULT_SPEED_BOUNDS = (20.0, 30.0, 50.0)

_F64 = np.dtype(np.float64)
_LOCAL = pin.ReferenceFrame.LOCAL
# cyclic permutations of each 3-vector of an (n, 3) array, for cross products
_P1 = np.array([1, 2, 0])
_P2 = np.array([2, 0, 1])


@dataclass(frozen=True)
class Payload:
    """A payload held at the tool: a small solid sphere of uniform density.

    Attributes:
        mass: [kg]. volume: Displaced volume [m^3].
        offset: Its centre in the tool frame [m] (3,).
    """

    mass: float
    volume: float
    offset: tuple[float, float, float]

    def body(self, water_density: float) -> tuple[pin.Inertia, float, FloatArray]:
        """Its rigid inertia about its centre, buoyant mass ``rho V`` and added mass (6x6)."""
        radius = (3.0 * self.volume / (4.0 * math.pi)) ** (1.0 / 3.0)
        inertia = pin.Inertia(self.mass, np.zeros(3), np.eye(3) * 0.4 * self.mass * radius ** 2)
        added = np.zeros((6, 6))
        added[:3, :3] = np.eye(3) * 0.5 * water_density * self.volume  # sphere: half rho V
        return inertia, water_density * self.volume, added


def _vector(value: Any, name: str, n: int) -> FloatArray:
    """A finite float64 vector of length n (no copy when it already is one)."""
    if (type(value) is np.ndarray and value.dtype is _F64 and value.shape == (n,)
            and math.isfinite(value.dot(value))):
        return value
    return as_vector(value, name, n)


def _spatial_force_cross_tensor(inertia: FloatArray) -> FloatArray:
    """``T`` (6, 36) with ``T @ outer(nu, nu).ravel() = nu x* (inertia @ nu)``."""
    T = np.zeros((6, 6, 6))
    for j in range(6):
        e = np.zeros(6)
        e[j] = 1.0
        cross = pin.Motion(e).action.T * -1.0  # ad(e)^T = -crf(e): crf(e) = -ad(e)^T
        T[:, j, :] = cross @ inertia
    return T.reshape(6, 36)


class FloatingPlant:
    """The UVMS as a floating multibody in water (module docstring: the equations).

    Args:
        model: A model with a spatial (free-flyer) vehicle; the plant works on a copy of its
            Pinocchio model (same frames, joints, names).
        parameters: A :class:`PlantParameters`, the name of a bundled set, or None for the
            model's default set.
        current: None (still water), a world velocity (3,) [m/s], a
            :class:`~uvms_qp.dynamics.current.Current` or a callable ``t -> velocity``.
        step: Default physics step [s] of :meth:`step`.
        speed_bounds: Sanity bounds ``(vehicle linear [m/s], vehicle angular [rad/s], joint
            [rad/s])`` per component.

    Attributes:
        model: The kinematic model. parameters: The parameter set in use.
        nq: Configuration size (Pinocchio's: position, unit quaternion, joints).
        nv: Generalized velocity size, ``6 + n_joints`` (every vehicle DOF, passive or not).
        physics_step: Default physics step [s] of :meth:`step`.
        payload: The attached :class:`Payload` or None.
        joint_torques: The servos' joint torques [N m] (n_joints,) at the start of the latest
            :meth:`step` (its first stage: the state and inputs it was given), zeros before any.

    Raises:
        PlantDataError: the model has no default parameters, or the parameters lack a link for
            one of its joints (or name a joint it does not have).
        ModelError: the vehicle is planar or fixed.
    """

    def __init__(self, model: Model, parameters: PlantParameters | str | None = None,
                 current: Any = None, *, step: float = DEFAULT_STEP,
                 speed_bounds: tuple[float, float, float] = DEFAULT_SPEED_BOUNDS) -> None:
        if not isinstance(model, Model):
            raise InputError(f"model: expected a Model, got {type(model).__name__}")
        if model.vehicle_kind != "spatial":
            raise ModelError(
                f"model {model.name!r} has a {model.vehicle_kind} vehicle: the floating plant "
                "needs a spatial (free-flyer) vehicle")
        if parameters is None:
            parameters = default_plant_parameters(model)
        elif isinstance(parameters, str):
            parameters = plant_parameters(parameters)
        elif not isinstance(parameters, PlantParameters):
            raise InputError("parameters: expected PlantParameters, a set name or None, got "
                             f"{type(parameters).__name__}")
        missing = [j for j in model.joint_names if j not in parameters.links]
        extra = [j for j in parameters.links if j not in model.joint_names]
        if missing or extra:
            what = []
            if missing:
                what.append(f"no link body for joint(s) {missing}")
            if extra:
                what.append(f"link bodies for unknown joint(s) {extra}")
            raise PlantDataError(
                f"parameters {parameters.name!r} do not fit model {model.name!r}: "
                f"{'; '.join(what)} (the model's joints: {list(model.joint_names)})")
        self.model = model
        self.parameters = parameters
        self.physics_step = as_scalar(step, "step", positive=True)
        bounds = as_vector(speed_bounds, "speed_bounds", 3, positive=True)
        self.speed_bounds = tuple(float(b) for b in bounds)
        self.payload: Payload | None = None
        self.joint_torques = np.zeros(model.n_joints)

        self._pm = pin.Model(model.pin_model)
        self._bm = pin.Model(model.pin_model)  # buoyancy: mass rho V at each centre of buoyancy
        self._data = self._pm.createData()
        self._bdata = self._bm.createData()
        self.nq = int(self._pm.nq)
        self.nv = int(self._pm.nv)
        self.n_joints = model.n_joints
        self._joint_ids = [int(self._pm.getJointId(j)) for j in model.joint_names]
        self._body_ids = [1, *self._joint_ids]  # the vehicle's free-flyer is joint 1
        n = len(self._body_ids)
        self._n_bodies = n
        tool = self._pm.frames[model.frame_id("tool")]
        self._tool_joint = int(tool.parentJoint)
        self._tool_placement = tool.placement
        if self._tool_joint not in self._body_ids:
            raise PlantDataError(f"model {model.name!r}: the tool frame is not on a body")

        # buffers: stacked body Jacobians (vehicle rows constant), Jdot v, current terms
        self._J = np.zeros((6 * n, self.nv))
        self._J[:6, :6] = np.eye(6)
        self._A = np.zeros(6 * n)
        self._links = [(slice(6 * k, 6 * k + 6), jid) for k, jid in enumerate(self._body_ids)
                       if jid != 1]
        self._vcg = np.zeros(self.nv)  # generalized velocity of a rigid translation with the water
        self._acg = np.zeros(self.nv)
        self._zero_nv = np.zeros(self.nv)
        bound = np.empty(self.nv)
        bound[:3], bound[3:6], bound[6:] = self.speed_bounds
        self._bound = bound
        self._inv_tau = 1.0 / parameters.joint_servo_time_constant
        self._gravity = parameters.gravity
        self._pm.gravity = pin.Motion(np.array([0.0, 0.0, parameters.gravity]), np.zeros(3))
        self._buoyancy_field = np.array([0.0, 0.0, -parameters.gravity])
        self._bm.gravity = pin.Motion(self._buoyancy_field.copy(), np.zeros(3))
        self._field_moved = False
        self._current: Current | None = as_current(current)
        self._configure()

    # --- configuration ---------------------------------------------------------------------

    def _bodies(self) -> list[BodyParameters]:
        p = self.parameters
        return [p.vehicle, *(p.links[j] for j in self.model.joint_names)]

    def _configure(self) -> None:
        """Write inertias, buoyant masses and the stacked hydrodynamic matrices."""
        rho = self.parameters.water_density
        n = self._n_bodies
        added = np.zeros((6 * n, 6 * n))
        rigid = np.zeros((6 * n, 6 * n))
        tensor = np.zeros((6 * n, 36 * n))
        linear = np.zeros(6 * n)
        quadratic = np.zeros(6 * n)
        for k, (jid, body) in enumerate(zip(self._body_ids, self._bodies(), strict=True)):
            inertia = pin.Inertia(body.mass, np.array(body.centre_of_gravity),
                                  np.array(body.inertia))
            buoyant = pin.Inertia(rho * body.volume, np.array(body.centre_of_buoyancy),
                                  np.zeros((3, 3)))
            ma = np.array(body.added_mass)
            if jid == self._tool_joint and self.payload is not None:
                p_inertia, p_buoyant, p_added = self.payload.body(rho)
                centre = self._tool_placement * pin.SE3(np.eye(3), np.array(self.payload.offset))
                inertia = inertia + centre.act(p_inertia)
                buoyant = buoyant + pin.Inertia(p_buoyant, centre.translation, np.zeros((3, 3)))
                X = centre.inverse().action  # body-origin twist -> payload-centre twist
                ma = ma + X.T @ p_added @ X
            self._pm.inertias[jid] = inertia
            self._bm.inertias[jid] = buoyant
            rows = slice(6 * k, 6 * k + 6)
            added[rows, rows] = ma
            rigid[rows, rows] = inertia.matrix()
            tensor[rows, 36 * k:36 * k + 36] = _spatial_force_cross_tensor(ma)
            linear[rows] = body.linear_damping
            quadratic[rows] = body.quadratic_damping
        self._added = added
        self._rigid = rigid
        self._tensor = tensor
        self._linear = linear
        self._quadratic = quadratic

    # --- run-time changes ------------------------------------------------------------------

    @property
    def current(self) -> Current | None:
        """The water current (None: still water); settable like the constructor's argument."""
        return self._current

    @current.setter
    def current(self, value: Any) -> None:
        self._current = as_current(value)

    def attach_payload(self, mass: float, volume: float = 0.0,
                       offset: Any = (0.0, 0.0, 0.0)) -> Payload:
        """Attach a payload to the tool (replacing one already held).

        The payload is a uniform solid sphere of the given volume centred at ``offset``: its mass
        and inertia join the tool's link, its buoyancy ``rho g V`` acts at its centre and its
        added mass is a sphere's, ``rho V / 2`` in every direction (no drag of its own).

        Args:
            mass: [kg], >= 0.
            volume: Displaced volume [m^3], >= 0.
            offset: Its centre in the tool frame [m] (3,).

        Returns:
            The attached :class:`Payload`.
        """
        m = as_scalar(mass, "payload mass", nonnegative=True)
        vol = as_scalar(volume, "payload volume", nonnegative=True)
        off = as_vector(offset, "payload offset", 3)
        self.payload = Payload(m, vol, (float(off[0]), float(off[1]), float(off[2])))
        self._configure()
        return self.payload

    def detach_payload(self) -> Payload | None:
        """Release the payload; returns it (None when none was held)."""
        payload, self.payload = self.payload, None
        self._configure()
        return payload

    # --- the dynamics ----------------------------------------------------------------------

    def _kinematics(self, q: FloatArray, v: FloatArray) -> None:
        """Placements, twists, ``Jdot v``, ``M_RB``, ``C_RB v + g_W`` and the body Jacobians."""
        pm, d = self._pm, self._data
        pin.computeAllTerms(pm, d, q, v)
        J, A, a = self._J, self._A, d.a
        for rows, jid in self._links:
            J[rows] = pin.getJointJacobian(pm, d, jid, _LOCAL)
            A[rows] = a[jid].vector

    def _mass_matrix(self) -> FloatArray:
        J = self._J
        return self._data.M + J.T.dot(self._added.dot(J))

    def _bias(self, q: FloatArray, v: FloatArray, t: float) -> FloatArray:
        """``h(q, v, t)`` after :meth:`_kinematics` (module docstring)."""
        J = self._J
        current = self._current
        twists = J.dot(v)
        if current is None:
            relative = twists
            rate = self._A
            if self._field_moved:
                self._bm.gravity.linear = self._buoyancy_field
                self._field_moved = False
        else:
            n = self._n_bodies
            R = self._data.oMi[1].rotation
            self._vcg[:3] = current.velocity(t).dot(R)  # R^T V_c
            water = J.dot(self._vcg)                    # [R_i^T V_c; 0] per body
            relative = twists - water
            w = twists.reshape(n, 6)[:, 3:]
            c = water.reshape(n, 6)[:, :3]
            if current.steady:
                rate = self._A.copy()
                if self._field_moved:
                    self._bm.gravity.linear = self._buoyancy_field
                    self._field_moved = False
            else:
                accel = current.acceleration(t)
                self._acg[:3] = accel.dot(R)
                rate = self._A - J.dot(self._acg)
                self._bm.gravity.linear = self._buoyancy_field + accel
                self._field_moved = True
            # - d/dt nu_c,i includes + w_i x (R_i^T V_c) in the linear rows
            rate.reshape(n, 6)[:, :3] += w[:, _P1] * c[:, _P2] - w[:, _P2] * c[:, _P1]
        outer = (relative.reshape(-1, 6, 1) * relative.reshape(-1, 1, 6)).ravel()
        force = (self._added.dot(rate) + self._tensor.dot(outer)
                 + (self._linear + self._quadratic * np.abs(relative)) * relative)
        buoyancy = pin.computeGeneralizedGravity(self._bm, self._bdata, q)
        return self._data.nle + buoyancy + J.T.dot(force)

    def _accelerations(self, q: FloatArray, v: FloatArray, wrench: FloatArray,
                       reference: FloatArray, t: float) -> tuple[FloatArray, FloatArray]:
        self._kinematics(q, v)
        M = self._mass_matrix()
        h = self._bias(q, v, t)
        qdd = (reference - v[6:]) * self._inv_tau
        rhs = wrench - h[:6] - M[:6, 6:].dot(qdd)
        vdot = np.empty(self.nv)
        _, vdot[:6], info = lapack.dposv(M[:6, :6], rhs)  # Cholesky: M_vv is positive definite
        if info:
            raise SimulationDiverged(
                f"at t = {t:.6g} s the vehicle's mass matrix is not positive definite "
                f"(LAPACK dposv info {info})", t=t, q=q.copy(), v=v.copy(),
                reason="mass matrix not positive definite")
        vdot[6:] = qdd
        torques = M[6:].dot(vdot) + h[6:]
        return vdot, torques

    def _inputs(self, q: Any, v: Any, wrench: Any, reference: Any, t: Any
                ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
        if not (type(q) is np.ndarray and q.dtype is _F64 and q.shape == (self.nq,)
                and math.isfinite(q.dot(q))):
            q = self.model.check_configuration(q)
        return (q, _vector(v, "v", self.nv), _vector(wrench, "wrench", 6),
                _vector(reference, "joint_reference", self.n_joints), as_time(t))

    def accelerations(self, q: Any, v: Any, wrench: Any, joint_reference: Any,
                      t: float = 0.0) -> tuple[FloatArray, FloatArray]:
        """Accelerations and servo torques at one instant.

        Args:
            q: Configuration (nq,): vehicle position [m] (world NED), unit quaternion of
                ``R_world_body``, joint angles [rad].
            v: Generalized velocity (nv,): ``nu`` [m/s, rad/s] (body FRD) and joint rates [rad/s].
            wrench: Vehicle wrench ``[X, Y, Z, K, M, N]`` in body FRD at the body origin
                [N, N m] (6,).
            joint_reference: Joint velocity references of the servos [rad/s] (n_joints,).
            t: Time [s] (for a time-varying current).

        Returns:
            ``(v_dot, joint_torques)``: ``v_dot`` (nv,) = ``[nu_dot [m/s^2, rad/s^2]; qdd
            [rad/s^2]]`` (``nu_dot`` the derivative of the body-frame components), and the
            generalized forces the servos produce at the joints [N m] (n_joints,).
        """
        q, v, wrench, reference, t = self._inputs(q, v, wrench, joint_reference, t)
        vdot, torques = self._accelerations(q, v, wrench, reference, t)
        return vdot, torques

    def step(self, q: Any, v: Any, wrench: Any, joint_reference: Any, t: float = 0.0,
             dt: float | None = None) -> tuple[FloatArray, FloatArray]:
        """Advance the state by one physics step, inputs held constant over it.

        Classical fourth-order Runge-Kutta in the chart of the configuration manifold at ``q``:
        the state is ``(xi, v)`` with ``q(xi) = integrate(q, xi)`` and ``xi_dot =
        dDifference(q, q(xi)) v`` (the inverse of the exponential's differential), so the
        scheme keeps its fourth order on SE(3) (``docs/dynamics.md``, section "Integrator").

        Args:
            q: Configuration (nq,), as in :meth:`accelerations`.
            v: Generalized velocity (nv,) [m/s, rad/s].
            wrench: Vehicle wrench, body FRD at the body origin [N, N m] (6,).
            joint_reference: Joint velocity references [rad/s] (n_joints,).
            t: Time at the step's start [s].
            dt: Step [s] (default :attr:`physics_step`).

        Returns:
            ``(q, v)`` at ``t + dt`` (new arrays).

        Raises:
            SimulationDiverged: the new state is not finite or a velocity exceeds
                :attr:`speed_bounds` (the error keeps ``t``, ``q`` and ``v`` of the step's start).
        """
        q, v, wrench, reference, t = self._inputs(q, v, wrench, joint_reference, t)
        h = self.physics_step if dt is None else as_scalar(dt, "dt", positive=True)
        pm = self._pm
        f = self._accelerations
        a1, self.joint_torques = f(q, v, wrench, reference, t)
        x2 = v * (0.5 * h)
        q2 = pin.integrate(pm, q, x2)
        v2 = v + a1 * (0.5 * h)
        k2 = pin.dDifference(pm, q, q2, pin.ARG1).dot(v2)
        a2, _ = f(q2, v2, wrench, reference, t + 0.5 * h)
        q3 = pin.integrate(pm, q, k2 * (0.5 * h))
        v3 = v + a2 * (0.5 * h)
        k3 = pin.dDifference(pm, q, q3, pin.ARG1).dot(v3)
        a3, _ = f(q3, v3, wrench, reference, t + 0.5 * h)
        q4 = pin.integrate(pm, q, k3 * h)
        v4 = v + a3 * h
        k4 = pin.dDifference(pm, q, q4, pin.ARG1).dot(v4)
        a4, _ = f(q4, v4, wrench, reference, t + h)
        sixth = h / 6.0
        q_new = pin.integrate(pm, q, (v + k4 + 2.0 * (k2 + k3)) * sixth)
        v_new = v + (a1 + a4 + 2.0 * (a2 + a3)) * sixth
        if not ((np.abs(v_new) <= self._bound).all() and math.isfinite(q_new.dot(q_new))):
            self._diverged(t, h, q, v, q_new, v_new)
        pin.normalize(pm, q_new)
        return q_new, v_new

    def _diverged(self, t: float, h: float, q: FloatArray, v: FloatArray, q_new: FloatArray,
                  v_new: FloatArray) -> None:
        names = ("u", "v", "w", "p", "q", "r", *self.model.joint_names)
        bad = np.flatnonzero(~(np.abs(v_new) <= self._bound))
        if bad.size:
            k = int(bad[0])
            reason = (f"velocity {names[k]} = {v_new[k]:.6g} beyond the sanity bound "
                      f"{self._bound[k]:g}")
        else:
            reason = "the configuration is not finite"
        raise SimulationDiverged(
            f"physics step from t = {t:.6g} s (dt {h:g} s) diverged: {reason}; state at the "
            f"step's start: q = {np.array2string(q, precision=4)}, "
            f"v = {np.array2string(v, precision=4)}",
            t=t, q=q.copy(), v=v.copy(), reason=reason)

    # --- quantities for controllers, reports and tests -------------------------------------

    def mass_matrix(self, q: Any) -> FloatArray:
        """Generalized mass matrix with added mass, ``M_RB(q) + sum J_i^T MA_i J_i`` (nv, nv).

        Symmetric; [kg, kg m, kg m^2] by block.
        """
        q = self.model.check_configuration(q)
        self._kinematics(q, self._zero_nv)
        M = self._mass_matrix()
        return 0.5 * (M + M.T)

    def restoring_wrench(self, q: Any) -> FloatArray:
        """Fossen's ``g(eta)`` of the whole UVMS on the vehicle's six DOFs (6,) [N, N m].

        Weight and buoyancy of the vehicle, the links and any payload, with the joints held,
        as they appear on the left-hand side of the equations of motion: the body wrench (FRD, at
        the body origin) the thrusters must produce to hold the UVMS still at ``q`` in still
        water. The weight and buoyancy acting on the vehicle are its negative.
        """
        q = self.model.check_configuration(q)
        weight = pin.computeGeneralizedGravity(self._pm, self._data, q)
        self._bm.gravity.linear = self._buoyancy_field
        self._field_moved = False
        buoyancy = pin.computeGeneralizedGravity(self._bm, self._bdata, q)
        return (weight + buoyancy)[:6].copy()

    def potential_energy(self, q: Any) -> float:
        """Potential of weight and buoyancy [J]: ``sum(-m_i g z_G,i + rho g V_i z_B,i)`` (NED z)."""
        q = self.model.check_configuration(q)
        self._bm.gravity.linear = self._buoyancy_field
        self._field_moved = False
        return float(pin.computePotentialEnergy(self._pm, self._data, q)
                     + pin.computePotentialEnergy(self._bm, self._bdata, q))

    def kinetic_energy(self, q: Any, v: Any) -> float:
        """``v^T M(q) v / 2`` [J]: the bodies' and, in still water, the water's (added mass)."""
        v = _vector(v, "v", self.nv)
        return float(0.5 * v.dot(self.mass_matrix(q).dot(v)))

    def momentum(self, q: Any, v: Any, t: float = 0.0) -> FloatArray:
        """World linear and angular momentum of the whole chain, with added mass (6,).

        ``sum_i X_i^* (I_i V_i + MA_i nu_r,i)``: each body's rigid momentum and the water's
        impulse (Kirchhoff) as world forces ``[N s]`` and moments about the world origin
        ``[N m s]``. Constant in still water without external forces.
        """
        q = self.model.check_configuration(q)
        v = _vector(v, "v", self.nv)
        self._kinematics(q, v)
        twists = self._J.dot(v)
        relative = twists - self._J.dot(self._water_velocity(t))
        local = self._rigid.dot(twists) + self._added.dot(relative)
        total = pin.Force.Zero()
        for k, jid in enumerate(self._body_ids):
            total += self._data.oMi[jid].act(pin.Force(local[6 * k:6 * k + 6]))
        return total.vector.copy()

    def _water_velocity(self, t: float) -> FloatArray:
        out = np.zeros(self.nv)
        if self._current is not None:
            out[:3] = self._current.velocity(as_time(t)).dot(self._data.oMi[1].rotation)
        return out

    def relative_velocity(self, q: Any, v: Any, t: float = 0.0) -> FloatArray:
        """The vehicle's body twist relative to the water, ``nu - [R^T V_c(t); 0]`` (6,)."""
        v = _vector(v, "v", self.nv)
        return v[:6] - self.water_velocity(q, t)

    def water_velocity(self, q: Any, t: float = 0.0) -> FloatArray:
        """The water's twist in the vehicle's body frame (FRD), ``[R^T V_c(t); 0]`` (6,).

        [m/s, rad/s]; zeros in still water. ``q`` sets the vehicle's attitude ``R`` (body to
        NED), ``t`` [s] the time of a varying current.
        """
        q = self.model.check_configuration(q)
        pin.forwardKinematics(self._pm, self._data, q)
        return self._water_velocity(t)[:6]

    def __repr__(self) -> str:
        held = "" if self.payload is None else f", payload {self.payload.mass:g} kg"
        return (f"<FloatingPlant {self.model.name} with {self.parameters.name}, step "
                f"{self.physics_step:g} s{held}>")
