"""Independent references for the floating plant's tests.

Nothing here calls the plant: each quantity is written from its textbook definition.

- :class:`FossenVehicle`: Fossen's 6-DOF equations of one rigid vehicle, written out in the
  book's matrices (Fossen (2011), Chapters 2-4 and 6-8): Euler-angle kinematics ``eta_dot =
  J(eta) nu``, ``M_RB`` and ``C_RB`` about a body origin away from the centre of gravity,
  ``C_A`` by Theorem 3.2, diagonal linear + quadratic damping, the restoring vector ``g(eta)``
  and an irrotational current, for ``scipy.integrate.solve_ivp``.
- Sums over bodies (:func:`bodies`): each body's world placement and body twist from Pinocchio's
  forward kinematics (kinematics only), its 6x6 rigid inertia from the parameters, then momentum,
  kinetic and potential energy and the restoring wrench as plain sums.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from uvms_qp.dynamics import BodyParameters, FloatingPlant, PlantParameters
from uvms_qp.model import Model


def skew(a: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def rigid_inertia(body: BodyParameters) -> np.ndarray:
    """``M_RB`` at the body origin (Fossen (2011), Section 3.3)."""
    m, S = body.mass, skew(body.centre_of_gravity)
    return np.block([[m * np.eye(3), -m * S], [m * S, body.inertia - m * S @ S]])


def rotation_rpy(phi: float, theta: float, psi: float) -> np.ndarray:
    cf, sf, ct, st, cp, sp = (math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta),
                              math.cos(psi), math.sin(psi))
    Rx = np.array([[1, 0, 0], [0, cf, -sf], [0, sf, cf]])
    Ry = np.array([[ct, 0, st], [0, 1, 0], [-st, 0, ct]])
    Rz = np.array([[cp, -sp, 0], [sp, cp, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def neutral_vehicle_only(params: PlantParameters, *, balanced: bool = True,
                         damping: bool = True) -> PlantParameters:
    """The vehicle alone (massless, volumeless links), neutrally buoyant (``rho V = m``).

    ``balanced``: centre of buoyancy at the centre of gravity (no restoring moment).
    """
    v = params.vehicle
    vehicle = BodyParameters(
        v.mass, v.inertia, v.centre_of_gravity, v.mass / params.water_density,
        v.centre_of_gravity if balanced else v.centre_of_buoyancy, v.added_mass,
        v.linear_damping if damping else np.zeros(6),
        v.quadratic_damping if damping else np.zeros(6), "test")
    empty = BodyParameters(0.0, np.zeros(3), np.zeros(3), 0.0, np.zeros(3), np.zeros(6),
                           np.zeros(6), np.zeros(6), "test")
    return params.with_changes(vehicle=vehicle, links={k: empty for k in params.links})


def neutral_links(params: PlantParameters) -> PlantParameters:
    """Every body neutrally buoyant with its centre of buoyancy at its centre of gravity."""
    def neutral(b: BodyParameters) -> BodyParameters:
        return BodyParameters(b.mass, b.inertia, b.centre_of_gravity,
                              b.mass / params.water_density, b.centre_of_gravity, b.added_mass,
                              b.linear_damping, b.quadratic_damping, "test")
    return params.with_changes(vehicle=neutral(params.vehicle),
                               links={k: neutral(b) for k, b in params.links.items()})


@dataclass
class FossenVehicle:
    """Fossen's vehicle model: ``M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r +
    D(nu_r) nu_r + g(eta) = tau`` with ``nu_r = nu - [R^T V_c; 0]`` (constant ``V_c``)."""

    body: BodyParameters
    water_density: float
    gravity: float
    wrench: np.ndarray
    current: np.ndarray

    def __post_init__(self) -> None:
        b = self.body
        self.m = b.mass
        self.rg = np.array(b.centre_of_gravity)
        self.rb = np.array(b.centre_of_buoyancy)
        self.W = b.mass * self.gravity
        self.B = self.water_density * self.gravity * b.volume
        self.Io = b.inertia - self.m * skew(self.rg) @ skew(self.rg)
        self.M_RB = np.block([[self.m * np.eye(3), -self.m * skew(self.rg)],
                              [self.m * skew(self.rg), self.Io]])
        self.M_A = np.array(b.added_mass)
        self.M_inv = np.linalg.inv(self.M_RB + self.M_A)

    def C_RB(self, nu: np.ndarray) -> np.ndarray:
        """Fossen (2011), Section 3.3: the parametrization independent of linear velocity."""
        w = nu[3:]
        m, Sr = self.m, skew(self.rg)
        return np.block([[m * skew(w), -m * skew(w) @ Sr],
                         [m * Sr @ skew(w), -skew(self.Io @ w)]])

    def C_A(self, nu: np.ndarray) -> np.ndarray:
        """Fossen (2011), Theorem 3.2 applied to ``M_A``."""
        A = self.M_A
        a1 = A[:3, :3] @ nu[:3] + A[:3, 3:] @ nu[3:]
        a2 = A[3:, :3] @ nu[:3] + A[3:, 3:] @ nu[3:]
        return np.block([[np.zeros((3, 3)), -skew(a1)], [-skew(a1), -skew(a2)]])

    def restoring(self, phi: float, theta: float) -> np.ndarray:
        """Fossen (2011), Chapter 4: ``g(eta)`` of a submerged body."""
        W, B = self.W, self.B
        (xg, yg, zg), (xb, yb, zb) = self.rg, self.rb
        sf, cf, st, ct = math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta)
        return np.array([
            (W - B) * st,
            -(W - B) * ct * sf,
            -(W - B) * ct * cf,
            -(yg * W - yb * B) * ct * cf + (zg * W - zb * B) * ct * sf,
            (zg * W - zb * B) * st + (xg * W - xb * B) * ct * cf,
            -(xg * W - xb * B) * ct * sf - (yg * W - yb * B) * st,
        ])

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        eta, nu = y[:6], y[6:]
        phi, theta, psi = eta[3:]
        R = rotation_rpy(phi, theta, psi)
        sf, cf, ct, tt = math.sin(phi), math.cos(phi), math.cos(theta), math.tan(theta)
        T = np.array([[1, sf * tt, cf * tt], [0, cf, -sf], [0, sf / ct, cf / ct]])
        vc = R.T @ self.current
        nu_c = np.concatenate((vc, np.zeros(3)))
        nu_c_dot = np.concatenate((-np.cross(nu[3:], vc), np.zeros(3)))
        nu_r = nu - nu_c
        d = self.body.linear_damping + self.body.quadratic_damping * np.abs(nu_r)
        rhs = (self.wrench - self.C_RB(nu) @ nu - self.C_A(nu_r) @ nu_r - d * nu_r
               - self.restoring(phi, theta) + self.M_A @ nu_c_dot)
        return np.concatenate((R @ nu[:3], T @ nu[3:], self.M_inv @ rhs))


def coriolis_theorem_3_2(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """``C(nu) nu`` of a symmetric 6x6 ``M`` by Fossen (2011), Theorem 3.2."""
    a1 = M[:3, :3] @ nu[:3] + M[:3, 3:] @ nu[3:]
    a2 = M[3:, :3] @ nu[:3] + M[3:, 3:] @ nu[3:]
    C = np.block([[np.zeros((3, 3)), -skew(a1)], [-skew(a1), -skew(a2)]])
    return C @ nu


@dataclass
class LockedUVMS:
    """The UVMS with its joints held: one rigid body whose parts each keep their own hydrodynamics.

    ``M_RB = sum X_i^T M_RB,i X_i`` and ``M_A = sum X_i^T M_A,i X_i`` with ``X_i`` the motion
    transform from the vehicle frame to body ``i`` (from the held joints), Coriolis terms by
    Theorem 3.2 of each composite matrix, damping ``sum X_i^T D_i(X_i nu_r) X_i nu_r``, the
    restoring vector from every weight and buoyancy, Euler-angle kinematics.
    """

    model: Model
    params: PlantParameters
    joints: np.ndarray
    wrench: np.ndarray
    current: np.ndarray

    def __post_init__(self) -> None:
        q = self.model.configuration(np.zeros(6), self.joints)
        data = kinematics(self.model, q, np.zeros(self.model.pin_model.nv))
        self.parts = []
        self.M_RB = np.zeros((6, 6))
        self.M_A = np.zeros((6, 6))
        self.loads = []  # (point in the vehicle frame, world force) of each weight and buoyancy
        g, rho = self.params.gravity, self.params.water_density
        for jid, body in bodies(self.model, self.params):
            M = data.oMi[jid]                    # body i in the vehicle frame (vehicle at I)
            X = M.inverse().action               # vehicle twist -> body i twist
            self.parts.append((X, body))
            self.M_RB += X.T @ rigid_inertia(body) @ X
            self.M_A += X.T @ body.added_mass @ X
            self.loads.append((M.rotation @ body.centre_of_gravity + M.translation,
                               np.array([0.0, 0.0, body.mass * g])))
            self.loads.append((M.rotation @ body.centre_of_buoyancy + M.translation,
                               np.array([0.0, 0.0, -rho * g * body.volume])))
        self.M_inv = np.linalg.inv(self.M_RB + self.M_A)

    def restoring(self, R: np.ndarray) -> np.ndarray:
        """``g(eta)``: minus the body wrench of every weight and buoyancy."""
        total = np.zeros(6)
        for point, force in self.loads:
            f = R.T @ force
            total += np.concatenate((f, np.cross(point, f)))
        return -total

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        eta, nu = y[:6], y[6:]
        phi, theta, psi = eta[3:]
        R = rotation_rpy(phi, theta, psi)
        sf, cf, ct, tt = math.sin(phi), math.cos(phi), math.cos(theta), math.tan(theta)
        T = np.array([[1, sf * tt, cf * tt], [0, cf, -sf], [0, sf / ct, cf / ct]])
        vc = R.T @ self.current
        nu_r = nu - np.concatenate((vc, np.zeros(3)))
        nu_c_dot = np.concatenate((-np.cross(nu[3:], vc), np.zeros(3)))
        damping = np.zeros(6)
        for X, body in self.parts:
            rel = X @ nu_r
            damping += X.T @ ((body.linear_damping + body.quadratic_damping * np.abs(rel)) * rel)
        rhs = (self.wrench - coriolis_theorem_3_2(self.M_RB, nu)
               - coriolis_theorem_3_2(self.M_A, nu_r) - damping - self.restoring(R)
               + self.M_A @ nu_c_dot)
        return np.concatenate((R @ nu[:3], T @ nu[3:], self.M_inv @ rhs))


# --- sums over the bodies of the whole chain --------------------------------------------------

def bodies(model: Model, params: PlantParameters) -> list[tuple[int, BodyParameters]]:
    """``(Pinocchio joint id, parameters)`` of the vehicle and each link."""
    pm = model.pin_model
    return [(1, params.vehicle),
            *((int(pm.getJointId(j)), params.links[j]) for j in model.joint_names)]


def kinematics(model: Model, q: np.ndarray, v: np.ndarray) -> pin.Data:
    data = model.pin_model.createData()
    pin.forwardKinematics(model.pin_model, data, q, v)
    return data


def world_momentum(model: Model, params: PlantParameters, q: np.ndarray,
                   v: np.ndarray) -> np.ndarray:
    """``sum_i X_i^* (M_RB,i + M_A,i) V_i``: world force and moment about the world origin."""
    data = kinematics(model, q, v)
    total = np.zeros(6)
    for jid, body in bodies(model, params):
        local = (rigid_inertia(body) + body.added_mass) @ data.v[jid].vector
        R, p = data.oMi[jid].rotation, data.oMi[jid].translation
        f = R @ local[:3]
        total += np.concatenate((f, np.cross(p, f) + R @ local[3:]))
    return total


def kinetic_energy(model: Model, params: PlantParameters, q: np.ndarray, v: np.ndarray) -> float:
    data = kinematics(model, q, v)
    return sum(0.5 * data.v[j].vector @ (rigid_inertia(b) + b.added_mass) @ data.v[j].vector
               for j, b in bodies(model, params))


def potential_energy(model: Model, params: PlantParameters, q: np.ndarray) -> float:
    """``sum(-m g z_G + rho g V z_B)``, world z down."""
    data = kinematics(model, q, np.zeros(model.pin_model.nv))
    g, rho = params.gravity, params.water_density
    total = 0.0
    for jid, body in bodies(model, params):
        M = data.oMi[jid]
        z_g = (M.rotation @ body.centre_of_gravity + M.translation)[2]
        z_b = (M.rotation @ body.centre_of_buoyancy + M.translation)[2]
        total += -body.mass * g * z_g + rho * g * body.volume * z_b
    return total


def world_forces(model: Model, params: PlantParameters, q: np.ndarray
                 ) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(world point, world force)`` of every weight and buoyancy."""
    data = kinematics(model, q, np.zeros(model.pin_model.nv))
    g, rho = params.gravity, params.water_density
    out = []
    for jid, body in bodies(model, params):
        M = data.oMi[jid]
        out.append((M.rotation @ body.centre_of_gravity + M.translation,
                    np.array([0.0, 0.0, body.mass * g])))
        out.append((M.rotation @ body.centre_of_buoyancy + M.translation,
                    np.array([0.0, 0.0, -rho * g * body.volume])))
    return out


def restoring_wrench(model: Model, params: PlantParameters, q: np.ndarray) -> np.ndarray:
    """Minus the body wrench (FRD, at the vehicle origin) of every weight and buoyancy."""
    data = kinematics(model, q, np.zeros(model.pin_model.nv))
    R, p = data.oMi[1].rotation, data.oMi[1].translation
    total = np.zeros(6)
    for point, force in world_forces(model, params, q):
        f = R.T @ force
        total += np.concatenate((f, np.cross(R.T @ (point - p), f)))
    return -total


# --- a run loop ------------------------------------------------------------------------------

def run(plant: FloatingPlant, q, v, duration: float, *, wrench=None, reference=None,
        dt: float | None = None, t0: float = 0.0, observe=None):
    """Step the plant for ``duration`` s with constant inputs; ``observe(t, q, v)`` after each."""
    h = plant.physics_step if dt is None else dt
    wrench = np.zeros(6) if wrench is None else np.asarray(wrench, dtype=float)
    reference = np.zeros(plant.n_joints) if reference is None else reference
    n = round(duration / h)
    t = t0
    for k in range(n):
        ref = reference(t) if callable(reference) else reference
        q, v = plant.step(q, v, wrench, ref, t, h)
        t = t0 + (k + 1) * h
        if observe is not None:
            observe(t, q, v)
    return q, v
