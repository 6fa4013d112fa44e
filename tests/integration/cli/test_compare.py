"""``uvms-qp compare``: one results.json per scheme, the table, figures, and clean errors."""

import json

from uvms_qp.cli import main


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
    moved = table["metrics"]["vehicle_displacement_max"]["values"]
    assert moved[1] == 0.0 and moved[2] > 0.05
    assert "| vehicle_displacement_max | m |" in (out / "comparison.md").read_text()
    for figure in ("vehicle_pose.png", "joints.png", "rates.png", "configurations.png",
                   "manipulability_tracking.png", "tool_tracking.png"):
        assert (out / figure).stat().st_size > 1000


def test_compare_rejects_a_scheme_the_scenario_does_not_name(tmp_path, capsys):
    code = main(["compare", "paper001_circle", "--out", str(tmp_path), "--schemes", "nenchev_sc",
                 "--quiet"])
    assert code == 2
    assert "not compared by scenario" in capsys.readouterr().err
    assert not (tmp_path / "hqp").exists()
