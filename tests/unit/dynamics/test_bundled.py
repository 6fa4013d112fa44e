"""The bundled parameter sets: published numbers in the FRD frame, the arm assumption, registry."""

import math

import numpy as np
import pytest

from tests.support.floating import neutral_vehicle_only
from uvms_qp.dynamics import (
    FloatingPlant,
    default_plant_parameters,
    plant_parameter_sets,
    plant_parameters,
)
from uvms_qp.dynamics.bundled import (
    ARM_MASS,
    ARM_VOLUME,
    CROSS_FLOW_ADDED_MASS_COEFFICIENT,
    CROSS_FLOW_DRAG_COEFFICIENT,
    link_segments,
)
from uvms_qp.errors import PlantDataError, UnknownParameterSetError


def test_von_benzon_set_is_the_published_heavy_in_frd(heavy):
    v = heavy.vehicle
    assert v.mass == 13.5 and v.volume == 0.0134
    assert heavy.water_density == 1000.0 and heavy.gravity == 9.82
    # published as negative derivatives: stored as positive magnitudes
    np.testing.assert_array_equal(np.diag(v.added_mass), [6.36, 7.12, 18.68, 0.189, 0.135, 0.222])
    np.testing.assert_array_equal(v.quadratic_damping, [141, 217, 190, 1.19, 0.47, 1.5])
    # origin at the CG, buoyancy 1 cm *above* it: z is down in FRD
    np.testing.assert_array_equal(v.centre_of_gravity, 0.0)
    np.testing.assert_array_equal(v.centre_of_buoyancy, [0.0, 0.0, -0.01])


def test_wu_set_has_its_published_weight_and_buoyancy(wu):
    v = wu.vehicle
    assert v.mass * wu.gravity == pytest.approx(112.8, abs=0.05)
    assert wu.water_density * wu.gravity * v.volume == pytest.approx(114.8, abs=1e-9)
    assert v.centre_of_gravity[2] - v.centre_of_buoyancy[2] == pytest.approx(0.02)


@pytest.mark.parametrize(("name", "head_on", "beam_on"), [
    ("heavy", 16.8, 19.5),   # facts: 16.8 N and 19.5 N in a 0.3 m/s current
    ("wu", 2.85, 3.82),      # about 6x smaller
])
def test_station_keeping_force_in_a_current_has_the_published_magnitude(rov, request, name,
                                                                        head_on, beam_on):
    params = neutral_vehicle_only(request.getfixturevalue(name))
    plant = FloatingPlant(rov, params)
    q, v = rov.configuration(np.zeros(6), rov.home()[7:]), np.zeros(plant.nv)
    M = plant.mass_matrix(q)[:6, :6]
    for direction, expected in (([0.3, 0, 0], head_on), ([0, 0.3, 0], beam_on)):
        plant.current = direction
        v_dot, _ = plant.accelerations(q, v, np.zeros(6), np.zeros(4))
        drag = M @ v_dot[:6]          # the water's force on the still vehicle, body axes
        axis = int(np.argmax(direction))
        assert drag[axis] == pytest.approx(expected, abs=0.05)  # pushed along the current


def test_arm_totals_and_split_by_length(rov, heavy):
    links = heavy.links
    assert sum(b.mass for b in links.values()) == pytest.approx(ARM_MASS)
    assert sum(b.volume for b in links.values()) == pytest.approx(ARM_VOLUME)
    segments = link_segments(rov)
    lengths = {k: np.linalg.norm(s) for k, s in segments.items()}
    for joint, b in links.items():
        assert b.mass / ARM_MASS == pytest.approx(lengths[joint] / sum(lengths.values()))


def test_both_sets_carry_the_arm_s_rated_payload_and_it_survives_a_copy(heavy, wu):
    import pickle

    # the vendor's figure: about 2 kg at full reach (mass in air)
    assert heavy.rated_payload == 2.0 and wu.rated_payload == 2.0
    assert pickle.loads(pickle.dumps(heavy)).rated_payload == 2.0
    assert heavy.with_changes(rated_payload=3.0) != heavy


def test_link_centres_are_midway_between_consecutive_joints_in_the_world(rov, heavy):
    q = rov.home()
    frames = ["m2_1_1_link", "m2_joint_link", "m2_1_2_link", "m1_link", "tool"]
    for k, joint in enumerate(rov.joint_names):
        T = rov.frame_pose(q, frames[k])
        start, end = T[:3, 3], rov.frame_pose(q, frames[k + 1])[:3, 3]
        for point in (heavy.links[joint].centre_of_gravity,
                      heavy.links[joint].centre_of_buoyancy):
            np.testing.assert_allclose(T[:3, :3] @ point + T[:3, 3], 0.5 * (start + end),
                                       atol=1e-12)


def _strips(segment, n=4000):
    length = np.linalg.norm(segment)
    s = (np.arange(n) + 0.5) / n * length
    return segment / length, s, length / n


def _skews(points):
    out = np.zeros((len(points), 3, 3))
    out[:, 0, 1], out[:, 0, 2], out[:, 1, 2] = -points[:, 2], points[:, 1], -points[:, 0]
    return out - out.transpose(0, 2, 1)


def test_link_added_mass_is_strip_theory_of_its_cylinder(rov, heavy):
    rho = heavy.water_density
    for joint, segment in link_segments(rov).items():
        b = heavy.links[joint]
        u, s, ds = _strips(segment)
        length = np.linalg.norm(segment)
        radius = math.sqrt(b.volume / (math.pi * length))
        per_length = CROSS_FLOW_ADDED_MASS_COEFFICIENT * rho * math.pi * radius ** 2
        P = np.eye(3) - np.outer(u, u)  # cross-flow only
        # a strip at r moves at v + w x r = G [v; w]
        G = np.concatenate((np.broadcast_to(np.eye(3), (len(s), 3, 3)),
                            -_skews(s[:, None] * u)), axis=2)
        expected = np.einsum("nki,kl,nlj->ij", G, per_length * ds * P, G)
        np.testing.assert_allclose(b.added_mass, expected, rtol=1e-6, atol=1e-9)


def test_link_swing_damping_is_the_integrated_cross_flow_drag(rov, heavy):
    rho = heavy.water_density
    for joint, segment in link_segments(rov).items():
        b = heavy.links[joint]
        u, s, ds = _strips(segment)
        points = s[:, None] * u
        length = np.linalg.norm(segment)
        diameter = 2.0 * math.sqrt(b.volume / (math.pi * length))
        for k in range(3):
            # unit rate about axis k through the joint: drag moment about that axis
            velocity = np.cross(np.eye(3)[k], points)
            force = (-0.5 * rho * CROSS_FLOW_DRAG_COEFFICIENT * diameter * ds
                     * np.linalg.norm(velocity, axis=1)[:, None] * velocity)
            moment = np.cross(points, force).sum(axis=0)[k]
            assert b.quadratic_damping[3 + k] == pytest.approx(-moment, rel=1e-5, abs=1e-12)


def test_registry_lists_sets_and_names_what_is_missing(rov, models):
    assert set(plant_parameter_sets()) >= {"bluerov2_heavy_von_benzon_2022", "bluerov2_wu_2018"}
    assert default_plant_parameters(rov).name == "bluerov2_heavy_von_benzon_2022"
    assert default_plant_parameters("bluerov2_heavy_alpha5") is plant_parameters(
        "bluerov2_heavy_von_benzon_2022")
    with pytest.raises(UnknownParameterSetError, match="bluerov2_wu_2018"):
        plant_parameters("bluerov3")
    with pytest.raises(PlantDataError, match=r"'wang_9dof' has no plant parameters.*mass"):
        default_plant_parameters(models["wang_9dof"])


def test_every_number_carries_a_source(heavy, wu):
    for params in (heavy, wu):
        assert params.source
        for b in params.bodies().values():
            assert b.source
    assert "von Benzon" in heavy.vehicle.source and "Wu (2018)" in wu.vehicle.source
    assert "Alpha-5-like" in heavy.links["axis_b"].source
