"""The UVMS model: a vehicle joint, an arm chain at a mount transform, and named frames.

Pinocchio holds the kinematic tree: a vehicle joint (free-flyer, planar or none, see
:mod:`uvms_qp.model.vehicle`), the frames ``world``, ``vehicle`` and ``arm_base`` (the mount
``T_vehicle_arm_base``), the arm (from a DH table or a URDF) appended at ``arm_base``, and a
``tool`` frame. The decision vector ``zeta = [actuated vehicle body rates; joint rates]`` selects
columns of Pinocchio's velocity vector; passive vehicle DOFs stay in ``q`` only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validation import as_array, as_scalar, as_vector
from ..errors import (
    InputError,
    ModelError,
    NonFiniteError,
    ShapeError,
    UnknownFrameError,
    UnknownJointError,
)
from .dh import build_dh_arm
from .state import State
from .transforms import as_transform, to_se3
from .urdf import check_path, load_urdf_arm
from .vehicle import ETA_NAMES, Vehicle, check_joint_names, resolve_vehicle

FloatArray = NDArray[np.float64]

#: Frame names every model defines (plus ``world``).
STANDARD_FRAMES: tuple[str, ...] = ("world", "vehicle", "arm_base", "tool")
#: Largest accepted deviation of a unit quaternion's squared norm from 1 before rejection.
QUATERNION_TOLERANCE = 1e-3
_VEHICLE_JOINT = "vehicle_joint"
_F64 = np.dtype(np.float64)


def _unique_frame_names(model: pin.Model) -> None:
    """Rename joint frames that share a link's name (legal in URDF; ambiguous to Pinocchio).

    Links keep their names (they are the model's public frames); a joint frame becomes
    ``"<name>:joint"``. The joint itself keeps its name.
    """
    bodies = {f.name for f in model.frames if f.type == pin.FrameType.BODY}
    for i, frame in enumerate(model.frames):
        if frame.type != pin.FrameType.BODY and frame.name in bodies:
            frame.name = f"{frame.name}:joint"
            model.frames[i] = frame


def _limits(value: Any, default: FloatArray, name: str, n: int) -> FloatArray:
    if value is None:
        return default.astype(np.float64, copy=True)
    return as_vector(value, name, n, allow_inf=True).copy()


class Model:
    """Kinematic model of a vehicle carrying one serial arm.

    Build one with :meth:`from_dh`, :meth:`from_urdf` or :func:`uvms_qp.load_model`.

    Attributes:
        name: Model name.
        nq: Pinocchio configuration size (a spatial vehicle stores a unit quaternion).
        nv: Length of ``zeta`` (actuated vehicle rates + joint rates).
        n_vehicle: Number of actuated vehicle rates (first block of ``zeta``).
        n_joints: Number of arm joints (last block of ``zeta``).
        vehicle_kind: ``"planar"``, ``"spatial"`` or ``"fixed"``.
        actuated: Actuated vehicle rate names in ``nu`` order (planar from ``("u", "v", "r")``).
        passive: Passive vehicle rate names.
        eta_size: Length of the vehicle pose ``eta`` (3 planar, 6 spatial, 0 fixed).
        eta_names: Names of the ``eta`` entries.
        joint_names: Arm joint names in chain order.
        zeta_names: ``actuated + joint_names``.
        frames: Frame names (``world``, ``vehicle``, ``arm_base``, ``tool``, then arm links).
        joint_lower: Lower joint limits [rad] (``-inf`` if none).
        joint_upper: Upper joint limits [rad] (``inf`` if none).
        joint_rate_limit: Symmetric joint rate limits [rad/s] (``inf`` if none).
        vehicle_rate_limit: Symmetric actuated vehicle rate limits [m/s, rad/s] (``inf`` if none).
        mount: ``T_vehicle_arm_base`` (4x4) [m].
        source: Where the model comes from (paper, file).
        pin_model: The underlying Pinocchio model.

    A model keeps a small pool of Pinocchio ``Data`` buffers that its states borrow for their
    lifetime (see :class:`~uvms_qp.model.state.State`).
    """

    def __init__(
        self,
        arm: pin.Model,
        *,
        vehicle: Vehicle,
        mount: FloatArray,
        tool_parent: str,
        tool_offset: FloatArray,
        joint_names: Sequence[str],
        joint_lower: FloatArray,
        joint_upper: FloatArray,
        joint_rate_limit: FloatArray,
        arm_frames: Sequence[str],
        name: str,
        source: str = "",
        home: Any = None,
    ) -> None:
        """Assemble a model from a fixed-base Pinocchio arm (use the ``from_*`` constructors)."""
        self.name = str(name)
        self.source = source
        self.vehicle = vehicle
        self.vehicle_kind: str = vehicle.kind
        self.actuated: tuple[str, ...] = tuple(vehicle.actuated or ())
        self.passive: tuple[str, ...] = vehicle.passive
        self.eta_size = vehicle.eta_size
        self.eta_names: tuple[str, ...] = ETA_NAMES[vehicle.kind]
        self.joint_names = check_joint_names(joint_names, vehicle.dofs)
        self.mount = mount.copy()
        self.mount.flags.writeable = False

        reserved = {*STANDARD_FRAMES, "universe", _VEHICLE_JOINT}
        clash = sorted(reserved & ({f.name for f in arm.frames[1:]} | set(self.joint_names)))
        if clash:
            raise ModelError(f"model {self.name!r}: arm names {clash} are reserved")

        _unique_frame_names(arm)
        base = pin.Model()
        base.name = self.name
        joint = vehicle.pin_joint()
        vjoint = 0 if joint is None else base.addJoint(0, joint, pin.SE3.Identity(), _VEHICLE_JOINT)
        identity = pin.SE3.Identity()
        op = pin.FrameType.OP_FRAME
        base.addFrame(pin.Frame("world", 0, 0, identity, op))
        fveh = base.addFrame(pin.Frame("vehicle", vjoint, 0, identity, op))
        farm = base.addFrame(pin.Frame("arm_base", vjoint, fveh, to_se3(mount), op))
        full = pin.appendModel(base, arm, farm, identity)
        if not full.existFrame(tool_parent):
            known = [f.name for f in full.frames[1:]]
            raise UnknownFrameError(tool_parent, known)
        for tree in (full, arm):  # the tool on the whole model and on the bare arm
            fparent = tree.getFrameId(tool_parent)
            parent = tree.frames[fparent]
            placement = parent.placement * to_se3(tool_offset)
            tree.addFrame(pin.Frame("tool", parent.parentJoint, fparent, placement, op))
        self.pin_model: pin.Model = full
        # Pinocchio buffers lent to states (State takes one and gives it back when collected)
        self._data_pool: list[Any] = []
        # the bare arm (root = arm_base) gives the arm-only Jacobian in arm_base axes directly
        self._arm_model: pin.Model = arm
        self._arm_pool: list[Any] = []

        self.nq = int(full.nq)
        n_pin = int(full.nv)
        self.n_joints = len(self.joint_names)
        if n_pin - vehicle.nv != self.n_joints or full.nq - vehicle.nq != self.n_joints:
            raise ModelError(f"model {self.name!r}: every arm joint must be 1-DOF")
        self.n_vehicle = len(self.actuated)
        self.nv = self.n_vehicle + self.n_joints
        self.zeta_names: tuple[str, ...] = self.actuated + self.joint_names
        self.nq_vehicle = vehicle.nq
        self.nv_vehicle_pin = vehicle.nv
        columns = [*vehicle.actuated_indices, *range(vehicle.nv, n_pin)]
        self._columns = np.array(columns, dtype=np.intp)
        # None = zeta is Pinocchio's whole velocity (no column selection on the hot path)
        self._select: np.ndarray | None = None if len(columns) == n_pin else self._columns
        # vehicle_pose_jacobian: where the entries of J(eta) with an actuated column go in the
        # (eta_size, nv) matrix, and which entries those are (None: all of them)
        act = list(vehicle.actuated_indices)
        pattern = vehicle.pose_jacobian_pattern
        kept = [i for i, (_, c) in enumerate(pattern) if c in act]
        self._eta_dst = np.array([pattern[i][0] * self.nv + act.index(pattern[i][1])
                                  for i in kept], dtype=np.intp)
        self._eta_src: list[int] | None = None if len(kept) == len(pattern) else kept

        self.frames: tuple[str, ...] = STANDARD_FRAMES + tuple(
            f for f in arm_frames if f not in STANDARD_FRAMES
        )
        self._frame_ids: dict[str, int] = {
            f: int(full.getFrameId(f, op if f in STANDARD_FRAMES else pin.FrameType.BODY))
            for f in self.frames
        }
        # frames moved by the arm (others have a zero arm Jacobian); arm_base is the arm's root
        self._arm_frame_ids: dict[str, int] = {"arm_base": 0}
        for f in self.frames:
            if f in ("tool", *arm_frames):
                kind = op if f == "tool" else pin.FrameType.BODY
                self._arm_frame_ids[f] = int(arm.getFrameId(f, kind))

        n = self.n_joints
        self.joint_lower = np.array(joint_lower, dtype=np.float64).reshape(n)
        self.joint_upper = np.array(joint_upper, dtype=np.float64).reshape(n)
        self.joint_rate_limit = np.array(joint_rate_limit, dtype=np.float64).reshape(n)
        self.vehicle_rate_limit = np.array(vehicle.rate_limit, dtype=np.float64)
        for label, arr in (("joint_lower", self.joint_lower), ("joint_upper", self.joint_upper)):
            if np.isnan(arr).any():
                raise ModelError(f"model {self.name!r}: {label} contains NaN")
        bad = np.flatnonzero(self.joint_lower > self.joint_upper)
        if bad.size:
            j = self.joint_names[int(bad[0])]
            raise ModelError(f"model {self.name!r}: joint {j!r} has lower limit > upper limit")
        if np.isnan(self.joint_rate_limit).any() or (self.joint_rate_limit <= 0).any():
            raise ModelError(f"model {self.name!r}: joint_rate_limit must be positive")
        for arr in (
            self.joint_lower,
            self.joint_upper,
            self.joint_rate_limit,
            self.vehicle_rate_limit,
        ):
            arr.flags.writeable = False
        if home is None:
            self._home_joints = np.clip(0.0, self.joint_lower, self.joint_upper)
        else:
            self._home_joints = self._check_joints(home, "home")
            outside = np.flatnonzero(
                (self._home_joints < self.joint_lower) | (self._home_joints > self.joint_upper)
            )
            if outside.size:
                j = self.joint_names[int(outside[0])]
                raise ModelError(
                    f"model {self.name!r}: home angle of joint {j!r} is outside limits"
                )

    # --- constructors --------------------------------------------------------------------

    @classmethod
    def from_dh(
        cls,
        table: Sequence[Any],
        convention: str = "standard",
        *,
        vehicle: Vehicle | str = "spatial",
        mount: Any = None,
        tool: Any = None,
        joint_names: Sequence[str] | None = None,
        joint_lower: Any = None,
        joint_upper: Any = None,
        joint_rate_limit: Any = None,
        home: Any = None,
        name: str = "dh_model",
        source: str = "",
    ) -> Model:
        """Build a model whose arm is given by a Denavit-Hartenberg table.

        Args:
            table: Rows as :class:`~uvms_qp.model.dh.DHRow` or mappings with keys
                ``a, alpha, d, theta`` (and optional ``kind, name, lower, upper, rate_limit``)
                [m, rad]; see :mod:`uvms_qp.model.dh` for both conventions.
            convention: ``"standard"`` or ``"modified"`` (Craig).
            vehicle: A :class:`Vehicle` or ``"planar"``, ``"spatial"``, ``"fixed"``.
            mount: ``T_vehicle_arm_base``: 4x4 matrix, ``{"xyz": ..., "rpy": ...}`` or None
                (identity). The arm base is DH frame 0.
            tool: ``T_flange_tool`` from the last DH frame to the tool (same forms as ``mount``).
            joint_names: Names of the moving joints (override the rows' names).
            joint_lower: Lower joint limits [rad] (override the rows' limits).
            joint_upper: Upper joint limits [rad].
            joint_rate_limit: Joint rate limits [rad/s].
            home: Default joint angles [rad] returned by :meth:`home` (zero clipped to limits).
            name: Model name.
            source: Free text naming where the numbers come from.

        Raises:
            InputError: a malformed row, mount or limit vector.
            ModelError: an inconsistent table (no joint, duplicate names, lower > upper).
        """
        arm = build_dh_arm(table, convention, joint_names)
        n = len(arm.joint_names)
        return cls(
            arm.model,
            vehicle=resolve_vehicle(vehicle),
            mount=as_transform(mount, "mount"),
            tool_parent=arm.flange,
            tool_offset=as_transform(tool, "tool"),
            joint_names=arm.joint_names,
            joint_lower=_limits(joint_lower, arm.lower, "joint_lower", n),
            joint_upper=_limits(joint_upper, arm.upper, "joint_upper", n),
            joint_rate_limit=_limits(joint_rate_limit, arm.rate_limit, "joint_rate_limit", n),
            arm_frames=[f.name for f in arm.model.frames if f.type == pin.FrameType.BODY],
            name=name,
            source=source,
            home=home,
        )

    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        *,
        vehicle: Vehicle | str = "spatial",
        mount: Any = None,
        tool: str | None = None,
        tool_offset: Any = None,
        joint_rate_limit: Any = None,
        home: Any = None,
        name: str | None = None,
        source: str = "",
    ) -> Model:
        """Build a model whose arm is read from a URDF file.

        The URDF's root link is the arm base and keeps its own axes; ``mount`` places it in the
        vehicle FRD body frame (use :func:`~uvms_qp.model.transforms.flu_to_frd` for a mount
        published in ROS FLU body axes).

        Args:
            path: URDF file of the arm (revolute/prismatic joints with limits, fixed joints).
            vehicle: A :class:`Vehicle` or ``"planar"``, ``"spatial"``, ``"fixed"``.
            mount: ``T_vehicle_arm_base`` (4x4, ``{"xyz", "rpy"}`` or None) [m, rad].
            tool: Link carrying the tool frame (default: the single leaf link).
            tool_offset: ``T_link_tool`` from that link to the tool (default identity).
            joint_rate_limit: Override of the URDF ``velocity`` limits [rad/s].
            home: Default joint angles [rad] returned by :meth:`home`.
            name: Model name (default: the file stem).
            source: Free text naming where the numbers come from.

        Raises:
            InputError: ``path`` is not a path.
            ModelFileError: the file is missing, too large, does not parse, or an element is
                malformed (the message names it; see :mod:`uvms_qp.model.urdf`).
            ModelError: unsupported joints (types, mimic), no moving joint, too many joints or
                links, inconsistent limits, ambiguous tool.
            UnknownFrameError: ``tool`` is not a link of the URDF.
        """
        path = check_path(path)
        arm = load_urdf_arm(path)
        if tool is None:
            if len(arm.leaves) != 1:
                raise ModelError(
                    f"URDF {str(path)!r}: several leaf links {list(arm.leaves)}; pass tool="
                )
            tool = arm.leaves[0]
        elif tool not in arm.links:
            raise UnknownFrameError(tool, arm.links)
        n = len(arm.joint_names)
        return cls(
            arm.model,
            vehicle=resolve_vehicle(vehicle),
            mount=as_transform(mount, "mount"),
            tool_parent=tool,
            tool_offset=as_transform(tool_offset, "tool_offset"),
            joint_names=arm.joint_names,
            joint_lower=arm.lower,
            joint_upper=arm.upper,
            joint_rate_limit=_limits(joint_rate_limit, arm.rate_limit, "joint_rate_limit", n),
            arm_frames=arm.links,
            name=Path(path).stem if name is None else name,
            source=source or f"URDF {Path(path).name}",
            home=home,
        )

    # --- names --------------------------------------------------------------------

    def frame_id(self, name: str) -> int:
        """Pinocchio frame id of a public frame name.

        Raises:
            UnknownFrameError: the name is not in :attr:`frames` (the message lists them).
        """
        try:
            return self._frame_ids[name]
        except (KeyError, TypeError):
            raise UnknownFrameError(name, self.frames) from None

    def joint_index(self, name: str) -> int:
        """Index of a joint in the joint vector (add :attr:`n_vehicle` for its ``zeta`` index).

        Raises:
            UnknownJointError: the name is not in :attr:`joint_names`.
        """
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise UnknownJointError(name, self.joint_names) from None

    # --- configurations --------------------------------------------------------------------

    def joint_outside_limits(self, angles: Any, joints: Any = None) -> tuple[int, str] | None:
        """The first angle outside its joint's position limits, or None when all are inside.

        Args:
            angles: Joint angles [rad] (or positions [m] of prismatic joints), one per entry of
                ``joints``.
            joints: Indices of the joints (default: every joint, in order).

        Returns:
            ``(k, sentence)``: the index into ``angles`` and a sentence naming the joint, the
            value and its limits (infinite limits never exclude).
        """
        idx = np.arange(self.n_joints) if joints is None else np.asarray(joints)
        values = np.asarray(angles, dtype=np.float64)
        lo, hi = self.joint_lower[idx], self.joint_upper[idx]
        outside = np.flatnonzero((values < lo) | (values > hi))
        if not outside.size:
            return None
        k = int(outside[0])
        return k, (f"joint {self.joint_names[int(idx[k])]!r} = {values[k]:g} is outside its "
                   f"limits [{lo[k]:g}, {hi[k]:g}]")

    def _check_joints(self, joints: Any, name: str) -> FloatArray:
        return as_vector(joints, name, self.n_joints).copy()

    def check_configuration(self, q: Any) -> FloatArray:
        """Validate a configuration and return it as a new float64 array.

        A quaternion (spatial) or ``(cos, sin)`` pair (planar) whose squared norm is within
        :data:`QUATERNION_TOLERANCE` of 1 is renormalised; a larger deviation is rejected.

        Raises:
            ShapeError: ``q`` does not have length :attr:`nq`.
            NonFiniteError: ``q`` holds NaN or inf.
            InputError: the vehicle orientation is far from unit norm.
        """
        # a float64 array (the control loop) is copied; anything else must be real numbers
        q = q.copy() if type(q) is np.ndarray and q.dtype is _F64 else np.array(as_array(q, "q"))
        if q.shape != (self.nq,):
            raise ShapeError(
                f"q: expected shape ({self.nq},) for model {self.name!r} "
                f"({self.nq_vehicle} vehicle + {self.n_joints} joints), got {q.shape}"
            )
        if not math.isfinite(q.dot(q)):
            as_vector(q, "q")  # raises NonFiniteError naming the first bad index
            raise NonFiniteError("q: values too large")
        if self.vehicle_kind != "fixed" and not pin.isNormalized(self.pin_model, q, 1e-12):
            spatial = self.vehicle_kind == "spatial"
            part = q[3:7] if spatial else q[2:4]
            norm2 = part.dot(part)
            if abs(norm2 - 1.0) > QUATERNION_TOLERANCE:
                what = "quaternion q[3:7]" if spatial else "(cos, sin) q[2:4]"
                raise InputError(f"q: vehicle {what} has squared norm {norm2:.6g}, not 1")
            part /= math.sqrt(norm2)
        return q

    def configuration(self, eta: Any, joints: Any) -> FloatArray:
        """Configuration ``q`` from a vehicle pose and joint angles.

        Args:
            eta: Vehicle pose: ``[x, y, z, phi, theta, psi]`` (spatial), ``[x, y, psi]``
                (planar) or empty or None (fixed) [m, rad], world NED, Z-Y-X Euler angles.
            joints: Joint angles [rad] (length :attr:`n_joints`).

        Returns:
            ``q`` of length :attr:`nq`.

        Raises:
            ShapeError, NonFiniteError: wrong lengths or non-finite values.
        """
        if not self.eta_size:
            if eta is not None and np.size(eta) != 0:
                raise ShapeError("eta: expected an empty pose (or None) for a fixed base, got "
                                 f"length {np.size(eta)}")
            eta_v = np.zeros(0)
        elif eta is None:
            raise ShapeError(f"eta: expected a {self.vehicle_kind} pose of length "
                             f"{self.eta_size}, got None")
        else:
            eta_v = as_vector(eta, "eta", self.eta_size)
        qj = self._check_joints(joints, "joints")
        return np.concatenate((self.vehicle.q_from_eta(eta_v), qj))

    def split(self, q: Any) -> tuple[FloatArray, FloatArray]:
        """Vehicle pose ``eta`` [m, rad] and joint angles [rad] of a configuration."""
        q = self.check_configuration(q)
        return self.vehicle.eta_from_q(q[: self.nq_vehicle]), q[self.nq_vehicle :]

    def neutral(self) -> FloatArray:
        """Vehicle at the origin, level, heading north; joints at zero clipped into limits."""
        return self.configuration(
            np.zeros(self.eta_size), np.clip(0.0, self.joint_lower, self.joint_upper)
        )

    def home(self) -> FloatArray:
        """Vehicle at the origin and the model's home joint angles (a paper's initial state)."""
        return self.configuration(np.zeros(self.eta_size), self._home_joints)

    def random_configuration(
        self,
        rng: np.random.Generator | int | None = None,
        *,
        position: float = 1.0,
        tilt: float = 0.4,
    ) -> FloatArray:
        """A random configuration for tests and examples.

        Args:
            rng: Generator or seed.
            position: Half-width of the uniform vehicle position box [m].
            tilt: Half-width of uniform roll and pitch [rad] (spatial); yaw is uniform in
                ``[-pi, pi]``.

        Returns:
            ``q`` with joints uniform within limits (infinite limits clipped to ``[-pi, pi]``).
        """
        position = as_scalar(position, "position", nonnegative=True)
        tilt = as_scalar(tilt, "tilt", nonnegative=True)
        try:
            gen = np.random.default_rng(rng)
        except (TypeError, ValueError) as exc:
            raise InputError(
                f"rng: expected a numpy Generator, a seed or None, got {rng!r}") from exc
        lo = np.maximum(self.joint_lower, -math.pi)
        hi = np.minimum(self.joint_upper, math.pi)
        joints = gen.uniform(lo, hi)
        if self.vehicle_kind == "spatial":
            eta = np.concatenate(
                (
                    gen.uniform(-position, position, 3),
                    gen.uniform(-tilt, tilt, 2),
                    gen.uniform(-math.pi, math.pi, 1),
                )
            )
        elif self.vehicle_kind == "planar":
            eta = np.array([*gen.uniform(-position, position, 2), gen.uniform(-math.pi, math.pi)])
        else:
            eta = np.zeros(0)
        return self.configuration(eta, joints)

    # --- motion --------------------------------------------------------------------

    def velocity(self, zeta: Any) -> FloatArray:
        """Pinocchio velocity (all vehicle DOFs + joints) of ``zeta``; passive rates are zero."""
        z = as_vector(zeta, "zeta", self.nv)
        v = np.zeros(self.pin_model.nv)
        v[self._columns] = z
        return v

    def integrate(self, q: Any, zeta: Any, dt: float) -> FloatArray:
        """Configuration after moving at constant ``zeta`` for ``dt`` seconds.

        Integrates on the configuration manifold (SE(3) exponential for a spatial vehicle:
        ``nu`` is a constant body twist) with passive vehicle rates at zero.

        Args:
            q: Configuration.
            zeta: Decision vector [m/s, rad/s].
            dt: Duration [s], positive like the controller's period (to move backwards, negate
                ``zeta``).

        Raises:
            InputError: ``dt`` zero, negative or not a number.
            ShapeError, NonFiniteError: bad ``q``, ``zeta`` or ``dt``, or a ``zeta * dt`` that
                overflows (finite inputs giving a non-finite configuration).
        """
        q = self.check_configuration(q)
        step = as_scalar(dt, "dt", positive=True)
        z = as_vector(zeta, "zeta", self.nv)
        if self._select is None:  # every Pinocchio velocity is a rate of zeta
            v = z * step
        else:
            v = np.zeros(self.pin_model.nv)
            v[self._columns] = z * step
        out = pin.integrate(self.pin_model, q, v)
        # finite zeta and dt whose product overflows (the sum of squares is the cheap test; an
        # overflowing sum of finite entries is re-checked entry by entry)
        if not math.isfinite(float(np.vdot(out, out))) and not np.isfinite(out).all():
            raise NonFiniteError(f"integrate: zeta * dt overflows (max |zeta| "
                                 f"{np.abs(np.asarray(zeta, dtype=np.float64)).max():.3g}, "
                                 f"dt {step:g}): the configuration is not finite")
        return out

    # --- kinematics --------------------------------------------------------------------

    def state(self, q: Any, velocity: Any = None) -> State:
        """Kinematic state at ``q`` (validated); see :class:`~uvms_qp.model.state.State`.

        Args:
            q: Configuration (nq,).
            velocity: Measured vehicle body velocity ``nu`` (6,) [m/s, rad/s] of a spatial
                vehicle, or None (none measured: a kinematic run).
        """
        return State(self, q, velocity)

    def check_body_velocity(self, velocity: Any) -> FloatArray:
        """Validate a measured body velocity ``nu`` (6,) [m/s, rad/s]: a read-only copy.

        Raises:
            InputError: the model's vehicle is not spatial (no six-component body velocity).
            ShapeError: not 6 entries. NonFiniteError: NaN or inf.
        """
        if self.vehicle_kind != "spatial":
            raise InputError(f"velocity: a measured body velocity needs a spatial vehicle; "
                             f"model {self.name!r} has a {self.vehicle_kind} one")
        nu = as_vector(velocity, "velocity", 6).copy()
        nu.setflags(write=False)
        return nu

    def frame_pose(self, q: Any, frame: str) -> FloatArray:
        """Pose ``T_world_frame`` (4x4) of a frame at configuration ``q``."""
        return self.state(q).pose(frame).copy()

    # --- description --------------------------------------------------------------------

    def summary(self) -> str:
        """One-line description: DOFs, vehicle kind, actuated rates, joints."""
        veh = f"{self.vehicle_kind} vehicle"
        if self.vehicle_kind != "fixed":
            veh += f" [{', '.join(self.actuated)}]"
            if self.passive:
                veh += f" (passive {', '.join(self.passive)})"
        return (
            f"{self.name}: {self.nv} DOF = {self.n_vehicle} vehicle + {self.n_joints} joints; "
            f"{veh}; joints [{', '.join(self.joint_names)}]"
        )

    def __deepcopy__(self, memo: dict[int, Any]) -> Model:
        """The model itself: a loaded model is shared, never copied.

        A deep copy of a stack or of a task bound to the model refers to the same model.
        """
        return self

    def __repr__(self) -> str:
        return f"<Model {self.summary()}>"
