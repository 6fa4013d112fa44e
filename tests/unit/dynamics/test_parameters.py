"""BodyParameters and PlantParameters: validation, scaling for sweeps, read-only values."""

import pickle

import numpy as np
import pytest

from tests.support.floating import rigid_inertia
from uvms_qp.dynamics import BodyParameters, PlantParameters
from uvms_qp.errors import ParameterError


def body(**changes):
    values = dict(mass=2.0, inertia=[0.1, 0.2, 0.25], centre_of_gravity=[0.1, 0.0, 0.02],
                  volume=0.002, centre_of_buoyancy=[0.1, 0.0, -0.01],
                  added_mass=[1.0, 2.0, 3.0, 0.1, 0.1, 0.1],
                  linear_damping=[1, 2, 3, 0.1, 0.1, 0.1],
                  quadratic_damping=[10, 20, 30, 1, 1, 1], source="test")
    values.update(changes)
    return BodyParameters(**values)


def plant(**changes):
    values = dict(name="test", vehicle=body(), links={"j1": body(mass=0.5)})
    values.update(changes)
    return PlantParameters(**values)


@pytest.mark.parametrize(("field", "value", "words"), [
    ("mass", -1.0, ">= 0"),
    ("mass", True, "expected a number"),
    ("mass", float("nan"), "finite"),
    ("volume", -1e-3, ">= 0"),
    ("inertia", [[0.1, 0.01, 0], [0, 0.2, 0], [0, 0, 0.25]], "symmetric"),
    ("inertia", [0.1, -0.2, 0.25], "semidefinite"),
    ("inertia", [0.1, 0.1, 0.5], "triangle inequality"),
    ("inertia", [0.1, 0.2], "shape"),
    ("centre_of_gravity", [0.0, 0.0], "shape"),
    ("centre_of_buoyancy", [0.0, "a", 0.0], "expected numbers"),
    ("added_mass", np.eye(6) + np.triu(np.ones((6, 6)), 1) * 0.1, "symmetric"),
    ("added_mass", np.diag([1, 1, 1, 1, 1, -0.5]), "semidefinite"),
    ("added_mass", np.ones((5, 5)), "shape"),
    ("added_mass", [1, 2, 3, 4, 5, float("inf")], "NaN or inf"),
    ("linear_damping", [1, 2, 3, 4, 5, -6], ">= 0"),
    ("quadratic_damping", [1, 2, 3], "shape"),
    ("source", 3, "string"),
])
def test_a_bad_body_value_names_its_field(field, value, words):
    with pytest.raises(ParameterError, match=words) as info:
        body(**{field: value})
    assert info.value.path == field
    assert str(info.value).startswith(field)


def test_body_stores_read_only_full_matrices():
    b = body()
    assert b.inertia.shape == (3, 3) and b.added_mass.shape == (6, 6)
    np.testing.assert_array_equal(np.diag(b.added_mass), [1, 2, 3, 0.1, 0.1, 0.1])
    with pytest.raises(ValueError):
        b.added_mass[0, 0] = 5.0
    assert body() == body()
    assert body() != body(mass=2.5)


def test_rigid_inertia_is_the_spatial_inertia_at_the_origin():
    b = body()
    np.testing.assert_allclose(b.rigid_inertia(), rigid_inertia(b), atol=1e-15)


@pytest.mark.parametrize(("changes", "path", "words"), [
    (dict(name=""), "name", "non-empty"),
    (dict(vehicle=body(mass=0.0)), "vehicle.mass", "positive mass"),
    (dict(vehicle="hull"), "vehicle", "BodyParameters"),
    (dict(links=[body()]), "links", "mapping"),
    (dict(links={"j1": 3}), "links.j1", "BodyParameters"),
    (dict(joint_servo_time_constant=0.0), "joint_servo_time_constant", "> 0"),
    (dict(water_density=-1.0), "water_density", ">= 0"),
    (dict(gravity=float("inf")), "gravity", "finite"),
    (dict(rated_payload=0.0), "rated_payload", "> 0"),
])
def test_a_bad_plant_value_names_its_path(changes, path, words):
    with pytest.raises(ParameterError, match=words) as info:
        plant(**changes)
    assert info.value.path == path


def test_links_are_read_only():
    p = plant()
    with pytest.raises(TypeError):
        p.links["j2"] = body()  # type: ignore[index]


def test_scaling_multiplies_the_named_quantities_and_leaves_the_rest():
    p = plant(links={"j1": body(mass=0.5), "j2": body(mass=0.7)})
    s = p.scaled({"vehicle.added_mass": 1.5, "links.mass": 2.0, "links.j2.mass": 3.0,
                  "water_density": 0.9, "vehicle.centre_of_buoyancy": 2.0})
    np.testing.assert_allclose(s.vehicle.added_mass, 1.5 * p.vehicle.added_mass)
    assert s.links["j1"].mass == pytest.approx(1.0)
    assert s.links["j2"].mass == pytest.approx(0.7 * 6.0)
    assert s.water_density == pytest.approx(0.9 * p.water_density)
    np.testing.assert_allclose(s.vehicle.centre_of_buoyancy, [0.2, 0.0, -0.02])
    np.testing.assert_array_equal(s.vehicle.inertia, p.vehicle.inertia)
    assert p.links["j1"].mass == 0.5  # the original is unchanged
    assert p.scaled({}) == p


@pytest.mark.parametrize(("path", "factor", "named", "words"), [
    ("vehicle.added_mass", -1.0, "vehicle.added_mass", "semidefinite"),
    ("vehicle.mass", -0.5, "vehicle.mass", ">= 0"),
    ("vehicle.mass", 0.0, "vehicle.mass", "positive mass"),
    ("links.volume", -1.0, "links.j1.volume", ">= 0"),
    ("links.j1.inertia", -2.0, "links.j1.inertia", "semidefinite"),
    ("joint_servo_time_constant", 0.0, "joint_servo_time_constant", "> 0"),
    ("vehicle.linear_damping", -1.0, "vehicle.linear_damping", ">= 0"),
])
def test_a_factor_that_breaks_physics_names_the_path(path, factor, named, words):
    with pytest.raises(ParameterError, match=words) as info:
        plant().scaled({path: factor})
    assert info.value.path == named
    assert f"scaling {path} by {factor:g}" in str(info.value)


@pytest.mark.parametrize(("factors", "words"), [
    ({"vehicle.colour": 2.0}, "unknown parameter path"),
    ({"links.j9.mass": 2.0}, "no link for joint 'j9'"),
    ({"vehicle.mass": float("nan")}, "finite"),
    ({"vehicle.mass": "2"}, "expected a number"),
])
def test_a_bad_scaling_request_is_refused(factors, words):
    with pytest.raises(ParameterError, match=words):
        plant().scaled(factors)


def test_with_changes_validates_and_refuses_unknown_fields():
    with pytest.raises(ParameterError, match="unknown field"):
        plant().with_changes(colour="red")
    with pytest.raises(ParameterError, match="gravity"):
        plant().with_changes(gravity=-9.81)
    assert plant().with_changes(thrusters="layout").thrusters == "layout"


def test_parameters_pickle_for_the_workers_of_a_sweep(heavy):
    copy = pickle.loads(pickle.dumps(heavy.scaled({"links.mass": 1.2})))
    assert copy == heavy.scaled({"links.mass": 1.2})
    assert not copy.vehicle.added_mass.flags.writeable
    with pytest.raises(TypeError):
        copy.links["extra"] = copy.vehicle  # type: ignore[index]
