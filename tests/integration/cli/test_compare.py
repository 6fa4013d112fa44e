"""``uvms-qp compare``: one results.json per scheme, the table, figures, and clean errors."""

import importlib.resources
import io
import json

import pytest
from rich.console import Console

from uvms_qp.cli import main
from uvms_qp.cli.compare import print_table
from uvms_qp.sim.comparison import BOUNDS_NOTE, Comparison, SchemeRun


def test_compare_writes_results_table_and_figures(tmp_path):
    out = tmp_path / "cmp"
    assert main(["compare", "paper001_circle", "--out", str(out), "--quiet"]) == 0
    schemes = ["hqp", "santos_kinematic_constraint", "santos_sr_task_priority"]
    for name in schemes:
        data = json.loads((out / name / "results.json").read_text())
        assert data["scheme"] == name
        assert data["scenario"] == "paper001_circle"
        for key in ("ee_error_max", "vehicle_displacement_max", "bound_violation_max",
                    "step_time_median_us", "nan_steps"):
            assert key in data["metrics"]
        assert len(data["series"]["time"]) == data["steps"] + 1
    table = json.loads((out / "comparison.json").read_text())
    assert table["schemes"] == schemes
    assert table["plants"] == ["kinematic"] * 3
    assert "| plant |  | kinematic | kinematic | kinematic |" in (out / "comparison.md").read_text()
    moved = table["metrics"]["vehicle_displacement_max"]["values"]
    assert moved[1] == 0.0 and moved[2] > 0.05
    assert "| vehicle_displacement_max | m |" in (out / "comparison.md").read_text()
    for figure in ("vehicle_pose.png", "joints.png", "rates.png", "configurations.png",
                   "manipulability_tracking.png", "tool_tracking.png"):
        assert (out / figure).stat().st_size > 1000


def test_compare_on_the_dynamic_plant_says_so_in_its_table(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "bluerov2_demo", "--plant", "dynamic", "--duration", "0.5",
                 "--out", str(out), "--no-plots"]) == 0
    assert json.loads((out / "comparison.json").read_text())["plants"] == ["dynamic"]
    assert json.loads((out / "hqp" / "results.json").read_text())["plant"] == "dynamic"
    assert "| plant |  | dynamic |" in (out / "comparison.md").read_text()
    assert any(line.split()[1:3] == ["plant", "\u2502"] and "dynamic" in line
               for line in capsys.readouterr().out.splitlines())


def test_compare_prints_and_records_each_distinct_warning_of_its_runs_once(tmp_path, capsys):
    # the demo's 2.5 kg payload, taken at once, is beyond the arm's 2 kg rating in both runs
    demo = importlib.resources.files("uvms_qp.scenarios").joinpath("bluerov2_demo.toml")
    text = demo.read_text().replace("time = 15.0", "time = 0.1")  # the pick-up and its event
    text = text.replace("[initial]", 'schemes = ["hqp", "wang_pseudoinverse"]\n\n[initial]', 1)
    path = tmp_path / "s.toml"
    path.write_text(text)
    out = tmp_path / "cmp"
    assert main(["compare", str(path), "--plant", "dynamic", "--duration", "0.3",
                 "--out", str(out), "--no-plots"]) == 0
    printed = capsys.readouterr()
    rated = "the payload of 2.5 kg exceeds the arm's rated payload of 2 kg"
    for name in ("hqp", "wang_pseudoinverse"):
        assert rated in json.loads((out / name / "results.json").read_text())["warnings"][0]
    warnings = [line for line in printed.err.splitlines() if rated in line]
    assert len(warnings) == 1 and warnings[0].startswith("warning: ")
    assert warnings[0].endswith("(runs: hqp, wang_pseudoinverse)")
    table = json.loads((out / "comparison.json").read_text())
    assert [w["runs"] for w in table["warnings"]] == [["hqp", "wang_pseudoinverse"]]
    assert table["warnings"][0]["warning"].startswith(rated)
    # the floating vehicle's attitude and thrust energy are rows of the table
    for key in ("roll_max", "pitch_max", "energy"):
        assert len(table["metrics"][key]["values"]) == 2
    assert "| energy | J |" in (out / "comparison.md").read_text()


def test_compare_rejects_a_scheme_the_scenario_does_not_name(tmp_path, capsys):
    code = main(["compare", "paper001_circle", "--out", str(tmp_path), "--schemes", "nenchev_sc",
                 "--quiet"])
    assert code == 2
    assert "not compared by scenario" in capsys.readouterr().err
    assert not (tmp_path / "hqp").exists()


# ---- closed-form schemes ignore the hard bounds: the comparison says so
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


# ---- the table follows the console's width
WANG = ["hqp", "wang_fuzzy_gradient_projection", "wang_fuzzy_gradient_projection_euclidean"]


def _wide_comparison():
    runs = [SchemeRun(name, result=None,  # type: ignore[arg-type]
                      metrics={"ee_error_max": 1.5e-6 * (k + 1), "vehicle_speed_max": 0.25,
                               "bound_violation_max": 0.0,
                               "status_counts": {"optimal": 1000}})
            for k, name in enumerate(WANG)]
    return Comparison("paper003_case1_no_payload", "three schemes with long names", runs)


def _cells(line, bar):
    return [cell.strip() for cell in line.split(bar)[1:-1]]


@pytest.mark.parametrize("width", [80, 100, 200])
def test_compare_table_fits_the_console_width_and_shows_every_scheme_once(width):
    """At its natural width (120 characters) the table fits only the widest console; on the
    others the schemes that do not fit follow in a second table with the metric column again."""
    console = Console(width=width, file=io.StringIO(), record=True)
    print_table(_wide_comparison(), console)
    lines = console.export_text().splitlines()
    assert max(len(line) for line in lines) <= width
    assert "\u2026" not in "".join(lines)  # no cell cut
    headers = [_cells(line, "\u2503") for line in lines if line.startswith("\u2503")]
    assert len(headers) == (1 if width == 200 else 2)
    assert all(header[:2] == ["metric", "unit"] for header in headers)
    assert [name for header in headers for name in header[2:]] == WANG
    errors = [_cells(line, "\u2502") for line in lines if line.startswith("\u2502 ee_error_max")]
    assert [value for row in errors for value in row[2:]] == ["1.5e-06", "3e-06", "4.5e-06"]
