"""Every task's rows equal a first-principles evaluation, on every bundled model and mode.

The reference side uses Pinocchio directly on a fresh ``Data`` (no :class:`State` caches) and
numpy: frame poses and world-aligned Jacobians restricted to the columns of zeta, the Z-Y-X
Euler angles of the vehicle, Fossen's ``J_eta`` (Wang et al. (2017), Eq. (2)-(3)),
the SO(3) log and its Jacobian, Yoshikawa's measure with the trace form of its gradient
(Soylu et al. (2007), Eq. (18)-(19)), the joint-limit index
(Wang et al. (2017), Eq. (15)-(16)) and the payload moment (Eq. (20)-(21)). Tasks run
over several ticks, so run-time memory (activation set points, ``w_dot``) is covered too.
Also: the per-instance units of the rows and errors.
"""

from __future__ import annotations

import math
import zlib

import numpy as np
import pinocchio as pin
import pytest

from tests.support.reference_kinematics import Ref, reference_manipulability, target_frame_jacobian
from uvms_qp.analytic import LIMIT_CLEARANCE, shaping_function
from uvms_qp.errors import InputError
from uvms_qp.model import bundled_models, load_model
from uvms_qp.tasks import (
    TASK_TYPES,
    CurrentAlignmentTask,
    EndEffectorTask,
    HeldPose,
    InFrame,
    JointLimitTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
    TrajectoryTarget,
    VehicleAttitudeTask,
    VehicleMotionTask,
)

MODELS = {name: load_model(name) for name in bundled_models()}
TICKS = 6
DT = 0.1
RTOL = 1e-10
#: manipulability rows: near a singular arm configuration both the fast gradient and the
#: reference trace formula lose digits with the conditioning of J J^T (1.3e-7 seen over 40 seeds
#: of random configurations); a wrong formula is off by O(1)
RTOL_MANIPULABILITY = 1e-6
_TWIST = ("x", "y", "z", "rx", "ry", "rz")


def wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def eta_names(model):
    return {"planar": ["x", "y", "psi"], "spatial": ["x", "y", "z", "phi", "theta", "psi"]}.get(
        model.vehicle_kind, [])


def joint_selector(model, idx):
    S = np.zeros((len(idx), model.nv))
    S[np.arange(len(idx)), model.n_vehicle + np.asarray(idx, dtype=int)] = 1.0
    return S


# ------------------------------------------------------------------------- reference rows
class Line:
    """A straight-line trajectory; with ``spin`` also a rotation about a fixed world axis."""

    def __init__(self, start, velocity, spin=None):
        self.p0, self.v = np.asarray(start, float), np.asarray(velocity, float)
        self.spin = None if spin is None else np.asarray(spin, float)
        self.duration = 10.0

    def sample(self, t):
        class Sample:
            pass

        s = Sample()
        s.position, s.velocity = self.p0 + t * self.v, self.v.copy()
        if self.spin is None:
            s.rotation = s.angular_velocity = None
        else:
            s.rotation = pin.exp3(t * self.spin) @ pin.rpy.rpyToMatrix(0.2, -0.1, 0.4)
            s.angular_velocity = self.spin.copy()
        return s


def ref_end_effector(task, ref, t, memory):
    """Rows of the frame relative to its target, the target fixed in ``task.reference``."""
    model = ref.model
    zero = np.zeros(3)
    v_l = w_l = zero
    target = task.setpoint
    if isinstance(target, InFrame):
        assert target.frame == task.reference
        target = target.target
    if isinstance(target, HeldPose):  # the frame's pose in the reference frame at first
        T_l = memory.setdefault("hold", np.linalg.inv(ref.pose(task.reference))
                                @ ref.pose(task.frame))
        p_l, R_l = T_l[:3, 3], T_l[:3, :3]
    elif isinstance(target, TrajectoryTarget):
        s = target.trajectory.sample(t)
        p_l, v_l = s.position, s.velocity
        R_l = target.rotation
        if s.rotation is not None:
            R_l, w_l = s.rotation, s.angular_velocity
    else:
        p_l, R_l = target.position, target.rotation
    T_l = np.eye(4)
    if p_l is not None:
        T_l[:3, 3] = p_l
    if R_l is not None:
        T_l[:3, :3] = R_l
    if task.reference == "world":
        T_d, J_d, R_r = T_l, np.zeros((6, model.nv)), np.eye(3)
    else:
        T_d, J_d = target_frame_jacobian(model, ref.q, task.reference, T_l)
        R_r = ref.pose(task.reference)[:3, :3]
    J6 = ref.jacobian(task.frame)
    T = ref.pose(task.frame)
    e = np.zeros(6)
    ff = np.zeros(6)
    A = J6 - J_d
    e[:3] = T_d[:3, 3] - T[:3, 3]
    ff[:3] = R_r @ v_l
    if task.mode != "position":
        R_e = T_d[:3, :3] @ T[:3, :3].T
        Jl = pin.Jlog3(R_e)
        e[3:] = pin.log3(R_e)
        ff[3:] = Jl.T @ (R_r @ w_l)
        A[3:] = Jl @ J6[3:] - Jl.T @ J_d[3:]
    sel = [_TWIST.index(a) for a in task.axes]
    return A[sel], np.multiply(task.gain, e[sel]) + ff[sel], None


def ref_station_keeping(task, ref, t, memory):
    idx = [eta_names(ref.model).index(a) for a in task.axes]
    eta = ref.eta[idx]
    if task.pose is not None:  # a world pose of the vehicle
        T = task.pose
        pose_eta = np.concatenate((T[:3, 3], pin.rpy.matrixToRpy(T[:3, :3])))
        if ref.model.vehicle_kind == "planar":
            pose_eta = np.array([T[0, 3], T[1, 3], math.atan2(T[1, 0], T[0, 0])])
        target = pose_eta[idx]
    elif task.target is not None:
        target = np.asarray(task.target, float)
    elif task.hold == "current":
        target = eta
    else:
        target = memory.setdefault("activation", eta.copy())
    e = target - eta
    for i, a in enumerate(task.axes):
        if a in ("phi", "theta", "psi"):
            e[i] = wrap(e[i])
    if task.blend is not None:
        rows = [0, 1] if ref.model.vehicle_kind == "planar" else [0, 1, 2]
        w, _ = reference_manipulability(ref.arm_jacobian(), rows)
        e = e * (1.0 - shaping_function(w, task._blend_task.threshold))
    return ref.eta_jacobian()[idx], np.multiply(task.gain, e), None


def ref_current_alignment(task, ref, t, memory):
    i = eta_names(ref.model).index("psi")
    e = wrap(task.heading + task.offset - ref.eta[i])
    return ref.eta_jacobian()[[i]], np.multiply(task.gain, [e]), None


def ref_vehicle_attitude(task, ref, t, memory):
    idx = [eta_names(ref.model).index(a) for a in task.axes]
    target = np.array([task.roll if a == "phi" else task.pitch for a in task.axes])
    e = np.array([wrap(x) for x in target - ref.eta[idx]])
    return ref.eta_jacobian()[idx], np.multiply(task.gain, e), None


def ref_posture(task, ref, t, memory):
    idx = [ref.model.joint_names.index(j) for j in task.joints] if task.joints else list(
        range(ref.model.n_joints))
    q = ref.joints[idx]
    fixed = task.posture if task.posture is not None else (
        0.5 * (ref.model.joint_lower[idx] + ref.model.joint_upper[idx])
        if task.reference == "middle" else None)
    if fixed is not None:
        q_ref = np.asarray(fixed, float)
    else:
        q_ref = memory.setdefault("activation", q.copy())
    return joint_selector(ref.model, idx), np.multiply(task.gain, q_ref - q), None


def ref_manipulability(task, ref, t, memory):
    m = ref.model
    rows = [_TWIST.index(a) for a in task.axes]
    w, g = reference_manipulability(ref.arm_jacobian(task.frame), rows)
    if task.mode == "floor":
        A = np.zeros((1, m.nv))
        A[0, m.n_vehicle:] = g
        short = task.minimum - w
        if short > 0 and w > 0:
            short = min(short, float(g @ g) / w)  # the cap near a maximum of w
        return A, np.array([task.gain * short]), np.array([np.inf])
    scale = task.gain
    if task.mode == "shaping":
        prev = memory.get("prev")
        w_dot = memory.get("w_dot", 0.0)
        if prev is not None and t > prev[0]:
            w_dot = (w - prev[1]) / (t - prev[0])
        memory["prev"], memory["w_dot"] = (t, w), w_dot
        scale *= shaping_function(w, task.threshold) * (0.0 if w_dot > 0.0 else 1.0)
    return joint_selector(m, range(m.n_joints)), scale * g, None


def ref_joint_limit(task, ref, t, memory):
    m = ref.model
    idx = list(task.joint_indices)
    lo, hi, q = m.joint_lower[idx], m.joint_upper[idx], ref.joints[idx]
    A = joint_selector(m, idx)
    if task.mode == "margin":
        return A, task.gain * (lo + task.margin - q), task.gain * (hi - task.margin - q)
    C = np.broadcast_to(np.asarray(task._strength, float), q.shape)
    span = hi - lo
    a = np.maximum(hi - q, LIMIT_CLEARANCE * span)
    b = np.maximum(q - lo, LIMIT_CLEARANCE * span)
    g = span**2 * (2.0 * q - hi - lo) / (C * a**2 * b**2)
    if task.mode == "damping":
        memory["weights"] = task.weight * (1.0 + np.abs(g))
        return A, np.zeros(len(idx)), None
    scale = -task.gain
    if task.normalize:
        scale /= np.linalg.norm(g)
    return A, scale * g, None


def ref_payload(task, ref, t, memory):
    m = ref.model
    T_b, T_e = ref.pose("arm_base"), ref.pose(task.frame)
    x, y, _ = T_b[:3, :3].T @ (T_e[:3, 3] - T_b[:3, 3])
    Ja = ref.arm_jacobian(task.frame)
    F = task.force
    g = 2.0 * F * (x * Ja[0] + y * Ja[1])
    M = (x * x + y * y) * F
    if task.mode == "bound":
        A = np.zeros((1, m.nv))
        A[0, m.n_vehicle:] = g
        return A, np.array([-np.inf]), np.array([task.gain * (task.maximum - M)])
    scale = -task.gain
    if task.normalize:
        scale /= np.linalg.norm(g)
    return joint_selector(m, range(m.n_joints)), scale * g, None


def ref_vehicle_motion(task, ref, t, memory):
    m = ref.model
    k = m.nv if task.include_arm else m.n_vehicle
    return np.eye(k, m.nv), np.zeros(k), None


REFERENCES = {
    EndEffectorTask: ref_end_effector,
    StationKeepingTask: ref_station_keeping,
    CurrentAlignmentTask: ref_current_alignment,
    VehicleAttitudeTask: ref_vehicle_attitude,
    PostureTask: ref_posture,
    ManipulabilityTask: ref_manipulability,
    JointLimitTask: ref_joint_limit,
    PayloadMomentTask: ref_payload,
    VehicleMotionTask: ref_vehicle_motion,
}

P = [0.5, 0.1, 0.2]
CASES = {
    "ee_position": lambda m: EndEffectorTask(position=P, gain=2.0),
    "ee_position_traj": lambda m: EndEffectorTask(trajectory=Line(P, [0.1, -0.2, 0.05]),
                                                  gain=2.0),
    "ee_position_axes": lambda m: EndEffectorTask(axes=["y", "x"], position=P, gain=[1.0, 3.0]),
    "ee_orientation": lambda m: EndEffectorTask(mode="orientation", rotation=[0.1, 0.2, 0.3],
                                                gain=1.5),
    "ee_orientation_rz": lambda m: EndEffectorTask(mode="orientation", axes=["rz"],
                                                   rotation=[0.1, 0.2, 0.3]),
    "ee_pose": lambda m: EndEffectorTask(mode="pose", position=P, rotation=[0.1, 0.2, 0.3]),
    "ee_pose_traj": lambda m: EndEffectorTask(
        mode="pose", trajectory=Line(P, [0.1, 0.0, 0.2], spin=[0.1, 0.0, -0.3])),
    "ee_pose_axes": lambda m: EndEffectorTask(mode="pose", axes=["y", "rz", "x"], position=P,
                                              rotation=[0.3, -0.2, 1.0], gain=[1.0, 2.0, 3.0]),
    "ee_se3": lambda m: EndEffectorTask(mode="pose", target=pin.SE3(
        pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.array(P))),
    "ee_hold": lambda m: EndEffectorTask(mode="pose", hold="activation", gain=1.5),
    "ee_vehicle_position": lambda m: EndEffectorTask(reference="vehicle", position=[0.5, 0.0, 0.3],
                                                     gain=2.0),
    "ee_vehicle_pose": lambda m: EndEffectorTask(
        mode="pose", reference="vehicle", target={"xyz": [0.6, 0.1, 0.2], "rpy": [0.2, 0, 1]}),
    "ee_arm_base_traj": lambda m: EndEffectorTask(
        mode="pose", reference="arm_base", rotation=[0.0, 0.1, 0.2],
        trajectory=Line(P, [0.1, 0.0, 0.2], spin=[0.1, 0.0, -0.3])),
    "ee_link_axes": lambda m: EndEffectorTask(mode="pose", reference=m.frames[4],
                                              axes=["x", "rz"], target=np.eye(4)),
    "ee_vehicle_hold": lambda m: EndEffectorTask(reference="vehicle", hold="activation"),
    "manip_ascend": lambda m: ManipulabilityTask(mode="ascend", gain=0.5),
    "manip_floor": lambda m: ManipulabilityTask(mode="floor", minimum=0.002, gain=2.0),
    "manip_shaping": lambda m: ManipulabilityTask(mode="shaping", threshold=0.5, gain=0.7),
    "manip_rows": lambda m: ManipulabilityTask(mode="ascend", axes=["x", "y", "rz"]),
    "manip_twist": lambda m: ManipulabilityTask(mode="floor", axes=list(_TWIST), minimum=1e-6),
    "jl_gradient": lambda m: JointLimitTask(mode="gradient", gain=0.3),
    "jl_normalized": lambda m: JointLimitTask(mode="gradient", normalize=True, strength=2.0),
    "jl_margin": lambda m: JointLimitTask(mode="margin", margin=0.1, gain=2.0),
    "jl_damping": lambda m: JointLimitTask(mode="damping", weight=2.0),
    "payload_reduce": lambda m: PayloadMomentTask(force=10.0, gain=0.5),
    "payload_normalized": lambda m: PayloadMomentTask(force=10.0, normalize=True),
    "payload_bound": lambda m: PayloadMomentTask(mode="bound", force=5.0, maximum=0.3),
    "posture": lambda m: PostureTask(gain=0.2),
    "posture_reversed": lambda m: PostureTask(joints=list(reversed(m.joint_names)), gain=0.4),
    "jl_reversed": lambda m: JointLimitTask(mode="margin", joints=list(reversed(m.joint_names)),
                                            margin=0.05),
    "posture_subset": lambda m: PostureTask(
        reference="middle", joints=[m.joint_names[-1], m.joint_names[0]], gain=[0.1, 0.3]),
    "station_hold": lambda m: StationKeepingTask(gain=1.0),
    "station_current": lambda m: StationKeepingTask(hold="current"),
    "station_target": lambda m: StationKeepingTask(axes=["psi", "x"], target=[3.1, 0.2],
                                                   gain=[1.0, 2.0]),
    "station_pose": lambda m: StationKeepingTask(pose=pin.SE3(pin.rpy.rpyToMatrix(0, 0, 2.0),
                                                              np.array([1.0, -0.5, 0.3]))),
    "current_alignment": lambda m: CurrentAlignmentTask(heading=0.78, gain=0.5),
    "current_direction": lambda m: CurrentAlignmentTask(direction=[1.0, -2.0], offset=3.0),
    "attitude": lambda m: VehicleAttitudeTask(gain=[1.0, 2.0]),
    "attitude_pitch": lambda m: VehicleAttitudeTask(axes=["theta"], pitch=0.1),
    "vehicle_motion": lambda m: VehicleMotionTask(beta=0.8),
    "vehicle_motion_only": lambda m: VehicleMotionTask(include_arm=False),
}


def _applies(make, model):
    """True when the case binds to the model (it may need an arm, a heading, roll, limits)."""
    try:
        make(model).bind(model)
    except InputError:
        return False
    return True


APPLICABLE = [(name, case) for name in sorted(MODELS) for case in sorted(CASES)
              if _applies(CASES[case], MODELS[name])]


def _configurations(model, seed):
    rng = np.random.default_rng(seed)
    return [model.random_configuration(rng) for _ in range(TICKS)]


def _check(task, model, qs, extra=None):
    reference = next(f for cls, f in REFERENCES.items() if isinstance(task, cls))
    rtol = RTOL_MANIPULABILITY if isinstance(task, ManipulabilityTask) else RTOL
    memory: dict = {}
    slot = task.new_slot()  # the task's run-time memory over the ticks
    if extra is not None:
        extra_slot = extra.new_slot()
        slot.peers = {extra: extra_slot, task: slot}
    for k, q in enumerate(qs):
        t = DT * k
        state = model.state(q)
        if extra is not None:
            extra.rows(state, t, extra_slot)
        rows = task.rows(state, t, slot)
        A, lo, hi = reference(task, Ref(model, q), t, memory)
        hi = lo if hi is None else hi
        scale = 1.0 + np.abs(A).max()
        np.testing.assert_allclose(rows.A, A, rtol=rtol, atol=rtol * scale)
        for got, want in ((rows.lower, lo), (rows.upper, hi)):
            np.testing.assert_allclose(got, want, rtol=rtol, atol=rtol * (1.0 + np.abs(
                want[np.isfinite(want)]).max(initial=0.0)))
        if "weights" in memory:
            np.testing.assert_allclose(rows.weights, memory["weights"], rtol=RTOL)


def test_every_case_applies_somewhere():
    assert {case for _, case in APPLICABLE} == set(CASES)


@pytest.mark.parametrize(("model_name", "case"), APPLICABLE)
def test_rows_equal_the_first_principles_rows(model_name, case):
    model = MODELS[model_name]
    task = CASES[case](model).bind(model)
    _check(task, model, _configurations(model, seed=zlib.crc32(case.encode()) % 1000))


@pytest.mark.parametrize("model_name", ["bluerov2_heavy_alpha5", "wang_9dof", "soylu_planar"])
def test_blended_station_keeping_reads_the_shaping_task_of_the_same_tick(model_name):
    """The blended demand ``(1 - k(w)) K e`` with ``w`` of the same state (shared per tick)."""
    model = MODELS[model_name]
    shaping = ManipulabilityTask(mode="shaping", threshold=0.5, name="shape").bind(model)
    station = StationKeepingTask(blend="shape", gain=0.5).bind(model)
    station.link({"shape": shaping, station.name: station})
    qs = _configurations(model, seed=5)
    _check(station, model, qs, extra=shaping)
    _check(station, model, qs)  # station keeping evaluated alone also computes w itself


# ------------------------------------------------------------------------------ units
@pytest.mark.parametrize(("make", "rate", "error"), [
    (lambda: EndEffectorTask(position=P), "m/s", "m"),
    (lambda: EndEffectorTask(mode="orientation", rotation=[0, 0, 0]), "rad/s", "rad"),
    (lambda: EndEffectorTask(mode="pose", position=P, rotation=[0, 0, 0]), "m/s, rad/s",
     "m, rad"),
    (lambda: EndEffectorTask(mode="pose", axes=["rx", "ry"], position=P, rotation=[0, 0, 0]),
     "rad/s", "rad"),
    (lambda: StationKeepingTask(), "m/s, rad/s", "m, rad"),
    (lambda: StationKeepingTask(axes=["x", "z"]), "m/s", "m"),
    (lambda: StationKeepingTask(axes=["psi"]), "rad/s", "rad"),
    (lambda: ManipulabilityTask(mode="floor", minimum=0.01), "m^3/s", "m^3"),
    (lambda: ManipulabilityTask(mode="ascend"), "rad/s", "m^3"),
    (lambda: ManipulabilityTask(mode="shaping", threshold=0.1, axes=["x", "rz"]), "rad/s",
     "m"),
    (lambda: ManipulabilityTask(mode="floor", minimum=0.1, axes=["rx", "ry"]), "1/s", "1"),
    (lambda: JointLimitTask(mode="margin"), "rad/s", "rad"),
    (lambda: JointLimitTask(mode="gradient"), "rad/s", "1"),
    (lambda: PayloadMomentTask(), "rad/s", "N m^2"),
    (lambda: PayloadMomentTask(mode="bound", maximum=1.0), "N m^2/s", "N m^2"),
])
def test_units_follow_the_bound_rows(make, rate, error):
    task = make()
    cls = type(task)
    assert (task.rate_unit, task.error_unit) == (cls.rate_unit, cls.error_unit)  # before bind
    task.bind(MODELS["bluerov2_heavy_alpha5"])
    assert (task.rate_unit, task.error_unit) == (rate, error)
    assert f"rows [{rate}]" in task.describe()
    assert (cls.rate_unit, cls.error_unit) == (type(make()).rate_unit, type(make()).error_unit)


def test_every_task_type_has_default_units():
    for cls in TASK_TYPES.values():
        assert cls.rate_unit and cls.error_unit, cls.__name__


def test_the_controller_reports_the_bound_units():
    from uvms_qp.controller import Controller
    from uvms_qp.stack import Level, Stack

    model = MODELS["bluerov2_heavy_alpha5"]
    stack = Stack(levels=[Level(EndEffectorTask(position=P)),
                          Level(StationKeepingTask(axes=["psi"]))])
    result = Controller(model, stack, dt=0.05).step(model.state(model.home()), 0.0)
    assert result.task_residuals["tool"][1] == "m/s"
    assert result.task_residuals["station_keeping"][1] == "rad/s"


# ----------------------------------------------------------------------------- the contract
@pytest.mark.parametrize("case", ["ee_pose", "ee_vehicle_pose", "station_hold", "attitude",
                                  "current_alignment", "posture"])
def test_compute_methods_are_views_of_the_one_evaluation(case):
    """``rows``, ``evaluate`` and ``compute_error`` are built from the one ``error_rows``."""
    model = MODELS["bluerov2_heavy_alpha5"]
    task = CASES[case](model).bind(model)
    state = model.state(_configurations(model, seed=6)[0])
    slot = task.new_slot()
    rows = task.rows(state, 0.3, slot)
    J, e, ff = task.error_rows(state, 0.3, slot)
    np.testing.assert_array_equal(task.compute_error(state, 0.3, slot), e)
    np.testing.assert_array_equal(J, rows.A)
    np.testing.assert_array_equal(rows.lower, np.multiply(task.gain, e) + (0.0 if ff is None
                                                                           else ff))
    np.testing.assert_array_equal(slot.last_error, e)
    J, lower, upper = task.evaluate(state, 0.3, slot)
    np.testing.assert_array_equal(J, rows.A)
    np.testing.assert_array_equal(lower, rows.lower)
    np.testing.assert_array_equal(upper, rows.upper)


@pytest.mark.parametrize("method", ["fill", "rows", "evaluate", "compute_error"])
def test_a_task_class_writes_only_its_one_evaluation(method):
    """Overriding a method the base classes define from ``error_rows`` is refused at once."""
    with pytest.raises(TypeError, match=f"overrides {method}"):
        type("Shifted", (PostureTask,), {method: lambda self, *args: None})


def test_a_set_based_task_may_not_override_fill():
    with pytest.raises(TypeError, match="overrides fill"):
        type("Direct", (JointLimitTask,), {"fill": lambda self, *args: None})


def test_the_kept_error_is_a_new_array_every_tick():
    """A step result keeps a reference to the task error: the next tick must not overwrite it."""
    model = MODELS["bluerov2_heavy_alpha5"]
    for make in (CASES["ee_position"], CASES["station_hold"], CASES["posture"],
                 CASES["manip_floor"], CASES["jl_margin"], CASES["payload_reduce"]):
        task = make(model).bind(model)
        slot = task.new_slot()
        s1, s2 = (model.state(q) for q in _configurations(model, seed=2)[:2])
        task.rows(s1, 0.0, slot)
        e1 = slot.last_error
        kept = e1.copy()
        task.rows(s2, 0.1, slot)
        assert slot.last_error is not e1
        np.testing.assert_array_equal(e1, kept)


def test_vehicle_attitude_set_point_update_reaches_the_rows():
    model = MODELS["bluerov2_heavy_alpha5"]
    task = VehicleAttitudeTask(roll=0.0, pitch=0.0, gain=[1.0, 2.0]).bind(model)
    task.update(roll=-3.0, pitch=3.1)
    for q in _configurations(model, seed=15):
        state = model.state(q)
        phi, theta = state.eta[3], state.eta[4]
        want = np.array([wrap(-3.0 - phi), wrap(3.1 - theta)]) * np.array([1.0, 2.0])
        np.testing.assert_allclose(task.rows(state).lower, want, rtol=0, atol=1e-15)


def test_current_alignment_without_heading_names_the_task():
    model = MODELS["bluerov2_heavy_alpha5"]
    task = CurrentAlignmentTask(name="yaw").bind(model)
    with pytest.raises(InputError, match="yaw"):
        task.rows(model.state(model.home()))
