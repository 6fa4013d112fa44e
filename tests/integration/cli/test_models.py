"""``uvms-qp models`` lists every bundled model with its DOFs, and describes one."""

import numpy as np
import pinocchio as pin
import pytest

from uvms_qp import bundled_models, load_model
from uvms_qp.cli import main


def test_models_lists_each_bundled_model_with_dofs(capsys):
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert "DOF" in lines[0]
    for name in bundled_models():
        model = load_model(name)
        row = next(line for line in lines if line.split()[0] == name)
        assert f"{model.nv} = {model.n_vehicle} + {model.n_joints}" in row
    assert "passive [p,q]" in out  # wang_9dof's passive roll and pitch


def test_models_describes_one_model(capsys):
    assert main(["models", "bluerov2_heavy_alpha5"]) == 0
    out = capsys.readouterr().out
    assert "axis_e" in out and "jaws_base_link" in out and "[0.5, 0.5, 0.5, 0.5]" in out


def test_models_unknown_name_is_a_clean_error(capsys):
    assert main(["models", "nautilus"]) == 2
    err = capsys.readouterr().err
    assert "unknown model 'nautilus'" in err and "bluerov2_heavy_alpha5" in err


def _printed_list(line, label):
    inside = line.split(f"{label} [", 1)[1].split("]", 1)[0]
    return np.array([float(v) for v in inside.split(", ")])


@pytest.mark.parametrize("name", ["bluerov2_heavy_alpha5", "santos_planar", "nenchev_pa10_arm"])
def test_models_prints_the_home_joints_and_the_tools_pose_at_home(name, capsys):
    assert main(["models", name]) == 0
    lines = capsys.readouterr().out.splitlines()
    model = load_model(name)
    T = model.frame_pose(model.home(), "tool")
    joints = next(line for line in lines if line.lstrip().startswith("home joints:"))
    assert np.allclose(_printed_list(joints, "joints:  "), model.split(model.home())[1],
                       atol=5e-5)
    tool = next(line for line in lines if line.lstrip().startswith("tool at home:"))
    assert np.allclose(_printed_list(tool, "xyz"), T[:3, 3], atol=5e-5)
    assert np.allclose(pin.rpy.rpyToMatrix(_printed_list(tool, "rpy")), T[:3, :3], atol=2e-4)


def _reaching(start):
    return f"""
model = "bluerov2_heavy_alpha5"
dt = 0.1
duration = 0.3

[trajectories.reach]
type = "line"
start = [{start}]
goal = [0.6, 0.1, 0.0]
duration = 0.3

[[levels]]
[[levels.tasks]]
type = "end_effector"
trajectory = "reach"
"""


def test_a_trajectory_from_the_printed_home_pose_runs_quietly_one_from_elsewhere_warns(
        capsys, tmp_path):
    """The loop of a new user: read the tool's home position, start the trajectory there."""
    assert main(["models", "bluerov2_heavy_alpha5"]) == 0
    tool = next(line for line in capsys.readouterr().out.splitlines() if "tool at home:" in line)
    start = tool.split("xyz [", 1)[1].split("]", 1)[0]
    for where, text in (("home", start), ("origin", "0.0, 0.0, 0.0")):
        path = tmp_path / f"{where}.toml"
        path.write_text(_reaching(text))
        code = main(["run", str(path), "--out", str(tmp_path / where), "--quiet", "--no-plots"])
        assert code == 0
        err = capsys.readouterr().err
        if where == "home":
            assert "warning" not in err
        else:  # one line: what, how far, where the tool is, what to do; the run goes on
            assert err.count("\n") == 1
            assert err.startswith("uvms-qp run: warning: task 'tool': its trajectory starts "
                                  "0.527 m from the frame 'tool'")
            assert f"the frame at [{start}]" in err
            assert "uvms-qp models bluerov2_heavy_alpha5" in err
            assert (tmp_path / where / "results.json").exists()
