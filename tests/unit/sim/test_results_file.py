"""``results.json`` as a file: provenance, permissions, atomic replacement of links."""

from __future__ import annotations

import datetime
import json
import os
import platform
from importlib import metadata

import pytest

import uvms_qp
from uvms_qp.cli import main
from uvms_qp.sim.results import PROVENANCE_PACKAGES, command_line, provenance, write_results
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario


@pytest.fixture(scope="module")
def result():
    return simulate(load_scenario("paper000_quintic"), duration=0.05)


def test_provenance_names_versions_python_date_and_command(result, tmp_path):
    before = datetime.datetime.now(datetime.UTC).replace(microsecond=0)
    data = json.loads(write_results(result, tmp_path, command=["uvms-qp", "run", "x y"])
                      .read_text())
    block = data["provenance"]
    assert set(block) == {"versions", "python", "platform", "date", "command"}
    assert set(block["versions"]) == set(PROVENANCE_PACKAGES)
    assert block["versions"]["uvms-qp"] == uvms_qp.__version__
    assert block["versions"]["daqp"] == metadata.version("daqp")
    assert block["versions"]["pin"] == metadata.version("pin")
    assert block["python"] == platform.python_version()
    date = datetime.datetime.fromisoformat(block["date"])
    assert date.tzinfo is not None and before <= date <= datetime.datetime.now(datetime.UTC)
    assert block["command"] == "uvms-qp run 'x y'"


def test_command_line_names_the_program_as_typed(monkeypatch):
    monkeypatch.setattr("sys.argv", ["/venv/bin/uvms-qp", "run", "demo", "--out", "a b"])
    assert command_line() == "uvms-qp run demo --out 'a b'"
    monkeypatch.setattr("sys.argv", ["/src/uvms_qp/__main__.py", "run", "demo"])
    assert command_line() == "python -m uvms_qp run demo"
    assert provenance()["command"] == "python -m uvms_qp run demo"


def test_cli_run_records_its_command(tmp_path, monkeypatch):
    out = tmp_path / "out"
    argv = ["run", "paper000_quintic", "--out", str(out), "--duration", "0.05", "--quiet",
            "--no-plots"]
    monkeypatch.setattr("sys.argv", ["/venv/bin/uvms-qp", *argv])
    assert main(argv) == 0
    data = json.loads((out / "results.json").read_text())
    assert data["provenance"]["command"].startswith("uvms-qp run paper000_quintic --out ")


def test_results_file_is_world_readable(result, tmp_path):
    path = write_results(result, tmp_path)
    assert os.stat(path).st_mode & 0o777 == 0o644


def test_a_results_file_that_is_a_link_is_replaced_not_followed(result, tmp_path):
    outside = tmp_path / "precious.json"
    outside.write_text("{}")
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.json").symlink_to(outside)
    path = write_results(result, out)
    assert outside.read_text() == "{}"
    assert not path.is_symlink() and json.loads(path.read_text())["scenario"] == result.scenario
    assert [p.name for p in out.iterdir()] == ["results.json"]


def test_series_carry_units_and_the_manipulability_floor(tmp_path):
    run = simulate(load_scenario("bluerov2_demo"), duration=0.2)
    series = json.loads(write_results(run, tmp_path).read_text())["series"]
    assert series["zeta_units"] == ["m/s"] * 3 + ["rad/s"] * 3 + ["rad/s"] * 4
    assert series["joint_units"] == ["rad"] * 4
    assert series["manipulability_unit"] == "m^3"
    assert series["manipulability_floor"] == [0.001] * len(series["time"])
