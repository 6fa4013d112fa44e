"""Plant parameters from a TOML file: the example loads, every fault names file, key and value."""

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

from uvms_qp.dynamics import FloatingPlant, ThrusterLayout, load_plant_parameters
from uvms_qp.errors import ModelFileError, ParameterError

EXAMPLE = Path(str(resources.files("uvms_qp.dynamics").joinpath("data/example_plant.toml")))

VEHICLE = """
[vehicle]
mass = 13.5
inertia = [0.26, 0.23, 0.37]
centre_of_gravity = [0.0, 0.0, 0.0]
volume = 0.0134
centre_of_buoyancy = [0.0, 0.0, -0.01]
added_mass = [6.36, 7.12, 18.68, 0.189, 0.135, 0.222]
linear_damping = [13.7, 0.0, 33.0, 0.0, 0.8, 0.0]
quadratic_damping = [141.0, 217.0, 190.0, 1.19, 0.47, 1.5]
"""

LINK = """
[links.{name}]
mass = 0.3
inertia = [[1e-4, 0, 0], [0, 1e-4, 0], [0, 0, 1e-5]]
centre_of_gravity = [0, 0, 0.05]
volume = 1.5e-4
centre_of_buoyancy = [0, 0, 0.05]
added_mass = [0.1, 0.1, 0, 0, 0, 0]
linear_damping = [0, 0, 0, 0, 0, 0]
quadratic_damping = [1, 1, 0.2, 0.01, 0.01, 0]
"""


def write(tmp_path, text, name="plant.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def full_file(**top):
    head = "\n".join(f"{k} = {v}" for k, v in {"name": '"mine"', **top}.items())
    links = "".join(LINK.format(name=j) for j in ("axis_e", "axis_d", "axis_c", "axis_b"))
    return head + "\n" + VEHICLE + links


def test_the_documented_example_loads_and_drives_a_plant(rov):
    params = load_plant_parameters(EXAMPLE)
    assert params.name == "my_bluerov2_heavy"
    assert params.water_density == 1025.0
    assert params.links["axis_b"].mass == 0.55
    assert params.links["axis_d"].mass > 0.5  # kept from the base set
    plant = FloatingPlant(rov, params)
    v_dot, _ = plant.accelerations(rov.home(), np.zeros(plant.nv), np.zeros(6), np.zeros(4))
    assert np.isfinite(v_dot).all()


def test_a_file_states_its_arm_s_rated_payload_or_keeps_its_base_s(tmp_path):
    assert load_plant_parameters(write(tmp_path, full_file())).rated_payload is None
    assert load_plant_parameters(write(tmp_path, full_file(rated_payload=4.5))).rated_payload \
        == 4.5
    based = 'name = "x"\nbase = "bluerov2_wu_2018"\n'
    assert load_plant_parameters(write(tmp_path, based)).rated_payload == 2.0


def test_a_complete_file_needs_no_base(tmp_path, rov):
    params = load_plant_parameters(write(tmp_path, full_file(water_density=1025.0)))
    assert params.vehicle.mass == 13.5 and params.water_density == 1025.0
    np.testing.assert_array_equal(params.links["axis_e"].inertia, np.diag([1e-4, 1e-4, 1e-5]))
    FloatingPlant(rov, params)


@pytest.mark.parametrize(("text", "key", "words"), [
    ("colour = 'red'\n" + full_file(), "colour", "unknown key"),
    (full_file().replace("mass = 13.5", "mass = 13.5\ncolor = 1"), "vehicle.color",
     "unknown key"),
    (full_file().replace("[links.axis_b]\nmass = 0.3", "[links.axis_b]\nmas = 0.3"),
     "links.axis_b.mas", "unknown key"),
    (full_file().replace("mass = 13.5", "mass = -13.5"), "vehicle.mass", ">= 0"),
    (full_file().replace("volume = 0.0134", "volume = -0.0134"), "vehicle.volume", ">= 0"),
    (full_file().replace("added_mass = [6.36, 7.12, 18.68, 0.189, 0.135, 0.222]",
                         "added_mass = [[1,0.5,0,0,0,0],[0,1,0,0,0,0],[0,0,1,0,0,0],"
                         "[0,0,0,1,0,0],[0,0,0,0,1,0],[0,0,0,0,0,1]]"),
     "vehicle.added_mass", "symmetric"),
    (full_file().replace("added_mass = [6.36, 7.12, 18.68, 0.189, 0.135, 0.222]",
                         "added_mass = [6.36, 7.12, -18.68, 0.189, 0.135, 0.222]"),
     "vehicle.added_mass", "semidefinite"),
    (full_file().replace("centre_of_gravity = [0.0, 0.0, 0.0]", "centre_of_gravity = [0.0, 0.0]"),
     "vehicle.centre_of_gravity", "shape"),
    (full_file().replace("mass = 13.5", "mass = true"), "vehicle.mass", "expected a number"),
    (full_file().replace("mass = 13.5", "mass = '13.5'"), "vehicle.mass", "expected a number"),
    (full_file().replace("quadratic_damping = [141.0, 217.0, 190.0, 1.19, 0.47, 1.5]", ""),
     "vehicle.quadratic_damping", "missing"),
    (full_file(joint_servo_time_constant=0.0), "joint_servo_time_constant", "> 0"),
    (full_file(rated_payload=-2.0), "rated_payload", "> 0"),
    (full_file().replace('name = "mine"', ""), "name", "missing"),
    ('name = "x"\nbase = "nope"\n', "base", "unknown plant parameter set"),
    ('name = "x"\nbase = "bluerov2_wu_2018"\n[links.axis_b]\nvolume = -1.0\n',
     "links.axis_b.volume", ">= 0"),
    ('name = "x"\nvehicle = 3\n', "vehicle", "expected a table"),
], ids=lambda x: x if isinstance(x, str) and len(x) < 40 and "\n" not in x else "")
def test_a_bad_file_names_file_key_and_value(tmp_path, text, key, words):
    path = write(tmp_path, text)
    with pytest.raises(ParameterError, match=words) as info:
        load_plant_parameters(path)
    assert info.value.path == key
    assert info.value.file == str(path)
    assert str(info.value).startswith(f"{path}: {key}: ")


def test_the_message_shows_the_bad_value(tmp_path):
    path = write(tmp_path, full_file().replace("mass = 13.5", "mass = -13.5"))
    with pytest.raises(ParameterError, match=r"got -13\.5") as info:
        load_plant_parameters(path)
    assert info.value.value == -13.5


def test_a_file_that_cannot_be_read_is_a_model_file_error(tmp_path):
    with pytest.raises(ModelFileError, match="cannot read"):
        load_plant_parameters(tmp_path / "missing.toml")
    with pytest.raises(ModelFileError, match="not valid TOML"):
        load_plant_parameters(write(tmp_path, "name = [unclosed"))


def test_a_file_whose_links_miss_a_joint_fails_at_the_plant(tmp_path, rov):
    text = full_file().split("[links.axis_b]")[0]
    params = load_plant_parameters(write(tmp_path, text))
    with pytest.raises(Exception, match="axis_b"):
        FloatingPlant(rov, params)


FOUR_THRUSTERS = """
name = "quad"
base = "bluerov2_heavy_von_benzon_2022"
[[thrusters]]
position = [0.2, 0.1, 0.0]
axis = [1.0, 0.0, 0.0]
model = "T200"
[[thrusters]]
position = [0.2, -0.1, 0.0]
axis = [1.0, 0.0, 0.0]
model = "T200"
[[thrusters]]
position = [0.0, 0.0, 0.1]
axis = [0.0, 1.0, 0.0]
model = "T200"
voltage = 12.0
[[thrusters]]
position = [0.1, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
forward_limit = 20.0
reverse_limit = 10.0
time_constant = 0.05
power_forward = [1.0, 1.5]
power_reverse = [1.0, 1.5]
"""


def test_a_file_gives_its_own_thrusters_or_keeps_the_bases():
    assert isinstance(load_plant_parameters(EXAMPLE).thrusters, ThrusterLayout)


def test_own_thrusters_replace_the_bases_and_the_layout_is_checked(tmp_path):
    path = write(tmp_path, FOUR_THRUSTERS)
    with pytest.raises(ParameterError, match=r"thrusters: .*cannot produce") as info:
        load_plant_parameters(path)  # four thrusters cannot give six DOFs
    assert str(path) in str(info.value)
    text = FOUR_THRUSTERS.replace("[[thrusters]]", "[[thrusters.thrusters]]", 4)
    text = text.replace('base = "bluerov2_heavy_von_benzon_2022"\n',
                        'base = "bluerov2_heavy_von_benzon_2022"\n[thrusters]\n'
                        'actuated = ["u", "v", "w", "r"]\n')
    params = load_plant_parameters(write(tmp_path, text, "quad.toml"))
    layout = params.thrusters
    assert layout.size == 4 and layout.actuated == ("u", "v", "w", "r")
    # a T200 at 12 V against one given by hand
    np.testing.assert_allclose(layout.upper, [51.5, 51.5, 36.4, 20.0])
    np.testing.assert_allclose(layout.matrix[:, 0], [1, 0, 0, 0, 0, -0.1])  # r x a, FRD


@pytest.mark.parametrize(("change", "key"), [
    (("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 1.0]"), "thrusters[3].axis"),
    (("model = \"T200\"\nvoltage = 12.0", "model = \"T200\"\nvoltage = 13.0"), "thrusters[2]"),
    (("time_constant = 0.05", "time_constant = 0.05\nspin = 1"), "thrusters[3]"),
])
def test_a_bad_thruster_names_file_and_key(tmp_path, change, key):
    path = write(tmp_path, FOUR_THRUSTERS.replace(*change))
    with pytest.raises(ParameterError) as info:
        load_plant_parameters(path)
    assert f"{path}: {key}" in str(info.value)


def test_a_link_of_a_joint_the_base_lacks_says_so(tmp_path):
    path = write(tmp_path, 'name = "x"\nbase = "bluerov2_heavy_von_benzon_2022"\n'
                 "[links.axis_z]\nmass = 0.2\n")
    with pytest.raises(ParameterError, match=r"links\.axis_z\.inertia: missing: 'axis_z' is not "
                       r"a joint of the base set .*axis_e"):
        load_plant_parameters(path)


def test_a_body_a_file_changes_names_the_file_as_its_source(tmp_path):
    path = write(tmp_path, 'name = "x"\nbase = "bluerov2_heavy_von_benzon_2022"\n'
                 "[vehicle]\nmass = 14.0\n")
    params = load_plant_parameters(path)
    assert params.vehicle.source.startswith(f"{path} over von Benzon")
    assert params.links["axis_b"].source == load_plant_parameters(EXAMPLE).links[
        "axis_e"].source  # untouched links keep the base's
