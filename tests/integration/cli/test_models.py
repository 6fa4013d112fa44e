"""``uvms-qp models`` lists every bundled model with its DOFs."""

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
