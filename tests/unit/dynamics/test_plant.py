"""FloatingPlant's interface: which models, inputs, servos, joint torques, payload, faults."""

import math

import numpy as np
import pinocchio as pin
import pytest

from tests.support import floating as ref
from uvms_qp.dynamics import DEFAULT_STEP, FloatingPlant, FunctionCurrent
from uvms_qp.errors import (
    InputError,
    ModelError,
    NonFiniteError,
    PlantDataError,
    ShapeError,
    SimulationDiverged,
    UnknownParameterSetError,
)


@pytest.fixture(scope="module")
def plant(rov):
    return FloatingPlant(rov)


def test_default_plant_of_the_bundled_uvms(plant, rov):
    assert plant.parameters.name == "bluerov2_heavy_von_benzon_2022"
    assert (plant.nq, plant.nv, plant.n_joints) == (rov.nq, 10, 4)
    assert plant.physics_step == DEFAULT_STEP
    assert "bluerov2_heavy_alpha5" in repr(plant)
    assert FloatingPlant(rov, "bluerov2_wu_2018").parameters.name == "bluerov2_wu_2018"
    with pytest.raises(UnknownParameterSetError):
        FloatingPlant(rov, "nope")


@pytest.mark.parametrize(("name", "error", "words"), [
    ("soylu_planar", ModelError, "planar vehicle"),
    ("nenchev_pa10_arm", ModelError, "fixed vehicle"),
    ("wang_9dof", PlantDataError, "'wang_9dof' has no plant parameters"),
])
def test_models_the_plant_cannot_float_are_refused(models, name, error, words):
    with pytest.raises(error, match=words):
        FloatingPlant(models[name])


def test_parameters_must_cover_the_models_joints(rov, heavy):
    links = dict(heavy.links)
    links.pop("axis_c")
    links["wrist"] = heavy.links["axis_c"]
    with pytest.raises(PlantDataError, match=r"no link body for joint\(s\) \['axis_c'\].*"
                                             r"unknown joint\(s\) \['wrist'\]"):
        FloatingPlant(rov, heavy.with_changes(links=links))


@pytest.mark.parametrize(("argument", "value", "error", "words"), [
    ("wrench", np.zeros(5), ShapeError, "wrench"),
    ("wrench", [0, 0, float("nan"), 0, 0, 0], NonFiniteError, "wrench"),
    ("joint_reference", np.zeros(3), ShapeError, "joint_reference"),
    ("v", np.zeros(9), ShapeError, "v"),
    ("q", np.zeros(5), ShapeError, "q"),
    ("t", "now", InputError, "t"),
])
def test_bad_inputs_are_named(plant, rov, argument, value, error, words):
    args = dict(q=rov.home(), v=np.zeros(10), wrench=np.zeros(6),
                joint_reference=np.zeros(4), t=0.0)
    args[argument] = value
    with pytest.raises(error, match=words):
        plant.accelerations(**args)
    with pytest.raises(error, match=words):
        plant.step(**args)


def test_joints_follow_first_order_servos(plant, rov, heavy):
    v = np.array([0.1, 0, 0, 0, 0.2, 0, 0.3, -0.2, 0.0, 0.1])
    reference = np.array([0.5, 0.0, -0.4, 0.1])
    v_dot, _ = plant.accelerations(rov.home(), v, np.zeros(6), reference)
    np.testing.assert_allclose(v_dot[6:], (reference - v[6:]) / heavy.joint_servo_time_constant)
    # over one step the joint rates move by the exact first-order lag (to RK4's accuracy)
    _, v_new = plant.step(rov.home(), v, np.zeros(6), reference, 0.0, 0.01)
    tau = heavy.joint_servo_time_constant
    np.testing.assert_allclose(v_new[6:], reference + (v[6:] - reference) * math.exp(-0.01 / tau),
                               atol=1e-4 * np.abs(reference - v[6:]).max())


def test_holding_the_uvms_still_needs_the_restoring_wrench_and_gravity_torques(plant, rov,
                                                                               heavy):
    q = rov.configuration([0, 0, 0, 0.2, -0.1, 0.3], rov.home()[7:])
    wrench = plant.restoring_wrench(q)
    v_dot, torques = plant.accelerations(q, np.zeros(10), wrench, np.zeros(4))
    np.testing.assert_allclose(v_dot, 0.0, atol=1e-12)
    # each servo holds the moment of the weights and buoyancies outboard of its joint
    data = rov.pin_model.createData()
    pin.computeJointJacobians(rov.pin_model, data, q)
    forces = ref.world_forces(rov, heavy, q)[2:]   # the links' (the vehicle's two first)
    for k, joint in enumerate(rov.joint_names):
        M = data.oMi[rov.pin_model.getJointId(joint)]
        axis = data.J[3:, 6 + k]                   # the joint's axis, world
        moment = sum(np.cross(point - M.translation, force)
                     for point, force in forces[2 * k:])
        assert torques[k] == pytest.approx(-axis @ moment, abs=1e-12)


def test_a_payload_adds_its_net_weight_and_a_spheres_inertia_at_the_tool(rov, heavy):
    plant = FloatingPlant(rov, heavy)
    q = rov.configuration([0, 0, 0, 0.3, 0.2, -0.4], rov.home()[7:])
    before, M_before = plant.restoring_wrench(q), plant.mass_matrix(q)
    mass, volume, offset = 1.2, 4e-4, np.array([0.0, 0.0, 0.05])
    payload = plant.attach_payload(mass, volume, offset=offset)
    assert (payload.mass, payload.volume) == (mass, volume)
    T_tool = rov.frame_pose(q, "tool")
    centre = T_tool[:3, :3] @ offset + T_tool[:3, 3]
    R, p = rov.frame_pose(q, "vehicle")[:3, :3], rov.frame_pose(q, "vehicle")[:3, 3]
    net = R.T @ np.array([0.0, 0.0, (mass - heavy.water_density * volume) * heavy.gravity])
    expected = -np.concatenate((net, np.cross(R.T @ (centre - p), net)))
    np.testing.assert_allclose(plant.restoring_wrench(q) - before, expected, atol=1e-12)
    # the mass matrix gains J^T M_sphere J at the payload's centre (its axes: the tool's)
    radius = (3 * volume / (4 * math.pi)) ** (1 / 3)
    M_sphere = np.diag([mass + 0.5 * heavy.water_density * volume] * 3
                       + [0.4 * mass * radius ** 2] * 3)
    pm = rov.pin_model
    data = pm.createData()
    pin.framesForwardKinematics(pm, data, q)
    pin.computeJointJacobians(pm, data, q)
    fid = rov.frame_id("tool")
    J = pin.getFrameJacobian(pm, data, fid, pin.ReferenceFrame.LOCAL)
    J = pin.SE3(np.eye(3), offset).inverse().action @ J    # the tool frame moved to the centre
    np.testing.assert_allclose(plant.mass_matrix(q) - M_before, J.T @ M_sphere @ J, atol=1e-12)
    assert plant.detach_payload() == payload
    np.testing.assert_array_equal(plant.restoring_wrench(q), before)
    assert plant.detach_payload() is None


def test_relative_velocity_subtracts_the_current_in_body_axes(rov, heavy):
    plant = FloatingPlant(rov, heavy, current=[0.3, 0.0, 0.1])
    q = rov.configuration([0, 0, 0, 0, 0, math.pi / 2], rov.home()[7:])  # heading east
    v = np.array([0.5, 0, 0, 0, 0, 0.1, 0, 0, 0, 0])
    # north current seen from a vehicle heading east comes from its left: -y in FRD
    np.testing.assert_allclose(plant.relative_velocity(q, v), [0.5, 0.3, -0.1, 0, 0, 0.1],
                               atol=1e-12)


def test_a_diverging_step_raises_with_time_and_state(rov, heavy):
    surge = FunctionCurrent(lambda t: [1e3 * max(t - 0.02, 0.0) ** 2, 0.0, 0.0])  # [m/s]
    plant = FloatingPlant(rov, heavy, current=surge)
    q, v = rov.home(), np.zeros(10)
    with pytest.raises(SimulationDiverged, match=r"t = 0.\d+ s .*beyond the sanity bound") as e:
        for k in range(100):
            q, v = plant.step(q, v, np.zeros(6), np.zeros(4), k * DEFAULT_STEP)
    err = e.value
    assert err.t > 0.02 and err.q.shape == (rov.nq,) and err.v.shape == (10,)
    assert np.isfinite(err.v).all() and "velocity" in err.reason


def test_step_returns_new_arrays_and_keeps_the_quaternion_unit(plant, rov):
    q, v = rov.home(), np.array([0.2, 0.1, 0, 0.5, -0.3, 0.8, 0.1, 0.1, 0.1, 0.1])
    q0, v0 = q.copy(), v.copy()
    for _ in range(200):
        q, v = plant.step(q, v, np.zeros(6), np.full(4, 0.1))
    np.testing.assert_array_equal(rov.home(), q0)
    assert np.array_equal(v0, np.array([0.2, 0.1, 0, 0.5, -0.3, 0.8, 0.1, 0.1, 0.1, 0.1]))
    assert abs(np.linalg.norm(q[3:7]) - 1.0) < 1e-14
