"""Independent reference computations shared by the task tests (plain numpy, no fast paths)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

_PIN_VELOCITY = {"spatial": "uvwpqr", "planar": "uvr", "fixed": ""}


def reference_manipulability(J6, rows):
    """``w = sqrt(det(J_S J_S^T))`` and ``dw/dq_i = w trace(dJ_S/dq_i J_S^+)``.

    Soylu et al. (2007), Eq. (18)-(19), with the columns' derivatives of a serial arm's
    twist Jacobian ``J6 = [V; W]`` (arm-base axes): joint ``i`` moves the columns after it.

    Args:
        J6: Twist Jacobian (6, n) of the arm.
        rows: Selected rows ``S`` (any sequence of indices).
    """
    rows = list(rows)
    Js = J6[rows]
    k, n = Js.shape
    G = Js @ Js.T if k <= n else Js.T @ Js
    w = math.sqrt(max(np.linalg.det(G), 0.0))
    pinv = np.linalg.pinv(Js)
    V, W = J6[:3], J6[3:]
    grad = np.zeros(n)
    for i in range(n):
        dJ = np.zeros((6, n))
        for j in range(n):
            if i <= j:  # joint i moves the columns after it
                dJ[:3, j] = np.cross(W[:, i], V[:, j])
                dJ[3:, j] = np.cross(W[:, i], W[:, j])
            else:
                dJ[:3, j] = np.cross(W[:, j], V[:, i])
        grad[i] = w * np.trace(dJ[rows] @ pinv)
    return w, grad


class Ref:
    """Kinematics of one configuration straight from Pinocchio (fresh Data) and numpy."""

    def __init__(self, model, q):
        self.model = model
        pm = model.pin_model
        data = pm.createData()
        pin.computeJointJacobians(pm, data, q)
        pin.updateFramePlacements(pm, data)
        self.pm, self.data, self.q = pm, data, q
        order = _PIN_VELOCITY[model.vehicle_kind]
        nvp = len(order)
        self.cols = [order.index(a) for a in model.actuated] + [
            nvp + j for j in range(model.n_joints)]
        self.joints = q[model.nq_vehicle:]
        self.eta = self._eta()

    def pose(self, frame):
        return self.data.oMf[self.model.frame_id(frame)].homogeneous.copy()

    def jacobian(self, frame):
        J = pin.getFrameJacobian(self.pm, self.data, self.model.frame_id(frame),
                                 pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        return J[:, self.cols]

    def arm_jacobian(self, frame="tool"):
        """Twist of ``frame`` over the joint rates, vehicle still, in arm-base axes."""
        R = self.pose("arm_base")[:3, :3]
        J = self.jacobian(frame)[:, self.model.n_vehicle:]
        return np.vstack([R.T @ J[:3], R.T @ J[3:]])

    def _eta(self):
        kind, q = self.model.vehicle_kind, self.q
        if kind == "spatial":
            R = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
            return np.concatenate([q[:3], pin.rpy.matrixToRpy(R)])
        if kind == "planar":
            return np.array([q[0], q[1], math.atan2(q[3], q[2])])
        return np.zeros(0)

    def eta_jacobian(self):
        """Fossen's ``J_eta`` over zeta (actuated vehicle columns; joint columns zero)."""
        m, eta = self.model, self.eta
        if m.vehicle_kind == "fixed":
            return np.zeros((0, m.nv))
        if m.vehicle_kind == "planar":
            c, s = math.cos(eta[2]), math.sin(eta[2])
            full = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        else:
            phi, theta, psi = eta[3:]
            sp, cp, ct, tt = math.sin(phi), math.cos(phi), math.cos(theta), math.tan(theta)
            T = np.array([[1.0, sp * tt, cp * tt], [0.0, cp, -sp], [0.0, sp / ct, cp / ct]])
            full = np.zeros((6, 6))
            full[:3, :3] = pin.rpy.rpyToMatrix(phi, theta, psi)
            full[3:, 3:] = T
        order = _PIN_VELOCITY[m.vehicle_kind]
        J = np.zeros((m.eta_size, m.nv))
        J[:, : m.n_vehicle] = full[:, [order.index(a) for a in m.actuated]]
        return J




def target_frame_jacobian(model, q, reference, T_local):
    """Pose and world-axes Jacobian over zeta of a frame fixed at ``T_local`` in ``reference``.

    Built on a copy of the Pinocchio model with one more frame, so it shares no code with the
    task's relative rows.
    """
    pm = pin.Model(model.pin_model)
    parent = pm.frames[model.frame_id(reference)]
    placement = parent.placement * pin.SE3(T_local[:3, :3], T_local[:3, 3])
    fid = pm.addFrame(pin.Frame("oracle_target", parent.parentJoint, model.frame_id(reference),
                                placement, pin.FrameType.OP_FRAME))
    data = pm.createData()
    pin.computeJointJacobians(pm, data, q)
    pin.updateFramePlacements(pm, data)
    order = _PIN_VELOCITY[model.vehicle_kind]
    cols = [order.index(a) for a in model.actuated] + [len(order) + j
                                                       for j in range(model.n_joints)]
    J = pin.getFrameJacobian(pm, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:, cols]
    return data.oMf[fid].homogeneous.copy(), J
