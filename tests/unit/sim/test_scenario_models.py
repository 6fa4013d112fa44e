"""Models that are not bundled: ``[model]`` tables, model files, registered names, entry points.

The arm is ``tests/data/three_joint_arm.urdf`` (written for these tests); its forward kinematics
is checked against an independent numpy chain written from the file's numbers.
"""

from __future__ import annotations

import math
import shutil
import textwrap
import tomllib
from pathlib import Path

import numpy as np
import pytest

from uvms_qp import Model
from uvms_qp.cli import main
from uvms_qp.errors import ConfigError, InputError, ModelError, UnknownModelError
from uvms_qp.model import Vehicle, bundled_models, load_model, model_names
from uvms_qp.model.registry import register_model, unregister_model
from uvms_qp.sim.comparison import compare
from uvms_qp.sim.model_file import read_model_file, register_model_file
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario, scenario_from_dict
from uvms_qp.sim.view import plotly_available

DATA = Path(__file__).parents[2] / "data"
WALK = Path(__file__).parents[3] / "examples" / "own_robot" / "walk.toml"  # docs/own_robot.md
URDF = DATA / "three_joint_arm.urdf"
MODEL_FILE = DATA / "holdout_rov.toml"
SCENARIO = DATA / "holdout_reach.toml"


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def gripper_in_arm_base(q: np.ndarray) -> np.ndarray:
    """The gripper origin in the URDF root frame, from the joint origins of the file [m]."""
    yaw, shoulder, elbow = q
    forearm = _ry(shoulder) @ (np.array([0.35, 0.0, 0.0]) + _ry(elbow) @ np.array([0.30, 0, 0]))
    return np.array([0.0, 0.0, 0.08]) + _rz(yaw) @ (np.array([0.05, 0.0, 0.06]) + forearm)


@pytest.fixture
def registered():
    """Models registered by a test are forgotten afterwards."""
    names: list[str] = []
    yield names
    for name in names:
        unregister_model(name)


def _scenario_text(model_lines: str, joints: str = "[0.0, 0.6, 1.2]") -> str:
    return textwrap.dedent(f"""
        dt = 0.1
        duration = 0.5
        {model_lines}

        [initial]
        joints = {joints}

        [[levels]]
        [[levels.tasks]]
        type = "end_effector"
        name = "tool"
        position = [0.5707, 0.0, -0.1498]
    """)


# ---- [model] tables


def test_urdf_model_table_matches_the_file_and_the_mount():
    scenario = load_scenario(SCENARIO)
    model = scenario.model
    assert model.zeta_names == ("u", "v", "w", "r", "yaw", "shoulder", "elbow")
    assert model.passive == ("p", "q")
    assert "gripper" in model.frames and "forearm" in model.frames
    rng = np.random.default_rng(3)
    for _ in range(5):
        joints = rng.uniform(model.joint_lower, model.joint_upper)
        eta = np.array([1.0, -2.0, 3.0, 0.1, -0.2, 0.7])
        q = model.configuration(eta, joints)
        T = model.frame_pose(q, "vehicle")  # T_world_vehicle
        in_body = np.array([0.30, 0.0, 0.20]) + gripper_in_arm_base(joints)  # mount, FRD body
        expected = T[:3, :3] @ in_body + T[:3, 3]
        np.testing.assert_allclose(model.frame_pose(q, "tool")[:3, 3], expected, atol=1e-12)


def test_urdf_path_is_relative_to_the_scenario_file(tmp_path):
    (tmp_path / "arms").mkdir()
    shutil.copy(URDF, tmp_path / "arms" / "arm.urdf")
    text = SCENARIO.read_text().replace('urdf = "three_joint_arm.urdf"', 'urdf = "arms/arm.urdf"')
    (tmp_path / "mine.toml").write_text(text)
    assert load_scenario(tmp_path / "mine.toml").model.n_joints == 3
    (tmp_path / "arms" / "arm.urdf").unlink()
    with pytest.raises(ConfigError, match=r"^model\.urdf: URDF file not found: .*arms/arm\.urdf"):
        load_scenario(tmp_path / "mine.toml")


def test_a_missing_urdf_is_named_by_its_absolute_path_and_what_it_was_relative_to(
        tmp_path, monkeypatch):
    """Loaded from another folder by a relative path, the scenario's relative ``urdf`` is
    reported as the absolute file it looked for, and the folder it was taken relative to."""
    text = SCENARIO.read_text().replace('urdf = "three_joint_arm.urdf"', 'urdf = "arms/arm.urdf"')
    (tmp_path / "scenarios").mkdir()
    (tmp_path / "scenarios" / "mine.toml").write_text(text)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError) as info:
        load_scenario(Path("scenarios") / "mine.toml")
    folder = tmp_path / "scenarios"
    assert str(info.value) == (f"model.urdf: URDF file not found: {folder / 'arms' / 'arm.urdf'} "
                               f"('arms/arm.urdf' taken relative to {folder})")
    absolute = text.replace('urdf = "arms/arm.urdf"', f'urdf = "{tmp_path / "gone.urdf"}"')
    (tmp_path / "scenarios" / "mine.toml").write_text(absolute)
    with pytest.raises(ConfigError) as info:
        load_scenario(Path("scenarios") / "mine.toml")
    assert str(info.value) == f"model.urdf: URDF file not found: {tmp_path / 'gone.urdf'}"


def test_mount_in_ros_axes_is_converted_to_the_body_frame():
    mount = 'mount = { xyz = [0.3, 0.1, -0.2], rpy = [0.0, 0.0, 0.5], axes = "flu" }'
    text = _scenario_text(f'[model]\nurdf = "{URDF}"\n{mount}')
    model = scenario_from_dict(tomllib.loads(text)).model
    # FLU -> FRD: y and z change sign, and so does a yaw
    np.testing.assert_allclose(model.mount[:3, 3], [0.3, -0.1, 0.2], atol=1e-15)
    np.testing.assert_allclose(model.mount[:3, :3], _rz(-0.5) @ np.diag([1.0, -1.0, -1.0]),
                               atol=1e-15)


def test_dh_model_table_builds_what_from_dh_builds():
    rows = "\n".join(f'  {{ a = 1.0, name = "j{i}", lower = -3.0, upper = 3.0 }},'
                     for i in (1, 2, 3))
    lines = (f'[model]\nname = "my_planar"\nvehicle = "planar"\n'
             f'mount = {{ xyz = [1.0, 0.0, 0.0] }}\ndh = [\n{rows}\n]')
    text = _scenario_text(lines, "[0.3, -0.2, 0.4]").replace(
        "position = [0.5707, 0.0, -0.1498]", "position = [3.0, 1.0]")
    model = scenario_from_dict(tomllib.loads(text)).model
    assert model.name == "my_planar" and model.zeta_names == ("u", "v", "r", "j1", "j2", "j3")
    q = model.configuration([0.5, -1.0, 0.3], [0.3, -0.2, 0.4])
    # planar chain: base at (x, y) + R(psi) (1, 0), then three 1 m links
    angles = 0.3 + np.cumsum([0.3, -0.2, 0.4])
    base = np.array([0.5, -1.0]) + np.array([math.cos(0.3), math.sin(0.3)])
    expected = base + np.array([np.cos(angles).sum(), np.sin(angles).sum()])
    np.testing.assert_allclose(model.frame_pose(q, "tool")[:2, 3], expected, atol=1e-12)
    np.testing.assert_array_equal(model.joint_upper, [3.0, 3.0, 3.0])


@pytest.mark.parametrize(("lines", "path", "fragment"), [
    ('[model]\nurdf = "URDF"\ndh = [{ a = 1.0 }]', "model", "exactly one of 'urdf'"),
    ('[model]\ntool = "gripper"', "model", "exactly one of 'urdf'"),
    ('[model]\nurdf = "URDF"\nmont = { xyz = [0, 0, 0] }', "model.mont",
     "did you mean 'mount'?"),
    ('[model]\nurdf = "URDF"\ntool = "hand"', "model.tool", "unknown frame 'hand'"),
    ('[model]\nurdf = "URDF"\nvehicle = { kind = "spatial", actuated = ["u", "x"] }',
     "model.vehicle", "unknown spatial DOF 'x'"),
    ('[model]\nurdf = "URDF"\nvehicle = "boat"', "model.vehicle.kind", "expected one of"),
    ('[model]\nurdf = "URDF"\nconvention = "modified"', "model.convention",
     "only for a DH arm"),
    ('[model]\nurdf = "URDF"\nmount = [[1, 0, 0]]', "model.mount", "expected 4 rows"),
    ('[model]\nurdf = "URDF"\nmount = { xyz = [0, 0] }', "model.mount.xyz",
     "expected 3 numbers"),
    ('[model]\nurdf = "URDF"\nhome = [0.0, 9.0, 0.0]', "model", "home angle of joint"),
    ('[model]\ndh = [{ a = 1.0 }, { a = "long" }]', "model.dh[1].a", "expected a number"),
    ('[model]\ndh = [{ a = 1.0, kind = "screw" }]', "model.dh[0].kind", "expected one of"),
    ('[model]\ndh = []', "model.dh", "non-empty array"),
    ("model = 3", "model", "expected a string, got an integer"),
])
def test_model_table_errors_name_their_field(lines, path, fragment):
    text = _scenario_text(lines.replace("URDF", str(URDF)))
    with pytest.raises(ConfigError) as info:
        scenario_from_dict(tomllib.loads(text))
    assert info.value.path == path, str(info.value)
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


# ---- names: model files, register_model, entry points


def test_model_file_registers_a_name_scenarios_can_use(registered):
    name, description, build = read_model_file(MODEL_FILE)
    assert (name, description) == ("holdout_rov", "4-DOF vehicle with a 3-joint URDF arm (test "
                                                   "model)")
    assert build() is not build()  # a fresh model per call
    registered.append(register_model_file(MODEL_FILE))
    assert "holdout_rov" in model_names() and "holdout_rov" not in bundled_models()
    model = load_model("holdout_rov")
    assert model.vehicle_rate_limit.tolist() == [0.5, 0.5, 0.3, 0.4]
    np.testing.assert_allclose(model.home()[-3:], [0.0, 0.6, 1.2])
    text = _scenario_text('model = "holdout_rov"')
    assert scenario_from_dict(tomllib.loads(text)).model.name == "holdout_rov"


def test_unknown_model_lists_registered_ones_and_the_model_table(registered):
    registered.append(register_model_file(MODEL_FILE))
    with pytest.raises(ConfigError) as info:
        scenario_from_dict(tomllib.loads(_scenario_text('model = "holdout"')))
    message = str(info.value)
    assert message.startswith("model: unknown model 'holdout'; bundled models: soylu_planar")
    assert "other known models: holdout_rov" in message and "[model] table" in message


def test_register_model_refuses_clashes_and_bad_factories(registered):
    with pytest.raises(InputError, match="is a bundled model"):
        register_model("wang_9dof", lambda: load_model("wang_9dof"))
    registered.append("mine")
    register_model("mine", lambda: "not a model")
    with pytest.raises(InputError, match="already registered"):
        register_model("mine", lambda: load_model("wang_9dof"))
    with pytest.raises(ModelError, match=r"model 'mine' \(registered\): expected a Model"):
        load_model("mine")
    with pytest.raises(InputError, match="without spaces"):
        register_model("my rov", lambda: load_model("wang_9dof"))


def test_model_file_errors_start_with_the_file(tmp_path):
    bad = tmp_path / "rov.toml"
    bad.write_text(f'name = "rov"\nurdf = "{URDF}"\nvehicle = {{ kind = "spatial", '
                   'actuated = ["u", "u"] }\n')
    with pytest.raises(ConfigError, match=rf"^{bad}: vehicle: .*repeated DOF"):
        read_model_file(bad)
    bad.write_text(f'urdf = "{URDF}"\n')
    with pytest.raises(ConfigError, match=r"missing required field 'name'"):
        read_model_file(bad)
    bad.write_text(f'name = "wang_9dof"\nurdf = "{URDF}"\n')
    with pytest.raises(ConfigError, match="is a bundled model"):
        register_model_file(bad)


def test_installed_packages_declare_models_by_entry_point(tmp_path, monkeypatch):
    (tmp_path / "holdout_plugin.py").write_text(textwrap.dedent(f'''
        """A package that ships a UVMS model."""
        from uvms_qp import Model


        def rov():
            """Plug-in ROV: fixed base and the 3-joint arm."""
            return Model.from_urdf({str(URDF)!r}, vehicle="fixed", name="plugin_rov")
    '''))
    info = tmp_path / "holdout_plugin-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: holdout-plugin\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[uvms_qp.models]\nplugin_rov = holdout_plugin:rov\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "plugin_rov" in model_names()
    assert load_model("plugin_rov").vehicle_kind == "fixed"
    with pytest.raises(InputError, match="declared by an installed package"):
        register_model("plugin_rov", lambda: load_model("wang_9dof"))


def test_unknown_name_without_registrations_is_unknown_model():
    with pytest.raises(UnknownModelError, match="unknown model 'nautilus'"):
        load_model("nautilus")


# ---- command line


def test_cli_runs_and_compares_a_scenario_with_its_own_urdf_model(tmp_path, capsys):
    assert main(["run", str(SCENARIO), "--out", str(tmp_path / "run"), "--quiet",
                 "--no-plots"]) == 0
    assert main(["compare", str(SCENARIO), "--out", str(tmp_path / "cmp"), "--quiet",
                 "--no-plots"]) == 0
    assert (tmp_path / "cmp" / "wang_pseudoinverse" / "results.json").is_file()


def test_cli_model_path_names_a_model_for_run_and_models(tmp_path, capsys, registered):
    registered.append("holdout_rov")
    scenario = tmp_path / "named.toml"
    scenario.write_text(_scenario_text('model = "holdout_rov"'))
    out = tmp_path / "out"
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--no-plots"]) == 2
    assert "unknown model 'holdout_rov'" in capsys.readouterr().err
    assert main(["run", str(scenario), "--out", str(out), "--quiet", "--no-plots",
                 "--model-path", str(MODEL_FILE)]) == 0
    assert main(["models", "--model-path", str(MODEL_FILE)]) == 0
    row = next(line for line in capsys.readouterr().out.splitlines()
               if line.startswith("holdout_rov"))
    assert "7 = 4 + 3" in row and "passive [p,q]" in row and "(registered)" in row


def test_a_whole_holdout_run_tracks_its_path():
    result = simulate(load_scenario(SCENARIO))
    metrics = result.metrics()
    assert metrics["ee_error_max"] < 5e-3 and metrics["bound_violation_max"] <= 1e-9
    assert metrics["vehicle_displacement_max"] > 0.2  # the path leaves the arm's reach


def test_own_robot_walk_runs_compares_and_views_from_the_command_line(tmp_path, capsys):
    scenario = load_scenario(WALK)
    assert scenario.model.name == "five_function_arm" and "five_function_arm" not in model_names()
    assert (scenario.model.n_vehicle, scenario.model.n_joints) == (4, 5)
    short = ["--duration", "1.0"]
    view = ["--view", str(tmp_path / "walk.html")] if plotly_available() else []
    assert main(["run", str(WALK), "--out", str(tmp_path / "run"), *short, *view]) == 0
    assert main(["compare", str(WALK), "--out", str(tmp_path / "cmp"), *short]) == 0
    assert "Traceback" not in capsys.readouterr().err
    assert (tmp_path / "run" / "results.json").is_file()
    assert (tmp_path / "run" / "rates.png").is_file()
    assert (tmp_path / "cmp" / "wang_pseudoinverse" / "results.json").is_file()
    assert (tmp_path / "cmp" / "configurations.png").is_file()
    assert not view or (tmp_path / "walk.html").stat().st_size > 1e6  # plotly.js is inside


def test_own_robot_walk_does_what_its_page_says():
    comparison = compare(load_scenario(WALK))
    hqp, pinv = (comparison.run(name).metrics for name in ("hqp", "wang_pseudoinverse"))
    assert hqp["ee_error_max"] < 1e-3 and pinv["ee_error_max"] < 1e-3
    assert 0.6 < hqp["vehicle_displacement_max"] < 0.9  # the path leaves the arm's reach
    assert hqp["vehicle_speed_max"] < 0.16
    assert hqp["min_manipulability"] >= 0.03 - 1e-6  # the floor holds
    assert hqp["joint_limit_violation_max"] == 0 and hqp["bound_violation_max"] <= 1e-9
    assert pinv["min_manipulability"] > 0.03
    assert pinv["vehicle_displacement_max"] > hqp["vehicle_displacement_max"]


def test_vehicle_table_is_a_vehicle():
    assert isinstance(load_scenario(SCENARIO).model.vehicle, Vehicle)
    assert isinstance(load_scenario(SCENARIO).model, Model)
