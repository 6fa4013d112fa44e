"""Messages and exit paths users hit: step inputs, --out, solver names, schemes, bounds flags."""

from __future__ import annotations

import importlib.resources
import json

import numpy as np
import pytest

import uvms_qp.sim.runner as runner
from uvms_qp.cli import main
from uvms_qp.controller import Controller
from uvms_qp.errors import ConfigError, InputError, ShapeError, UnknownSolverError
from uvms_qp.hqp import solve_hierarchy
from uvms_qp.model import load_model
from uvms_qp.schemes import WangPseudoinverse, build_scheme
from uvms_qp.sim.comparison import BOUNDS_NOTE, Comparison, SchemeRun
from uvms_qp.sim.scenario import load_scenario
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import PostureTask

# ---- step() called with a configuration instead of a State


def test_controller_step_with_a_configuration_says_to_build_a_state():
    model = load_model("bluerov2_heavy_alpha5")
    controller = Controller(model, Stack(levels=[Level(PostureTask())]))
    with pytest.raises(InputError, match=r"expects a State.*model\.state\(q\)"):
        controller.step(model.home(), 0.0)
    assert controller.step(model.state(model.home()), 0.0).status == "optimal"


def test_scheme_step_with_a_configuration_says_to_build_a_state():
    model = load_model("wang_9dof")
    scheme = WangPseudoinverse().bind(model, 0.01)
    with pytest.raises(InputError, match=r"expects a State.*model\.state\(q\)"):
        scheme.step(model.home(), 0.0)


# ---- --out that cannot be used: one line, exit 2, and before any simulation


@pytest.fixture
def no_simulation(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("the simulation ran before --out was checked")

    monkeypatch.setattr(runner, "simulate", refuse)


@pytest.mark.parametrize("command", ["run", "compare"])
@pytest.mark.parametrize("where", ["file", "under_file"])
def test_unusable_out_fails_before_simulating(command, where, tmp_path, capsys, no_simulation):
    existing = tmp_path / "afile"
    existing.write_text("keep me")
    out = existing if where == "file" else existing / "sub"
    code = main([command, "paper000_quintic", "--out", str(out), "--quiet", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith(f"uvms-qp {command}: error: --out: ")
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert existing.read_text() == "keep me"


def test_failed_compare_leaves_no_empty_output_directory(tmp_path, capsys):
    out = tmp_path / "new" / "cmp"
    code = main(["compare", "paper000_quintic", "--out", str(out), "--schemes", "nope",
                 "--quiet"])
    assert code == 2 and "not compared by scenario" in capsys.readouterr().err
    assert not out.exists()


# ---- unknown solver names: the list once, the likely intended name


def _count_lists(message: str) -> int:
    return message.count("known solvers:")


def test_bare_backend_name_suggests_the_cascade():
    model = load_model("bluerov2_heavy_alpha5")
    with pytest.raises(UnknownSolverError) as info:
        Controller(model, Stack(levels=[Level(PostureTask())]), solver="osqp")
    message = str(info.value)
    assert _count_lists(message) == 1 and message.count("cascade:osqp") == 2
    assert "did you mean 'cascade:osqp'?" in message
    with pytest.raises(UnknownSolverError) as info:
        solve_hierarchy([[(np.eye(2), [1.0, 1.0])]], solver="quadprog")
    assert _count_lists(str(info.value)) == 1
    assert "did you mean 'cascade:quadprog'?" in str(info.value)


def test_unknown_name_lists_the_solvers_once():
    with pytest.raises(UnknownSolverError) as info:
        solve_hierarchy([[(np.eye(2), [1.0, 1.0])]], solver="foo")
    message = str(info.value)
    assert _count_lists(message) == 1
    assert message.count("nullspace") == 1 and "did you mean" not in message


def test_cli_solver_typo_names_the_option(tmp_path, capsys, no_simulation):
    out = tmp_path / "out"
    code = main(["run", "paper000_quintic", "--out", str(out), "--quiet", "--solver", "foo"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("uvms-qp run: error: --solver: unknown solver 'foo'")
    assert _count_lists(err) == 1
    assert not out.exists()


# ---- messages that named the culprit several times, or misread None


def test_scheme_for_the_wrong_model_kind_is_named_once():
    scenario = load_scenario("bluerov2_demo")
    with pytest.raises(ConfigError) as info:
        build_scheme("soylu_dexterous", scenario, "schemes[1]")
    message = str(info.value)
    assert message.count("soylu_dexterous") == 1, message
    assert message.startswith("schemes[1]: scheme 'soylu_dexterous': ")
    assert "'planar'" in message and "'spatial'" in message


def test_fixed_base_accepts_none_as_the_empty_pose():
    model = load_model("nenchev_pa10_arm")
    joints = model.split(model.home())[1]
    np.testing.assert_array_equal(model.configuration(None, joints), model.home())
    with pytest.raises(ShapeError, match="got length 1"):
        model.configuration([0.0], joints)
    spatial = load_model("wang_9dof")
    with pytest.raises(ShapeError, match="length 6, got None"):
        spatial.configuration(None, spatial.split(spatial.home())[1])


# ---- closed-form schemes ignore the hard bounds: the comparison must say so


def _run(name, violation):
    return SchemeRun(name, result=None, metrics={"bound_violation_max": violation})  # type: ignore[arg-type]


def test_comparison_flags_runs_that_exceed_the_hard_bounds():
    comparison = Comparison("s", "d", [_run("hqp", 1e-12), _run("wang_pseudoinverse", 2500.0)])
    assert [comparison.exceeds_bounds(r) for r in comparison.runs] == [False, True]
    notes = comparison.notes()
    assert len(notes) == 1 and notes[0].startswith("wang_pseudoinverse: " + BOUNDS_NOTE)
    assert "2500" in notes[0]
    markdown = comparison.markdown()
    assert "| bound_violation_max |  | 1e-12 | 2500 (exceeded) |" in markdown
    assert BOUNDS_NOTE in markdown


def test_compare_of_a_closed_form_scheme_reports_the_bound_violation(tmp_path, capsys):
    text = (importlib.resources.files("uvms_qp.scenarios")
            / "paper003_case2_pseudoinverse.toml").read_text()
    # joint rates far below what the pseudoinverse commands, over one second
    text = text.replace("duration = 43.0", "duration = 1.0").split("[[phases]]")[0]
    text = text.replace("limits = [1.0, 1.0, 1.0, 1.0, 1.0]",
                        "limits = [0.001, 0.001, 0.001, 0.001, 0.001]")
    path = tmp_path / "tight.toml"
    path.write_text(text)
    out = tmp_path / "cmp"
    assert main(["compare", str(path), "--out", str(out), "--no-plots"]) == 0
    captured = capsys.readouterr()
    wang = json.loads((out / "wang_pseudoinverse" / "results.json").read_text())
    assert set(wang["series"]["status"]) == {"optimal"}  # the per-step status cannot show it
    assert wang["metrics"]["bound_violation_max"] > 1e-3
    hqp = json.loads((out / "hqp" / "results.json").read_text())
    assert hqp["metrics"]["bound_violation_max"] <= 1e-9
    assert "(exceeded)" in captured.out
    assert f"warning: wang_pseudoinverse: {BOUNDS_NOTE}" in captured.err
    table = json.loads((out / "comparison.json").read_text())
    assert table["exceeds_hard_bounds"] == [False, True]
    assert BOUNDS_NOTE in (out / "comparison.md").read_text()
