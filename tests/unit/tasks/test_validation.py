"""Task construction, binding and run-time validation: bad input raises the project's errors."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from tests.support.culprit import assert_names_culprit, bad_cases
from uvms_qp.analytic import LIMIT_CLEARANCE, joint_limit_gradient
from uvms_qp.errors import (
    InputError,
    NonFiniteError,
    ShapeError,
    UnknownFrameError,
    UnknownJointError,
)
from uvms_qp.model import DHRow, Model, load_model
from uvms_qp.sim.trajectories import (
    CircleTrajectory,
    FixedTarget,
    LineTrajectory,
    QuinticTrajectory,
    WaypointTrajectory,
)
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import (
    TASK_TYPES,
    CurrentAlignmentTask,
    EndEffectorTask,
    JointLimitTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
    VehicleAttitudeTask,
    VehicleMotionTask,
)


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


@pytest.fixture(scope="module")
def wang():
    return load_model("wang_9dof")


def test_registry_keys_are_type_names():
    assert set(TASK_TYPES) == {
        "end_effector", "station_keeping", "manipulability", "joint_limit", "payload_moment",
        "current_alignment", "vehicle_attitude", "posture", "vehicle_motion"}
    for key, cls in TASK_TYPES.items():
        assert cls.type_name == key
        assert cls.__doc__ and cls.error_unit and cls.rate_unit


def test_target_never_set_names_the_task(rov):
    task = EndEffectorTask(name="grab").bind(rov)
    with pytest.raises(InputError, match=r"'grab'.*target never set"):
        task.rows(rov.state(rov.neutral()), 0.0)
    align = CurrentAlignmentTask(name="align").bind(rov)
    with pytest.raises(InputError, match="'align'"):
        align.rows(rov.state(rov.neutral()), 0.0)


def test_unknown_frame_lists_known_frames(rov):
    with pytest.raises(UnknownFrameError, match=r"tool2.*known frames.*tool"):
        EndEffectorTask("tool2", position=[0, 0, 0]).bind(rov)
    with pytest.raises(UnknownFrameError):
        ManipulabilityTask(mode="ascend", frame="nope").bind(rov)
    with pytest.raises(UnknownJointError, match="elbow"):
        PostureTask(joints=["elbow"]).bind(rov)


@pytest.mark.parametrize("kwargs, match", [
    ({"mode": "speed"}, "mode"),
    ({"axes": ["x", "w"]}, "unknown axis 'w'"),
    ({"axes": ["x", "x"]}, "twice"),
    ({"gain": -1.0}, "gain"),
    ({"weight": 0.0}, "weight"),
    ({"position": [1.0, 2.0, float("nan")]}, "NaN"),
    ({"mode": "orientation", "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}, "not a rotation"),
    ({"mode": "orientation", "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, -1]]}, "reflection"),
    ({"trajectory": 3.0}, "sample"),
    ({"name": " padded "}, "name"),
])
def test_end_effector_rejects_bad_arguments(kwargs, match):
    with pytest.raises(InputError, match=match):
        EndEffectorTask(**kwargs)


def test_gain_length_checked_at_bind(rov):
    with pytest.raises(InputError, match="expected 3 gains"):
        EndEffectorTask(position=[0, 0, 0], gain=[1.0, 2.0]).bind(rov)


def test_attitude_needs_actuated_roll_pitch(rov, wang):
    VehicleAttitudeTask().bind(rov)  # BlueROV2 Heavy actuates p and q
    with pytest.raises(InputError, match="does not actuate 'p'"):
        VehicleAttitudeTask().bind(wang)
    with pytest.raises(InputError, match="passive"):
        StationKeepingTask(axes=["x", "phi"]).bind(wang)


def test_fixed_base_has_no_vehicle_tasks():
    arm = load_model("nenchev_pa10_arm")
    for task in (StationKeepingTask(), CurrentAlignmentTask(heading=0.0), VehicleMotionTask()):
        with pytest.raises(InputError):
            task.bind(arm)


def test_mode_parameters_required():
    with pytest.raises(InputError, match="minimum"):
        ManipulabilityTask(mode="floor")
    with pytest.raises(InputError, match="threshold"):
        ManipulabilityTask(mode="shaping")
    with pytest.raises(InputError, match="maximum"):
        PayloadMomentTask(mode="bound")
    with pytest.raises(InputError, match="beta"):
        VehicleMotionTask(beta=1.0)


def test_joint_limit_margin_too_large(rov):
    with pytest.raises(InputError, match="no room"):
        JointLimitTask(margin=2.0).bind(rov)  # axis_c spans 3.5 rad


def test_update_validates_and_applies(rov):
    payload = PayloadMomentTask(force=0.0).bind(rov)
    state = rov.state(rov.home())
    assert np.all(payload.rows(state).lower == 0.0)  # no payload: no demand
    payload.update(force=20.0)
    assert payload.force == 20.0
    assert np.any(payload.rows(state).lower != 0.0)
    with pytest.raises(InputError, match="force"):
        payload.update(force=-1.0)
    with pytest.raises(InputError, match=r"unknown parameter 'mass'.*force"):
        payload.update(mass=3.0)


def test_station_keeping_holds_the_whole_actuated_pose_by_default(rov):
    assert StationKeepingTask().bind(rov).axes == ["x", "y", "z", "phi", "theta", "psi"]
    four = load_model("wang_9dof")  # roll and pitch passive
    assert StationKeepingTask().bind(four).axes == ["x", "y", "z", "psi"]


def test_station_keeping_holds_activation_pose(rov):
    rng = np.random.default_rng(0)
    task = StationKeepingTask(gain=2.0).bind(rov)
    slot = task.new_slot()  # the memory of one controller
    q0 = rov.random_configuration(rng)
    rows0 = task.rows(rov.state(q0), slot=slot)
    np.testing.assert_allclose(rows0.lower, 0.0, atol=1e-15)
    q1 = rov.integrate(q0, np.r_[0.3, 0, 0, 0, 0, 0.2, 0, 0, 0, 0], 1.0)
    e = task.compute_error(rov.state(q1), 0.0, slot)
    eta0, eta1 = rov.split(q0)[0], rov.split(q1)[0]
    np.testing.assert_allclose(e, eta0 - eta1, atol=1e-12)  # all six: roll and pitch actuated
    slot.clear()
    np.testing.assert_allclose(task.compute_error(rov.state(q1), 0.0, slot), 0.0)
    np.testing.assert_allclose(task.compute_error(rov.state(q1), 0.0), 0.0)  # a new slot
    current = StationKeepingTask(hold="current").bind(rov)
    np.testing.assert_allclose(current.compute_error(rov.state(q1), 0.0), 0.0)


def test_current_alignment_wraps_the_error(rov):
    task = CurrentAlignmentTask(heading=3.1, gain=1.0).bind(rov)
    q = rov.configuration([0, 0, 0, 0, 0, -3.1], rov.split(rov.home())[1])
    e = task.compute_error(rov.state(q), 0.0)
    assert e[0] == pytest.approx(6.2 - 2 * np.pi)  # the short way round, not 6.2 rad
    task.update(direction=[0.0, 1.0])
    assert task.heading == pytest.approx(np.pi / 2)


def test_shaping_sign_switch(rov):
    """Eq. (21): the gradient term acts only while w is not increasing."""
    task = ManipulabilityTask(mode="shaping", threshold=10.0, gain=1.0).bind(rov)
    rng = np.random.default_rng(1)
    q0 = rov.home()
    w0, g0 = task.compute_value(rov.state(q0))
    slot = task.new_slot()
    first = task.rows(rov.state(q0), 0.0, slot)
    np.testing.assert_allclose(first.lower, g0)  # k = 1 (w << threshold), w_dot = 0 -> active
    zeta = np.zeros(rov.nv)
    zeta[6:] = g0 / np.linalg.norm(g0) * 0.1  # increase w
    q1 = rov.integrate(q0, zeta, 0.1)
    assert task.compute_value(rov.state(q1))[0] > w0
    rows = task.rows(rov.state(q1), 0.1, slot)
    np.testing.assert_allclose(rows.lower, 0.0)  # switched off while w grows
    del rng


def test_vehicle_motion_weights_follow_eq14(rov):
    task = VehicleMotionTask(beta=0.8, w_max=0.5).bind(rov)
    w = task.row_weights
    np.testing.assert_allclose(w[:6], 1 / ((1 - 0.8) * 0.5))
    np.testing.assert_allclose(w[6:], 1 / 0.8)


def test_stack_validation():
    a = EndEffectorTask(position=[0, 0, 0], name="a")
    with pytest.raises(InputError, match="at least one task"):
        Level()
    with pytest.raises(InputError, match="at least one task"):
        Stack(levels=[[a], []])
    with pytest.raises(InputError, match="duplicate task name 'a'"):
        Stack(levels=[Level(a), Level(EndEffectorTask(position=[1, 0, 0], name="a"))])
    with pytest.raises(InputError, match="non-empty list"):
        Stack(levels=[])
    with pytest.raises(InputError, match="expected a Task"):
        Level("end_effector")


def test_stack_bind_error_carries_location(rov):
    stack = Stack(levels=[Level(EndEffectorTask(position=[0, 0, 0])),
                          Level(PostureTask(), EndEffectorTask("gripper", name="g"))])
    with pytest.raises(UnknownFrameError, match=r"levels\[1\]\.tasks\[1\] \(g\).*gripper"):
        stack.bind(rov)


def test_joint_limit_damping_weights_follow_eq17(rov):
    """Row weights 1 + |dH/dq_i| (the inverse of Eq. (17)'s w_i), refreshed every evaluation."""
    task = JointLimitTask(mode="damping", strength=[10.0, 6.0, 10.0, 10.0], weight=2.0).bind(rov)
    joints = np.array([0.1, 1.9, 3.3, 3.1])  # axis_e and axis_c near a limit
    state = rov.state(rov.configuration(np.zeros(6), joints))
    rows = task.rows(state)
    grad = joint_limit_gradient(joints, rov.joint_lower, rov.joint_upper,
                                [10.0, 6.0, 10.0, 10.0], clearance=LIMIT_CLEARANCE)
    np.testing.assert_allclose(rows.weights, 2.0 * (1.0 + np.abs(grad)))
    np.testing.assert_allclose(rows.lower, 0.0)
    assert rows.weights[0] > 10 * rows.weights[1]  # near-limit joint is the expensive one


def test_two_value_point_is_rejected_on_a_spatial_model(rov):
    with pytest.raises(ShapeError, match=r"tip\.position.*2 coordinates"):
        EndEffectorTask(position=[1.0, 2.0], name="tip").bind(rov)
    with pytest.raises(ShapeError, match=r"tip\.velocity"):
        free = EndEffectorTask(name="tip")
        free.set_target(position=[1.0, 2.0, 3.0], velocity=[0.1, 0.0])
        free.bind(rov)
    bound = EndEffectorTask(position=[1.0, 2.0, 3.0], name="tip").bind(rov)
    with pytest.raises(ShapeError, match=r"tip\.position"):
        bound.set_target(position=[1.0, 2.0])
    with pytest.raises(InputError, match=r"tip\.position"):
        bound.update(position=[1.0, 2.0])
    pa10 = load_model("nenchev_pa10_arm")
    with pytest.raises(ShapeError, match=r"tip\.position"):
        EndEffectorTask(position=[1.0, 2.0], name="tip").bind(pa10)


def test_two_value_point_on_a_planar_model_has_zero_depth(rov):
    planar = load_model("soylu_planar")
    state = planar.state(planar.neutral())
    task = EndEffectorTask(position=[1.0, 2.0], name="tip").bind(planar)
    expected = np.array([1.0, 2.0, 0.0]) - state.position("tool")
    np.testing.assert_allclose(task.compute_error(state, 0.0), expected[:2])
    task.set_target(position=[0.5, -0.5])
    assert task.target(0.0)[0].tolist() == [0.5, -0.5, 0.0]
    # a 2-value target replaced by a 3-value one no longer blocks a spatial bind
    moving = EndEffectorTask(position=[1.0, 2.0], name="tip")
    moving.set_target(position=[1.0, 2.0, 3.0])
    moving.bind(rov)


# ---------------------------------------------------------------------- choices and targets
@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: EndEffectorTask(mode=["position"]), r"tool\.mode: expected one of"),
        (lambda: EndEffectorTask(mode={"pose": 1}), r"tool\.mode: expected one of"),
        (lambda: JointLimitTask(mode=np.array(["margin", "damping"])),
         r"joint_limit\.mode: expected one of"),
        (lambda: StationKeepingTask(hold=np.array(["activation", "current"])),
         r"station_keeping\.hold: expected one of 'activation', 'current'"),
        (lambda: ManipulabilityTask(mode=["floor"]), r"manipulability\.mode: expected one of"),
        (lambda: PayloadMomentTask(mode=("bound",)), r"payload_moment\.mode: expected one of"),
        (lambda: PostureTask(reference=[0.0]), r"posture\.reference: expected one of"),
        (lambda: EndEffectorTask(hold=True), r"tool\.hold: expected one of 'activation'"),
    ],
)
def test_a_choice_that_is_not_a_string_is_an_input_error(make, match):
    """Lists, arrays and mappings used to escape as TypeError or numpy's ambiguous truth value."""
    with pytest.raises(InputError, match=match):
        make()


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"target": np.eye(3)}, ShapeError, r"tool\.target: expected 4 rows"),
        ({"target": np.diag([1.0, 1.0, 1.0, 2.0])}, InputError, "bottom row"),
        ({"target": np.diag([1.0, 2.0, 1.0, 1.0])}, InputError, "not a rotation matrix"),
        ({"target": np.diag([1.0, 1.0, -1.0, 1.0])}, InputError, "reflection"),
        ({"target": {"xyz": [0, 0, 0], "rotation": 0}}, InputError, "unknown keys"),
        ({"target": "tool"}, InputError, r"tool\.target: expected real numbers"),
        ({"target": np.eye(4), "position": [0, 0, 0]}, InputError, "not both"),
        ({"hold": "activation", "position": [0, 0, 0]}, InputError,
         "give one target: hold, position exclude each other"),
        ({"reference": "tool"}, InputError, "the controlled frame itself"),
        ({"reference": 3}, InputError, r"tool\.reference: expected a frame name"),
    ],
)
def test_end_effector_targets_are_validated(kwargs, error, match):
    with pytest.raises(error, match=match):
        EndEffectorTask(**kwargs)


def test_a_target_frame_must_exist(rov):
    task = EndEffectorTask(reference="object", position=[0.1, 0, 0])
    with pytest.raises(UnknownFrameError, match="'object'; known frames: world, vehicle"):
        task.bind(rov)


def test_pose_targets_equal_position_and_rotation(rov):
    """SE3, 4x4 and {"xyz", "rpy"} targets give the rows of position= plus rotation=."""
    import pinocchio as pin

    R = pin.rpy.rpyToMatrix(0.3, -0.2, 1.1)
    p = np.array([0.6, 0.1, -0.2])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    state = rov.state(rov.random_configuration(4))
    want = EndEffectorTask(mode="pose", position=p, rotation=R).bind(rov).rows(state)
    for target in (pin.SE3(R, p), T, {"xyz": p.tolist(), "rpy": [0.3, -0.2, 1.1]}):
        got = EndEffectorTask(mode="pose", target=target).bind(rov).rows(state)
        np.testing.assert_allclose(got.A, want.A, atol=1e-14)
        np.testing.assert_allclose(got.lower, want.lower, atol=1e-14)
    task = EndEffectorTask(mode="pose", position=[0, 0, 0], rotation=np.eye(3)).bind(rov)
    task.update(target=pin.SE3(R, p))
    np.testing.assert_allclose(task.rows(state).lower, want.lower, atol=1e-14)
    assert task.target(0.0)[0].tolist() == p.tolist()


def test_holding_takes_the_pose_of_the_first_evaluation(rov):
    rng = np.random.default_rng(2)
    s0, s1 = (rov.state(rov.random_configuration(rng)) for _ in range(2))
    task = EndEffectorTask(mode="pose", reference="vehicle", hold="activation").bind(rov)
    slot = task.new_slot()  # the memory of one controller
    assert task.has_target and task.target(0.0, slot=slot) == (None, None)
    np.testing.assert_allclose(task.compute_error(s0, 0.0, slot), 0.0, atol=1e-12)  # held
    held = s0.pose_in("tool", "vehicle")
    np.testing.assert_allclose(task.target(0.0, slot=slot)[0], held[:3, 3])
    assert np.abs(task.compute_error(s1, 0.1, slot)).max() > 1e-3  # moved away: error
    T_v = s1.pose("vehicle")  # the held point, carried by the vehicle, in world coordinates
    np.testing.assert_allclose(task.target(0.1, s1, slot)[0],
                               T_v[:3, :3] @ held[:3, 3] + T_v[:3, 3])
    other = task.new_slot()  # another controller holds its own pose
    np.testing.assert_allclose(task.compute_error(s1, 0.2, other), 0.0, atol=1e-12)
    assert np.abs(task.compute_error(s1, 0.2, slot)).max() > 1e-3
    slot.clear()  # re-armed: the next evaluation holds again
    np.testing.assert_allclose(task.compute_error(s1, 0.2, slot), 0.0, atol=1e-12)
    task.set_target(hold="activation")  # a new hold: every slot takes the pose again
    np.testing.assert_allclose(task.compute_error(s0, 0.3, other), 0.0, atol=1e-12)
    task.update(position=[0.5, 0.0, 0.0], rotation=np.eye(3))  # a fixed target ends holding
    assert task.compute_error(s0, 0.3, slot)[:3].tolist() != [0.0, 0.0, 0.0]


# ------------------------------------------- trajectories and axes bound to a model
SPATIAL_MESSAGE = "got 2 coordinates, but the model is spatial; give 3 (x, y, z)"


SPATIAL = re.escape(SPATIAL_MESSAGE)


@pytest.fixture(scope="module")
def spatial(rov):
    return rov


@pytest.fixture(scope="module")
def planar(models):
    return models["soylu_planar"]


@pytest.mark.parametrize(
    "trajectory",
    [
        QuinticTrajectory([0.5, 0.1], [0.5, 0.2], 1.0),
        LineTrajectory([0.5, 0.1], [0.5, 0.2], 1.0),
        CircleTrajectory([0.5, 0.1], 0.1, 1.0),
        WaypointTrajectory([[0.5, 0.1], [0.5, 0.2]], [0.0, 1.0]),
        FixedTarget([0.5, 0.1]),
    ],
    ids=["quintic", "line", "circle", "waypoints", "fixed"],
)
def test_a_planar_trajectory_is_rejected_on_a_spatial_model(spatial, planar, trajectory):
    task = EndEffectorTask(trajectory=trajectory, name="tool")
    with pytest.raises(ShapeError, match=r"^tool\.trajectory: " + SPATIAL):
        task.bind(spatial)
    # tracking it after binding is rejected too, and the previous target is kept
    bound = EndEffectorTask(position=[0.5, 0.1, 0.2], name="tool").bind(spatial)
    with pytest.raises(ShapeError, match=SPATIAL):
        bound.set_target(trajectory=trajectory)
    np.testing.assert_allclose(bound.target(0.0)[0], [0.5, 0.1, 0.2])
    # a planar model accepts it
    EndEffectorTask(trajectory=trajectory, name="tool").bind(planar)


def test_same_message_as_a_two_coordinate_position(spatial):
    with pytest.raises(ShapeError) as position_error:
        EndEffectorTask(position=[0.5, 0.1], name="tool").bind(spatial)
    with pytest.raises(ShapeError) as trajectory_error:
        EndEffectorTask(trajectory=FixedTarget([0.5, 0.1]), name="tool").bind(spatial)
    assert str(position_error.value).split(": ", 1)[1] == str(trajectory_error.value).split(
        ": ", 1)[1]


class _FlatTrajectory:
    """A trajectory that does not follow the contract: 2-vector positions and no dimension."""

    duration = 1.0

    def sample(self, t):
        class S:
            position = np.array([0.5, 0.1])
            velocity = np.zeros(2)
            rotation = None
            angular_velocity = None

        return S()


def test_a_duck_typed_trajectory_is_sampled_at_bind(spatial, planar):
    with pytest.raises(ShapeError, match=SPATIAL):
        EndEffectorTask(trajectory=_FlatTrajectory(), name="tool").bind(spatial)
    with pytest.raises(ShapeError, match=r"sample\(t\)\.position has 2 coordinates; expected 3"):
        EndEffectorTask(trajectory=_FlatTrajectory(), name="tool").bind(planar)



def test_a_posture_outside_the_joint_limits_names_the_joint_the_angle_and_the_limits(rov):
    lower, upper = rov.joint_lower, rov.joint_upper
    assert np.isfinite(lower).all() and np.isfinite(upper).all()
    inside = 0.5 * (lower + upper)
    beyond = inside.copy()
    beyond[2] = upper[2] + 0.1
    joint = rov.joint_names[2]
    message = (f"reach.posture: joint {joint!r} = {beyond[2]:g} is outside its limits "
               f"[{lower[2]:g}, {upper[2]:g}]")
    with pytest.raises(InputError, match=re.escape(message)):
        PostureTask(posture=beyond, name="reach").bind(rov)
    task = PostureTask(posture=inside, name="reach").bind(rov)
    with pytest.raises(InputError, match=re.escape(message)):  # at run time, once bound
        task.update(posture=beyond)
    state = rov.state(rov.home())
    np.testing.assert_allclose(task.rows(state, 0.0).lower, inside - state.joints)  # unchanged
    PostureTask(posture=upper, name="reach").bind(rov)  # the limits themselves are reachable
    # a joint without limits accepts any angle
    free = Model.from_dh([DHRow(a=0.3), DHRow(a=0.2, lower=-1.0, upper=1.0)], vehicle="planar")
    PostureTask(posture=[10.0, 0.5]).bind(free)
    with pytest.raises(InputError, match=r"joint '\w+' = 2 is outside its limits \[-1, 1\]"):
        PostureTask(posture=[10.0, 2.0]).bind(free)

class _TupleTrajectory:
    """``sample(t)`` returns a bare ``(position, velocity)`` tuple from ``start`` [s] on."""

    def __init__(self, position, start):
        self.position, self.start = np.asarray(position, dtype=float), start

    def sample(self, t):
        if t < self.start:
            return SimpleNamespace(position=self.position, velocity=None)
        return self.position, np.zeros(3)


def test_a_trajectory_sampling_a_tuple_names_the_task_and_what_sample_must_return(spatial):
    position = spatial.frame_pose(spatial.home(), "tool")[:3, 3]
    expected = (r"task 'reach': trajectory\.sample\(t\) returned a tuple; "
                r"expected a TrajectorySample")
    with pytest.raises(InputError, match=expected):  # at bind
        EndEffectorTask(trajectory=_TupleTrajectory(position, 0.0), name="reach").bind(spatial)
    task = EndEffectorTask(trajectory=_TupleTrajectory(position, 0.05), name="reach")
    state = spatial.state(spatial.home())
    task.bind(spatial).rows(state, 0.0)
    with pytest.raises(InputError, match=expected):  # at a later tick
        task.rows(state, 0.05)


class _ShrinkingTrajectory:
    """Valid samples at bind time (t = 0), then ``key`` loses a coordinate (or rotation a row)."""

    def __init__(self, position, key):
        self.position, self.key = position, key

    def sample(self, t):
        values = {"position": self.position, "velocity": np.zeros(3), "rotation": np.eye(3),
                  "angular_velocity": np.zeros(3)}
        if t > 0.0:
            values[self.key] = values[self.key][:2]
        return SimpleNamespace(**values)


@pytest.mark.parametrize(
    ("key", "mode", "expected"),
    [("position", "position", "(3,)"), ("velocity", "position", "(3,)"),
     ("rotation", "pose", "(3, 3)"), ("angular_velocity", "orientation", "(3,)")],
)
def test_a_trajectory_sample_changing_shape_after_bind_names_the_task_and_the_shape(
        spatial, key, mode, expected):
    position = spatial.frame_pose(spatial.home(), "tool")[:3, 3]
    task = EndEffectorTask(trajectory=_ShrinkingTrajectory(position, key), mode=mode,
                           name="reach").bind(spatial)
    state = spatial.state(spatial.home())
    task.rows(state, 0.0)
    with pytest.raises(ShapeError, match=re.escape(
            f"task 'reach': trajectory.sample(0.05).{key} has shape (2") + r".*expected "
            + re.escape(expected)):
        task.rows(state, 0.05)


@pytest.mark.parametrize(
    ("mode", "axes", "needs"),
    [
        ("position", ["x", "rz"], "'rz' needs mode = \"orientation\" or \"pose\""),
        ("orientation", ["rz", "x"], "'x' needs mode = \"position\" or \"pose\""),
    ],
)
def test_axes_of_another_mode_name_the_mode_they_need(mode, axes, needs):
    with pytest.raises(InputError) as info:
        EndEffectorTask(mode=mode, axes=axes, name="tool")
    assert str(info.value).startswith("tool.axes: ")
    assert needs in str(info.value)
    EndEffectorTask(mode="pose", axes=axes, name="tool")  # both kinds are pose axes


def test_axes_typo_is_still_an_unknown_axis():
    with pytest.raises(InputError, match=r"unknown axis 'q'; known axes: x, y, z"):
        EndEffectorTask(axes=["x", "q"])


# ------------------------------------------------------------------------------ task arguments
# (id, callable taking the model, error type, fragment of the message naming the culprit)
BAD_TASKS = [
    ("target NaN", lambda m: EndEffectorTask(position=[0.0, math.nan, 0.0]), NonFiniteError,
     "position"),
    ("target wrong length", lambda m: EndEffectorTask(position=[0.0, 1.0, 2.0, 3.0]),
     ShapeError, "position"),
    ("gain negative", lambda m: EndEffectorTask(position=[0, 0, 0], gain=-1.0), InputError,
     "gain"),
    ("gain NaN", lambda m: PostureTask(gain=math.nan), NonFiniteError, "gain"),
    ("gains list with a negative", lambda m: PostureTask(gain=[1.0, -1.0, 1.0, 1.0]),
     InputError, "gain"),
    ("weight zero", lambda m: PostureTask(weight=0.0), InputError, "weight"),
    ("weight NaN", lambda m: PostureTask(weight=math.nan), NonFiniteError, "weight"),
    ("weight negative", lambda m: StationKeepingTask(weight=-2.0), InputError, "weight"),
    ("level not a task", lambda m: Level("posture"), InputError, "Task"),
    ("axis unknown", lambda m: StationKeepingTask(axes=["x", "w"]).bind(m), InputError, "w"),
]


@pytest.mark.parametrize("build, error, fragment", bad_cases(BAD_TASKS))
def test_bad_task_argument_is_raised_with_its_culprit(rov, build, error, fragment):
    assert_names_culprit(build, error, fragment, rov)
