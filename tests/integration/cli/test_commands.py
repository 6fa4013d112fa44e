"""The ``uvms-qp`` command line: its commands, plain help, one-line errors with exit status 2."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import pytest

import uvms_qp.sim.runner as runner
import uvms_qp.sim.scenario as scenario_module
from uvms_qp.cli import build_parser, main
from uvms_qp.errors import ConfigError
from uvms_qp.sim.config import read_toml
from uvms_qp.sim.scenario import bundled_scenarios, resolve_scenario


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


@pytest.fixture
def no_simulation(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("the simulation ran although the input was invalid")

    monkeypatch.setattr(runner, "simulate", refuse)


def test_python_dash_m_runs_the_command_line():
    proc = subprocess.run([sys.executable, "-m", "uvms_qp.cli", "scenarios"],
                          capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "bluerov2_demo" in proc.stdout



@pytest.mark.parametrize("argv", [["solvers"], ["models", "bluerov2_heavy_alpha5"]])
def test_a_closed_output_pipe_ends_the_command_quietly(argv):
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader is gone before the first line (as `| head -0` would be)
    try:
        proc = subprocess.run([sys.executable, "-m", "uvms_qp", *argv], stdout=write_end,
                              stderr=subprocess.PIPE, text=True, timeout=120, check=False)
    finally:
        os.close(write_end)
    assert proc.returncode == 1
    assert proc.stderr == ""

def test_scenarios_lists_each_bundled_scenario_with_its_description(capsys):
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["scenario", "model", "description"]
    assert len(lines) == 1 + len(bundled_scenarios())
    for name, line in zip(bundled_scenarios(), lines[1:], strict=True):
        data = read_toml(resolve_scenario(name))
        assert line.split()[:2] == [name, data["model"]]
        assert line.endswith(data["description"])


@pytest.mark.parametrize("command", ["scenarios", "models"])
def test_lists_wrap_to_a_100_column_terminal_and_keep_one_line_per_row_in_a_pipe(
        command, monkeypatch, capsys):
    assert main([command]) == 0
    piped = capsys.readouterr().out.splitlines()
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    monkeypatch.setenv("COLUMNS", "100")
    assert main([command]) == 0
    wrapped = capsys.readouterr().out.splitlines()
    assert max(len(line) for line in wrapped) < 100 < max(len(line) for line in piped)
    indent = len(piped[0]) - len(piped[0].split()[-1])  # where the description column starts
    rows = []
    for line in wrapped:
        if line[:indent].strip():
            rows.append(line)
        else:
            rows[-1] += " " + line.strip()
    assert [" ".join(r.split()) for r in rows] == [" ".join(r.split()) for r in piped]


@pytest.mark.parametrize("command", sorted(_commands()))
def test_help_is_plain_text(command):
    text = _commands()[command].format_help()
    for markup in ("``", ":func:", ":class:", ":meth:", ":mod:", "::\n"):
        assert markup not in text, f"{command} --help shows {markup!r}"


@pytest.mark.parametrize(("duration", "fragment"), [
    ("1e12", "1e+12 s at dt = 0.05 s is 2e+13 steps; at most 2000000 are allowed"),
    ("2e5", "200000 s at dt = 0.05 s is 4e+06 steps; at most 2000000 are allowed"),
    ("0.01", "0.01 s is shorter than one control period (dt = 0.05 s)"),
    ("nan", "expected a positive number of seconds, got nan"),
    ("inf", "expected a positive number of seconds, got inf"),
    ("-2", "expected a positive number of seconds, got -2.0"),
])
def test_duration_override_obeys_the_scenario_limits(duration, fragment, tmp_path, capsys,
                                                     no_simulation):
    out = tmp_path / "out"
    code = main(["run", "bluerov2_demo", "--out", str(out), "--quiet", "--duration", duration])
    err = capsys.readouterr().err
    assert code == 2
    assert err == f"uvms-qp run: error: --duration: {fragment}\n"
    assert not out.exists()  # refused before the output folder is made


def test_a_duration_between_periods_says_what_it_ran(tmp_path, capsys):
    code = main(["run", "paper001_circle", "--out", str(tmp_path), "--no-plots",
                 "--duration", "0.27"])
    out = capsys.readouterr().out
    assert code == 0
    assert "paper001_circle: 3 steps of 0.1 s (0.3 s)" in out
    assert "note: 0.27 s is not a whole number of control periods; ran the nearest, 0.3 s" in out


@pytest.mark.parametrize(("text", "fragment"), [
    ("dt = 5e-324", "dt: expected a control period in [1e-06, 10] s"),
    ("duration = 1e308", "duration: 1e+308 s at dt = 0.05 s is over 1e308 steps"),
    ("deep = " + "{ a = " * 400 + "1" + " }" * 400, "arrays and tables nested more than 32"),
    ("deep = " + "[" * 1000 + "]" * 1000, "arrays and tables nested more than 32"),
], ids=["tiny_dt", "huge_duration", "inline_tables_400", "arrays_1000"])
def test_file_errors_are_one_line_and_exit_2(text, fragment, tmp_path, capsys, no_simulation):
    source = read_toml(resolve_scenario("bluerov2_demo"))
    path = tmp_path / "bad.toml"
    key = text.split(" = ", 1)[0]
    body = resolve_scenario("bluerov2_demo").read_text()
    if key in source:
        body = "\n".join(line for line in body.splitlines() if not line.startswith(f"{key} ="))
    path.write_text(text + "\n" + body)
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and fragment in err and "Traceback" not in err


def test_a_multi_line_message_is_printed_on_one_line(monkeypatch, tmp_path, capsys):
    def fail(source):
        raise ConfigError("first line\n  second line\n")

    monkeypatch.setattr(scenario_module, "load_scenario", fail)
    assert main(["run", "x", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err == "uvms-qp run: error: first line; second line\n"


@pytest.mark.parametrize(("options", "says_figures"), [(["--no-plots"], False), ([], True)])
def test_compare_says_figures_only_when_it_writes_them(options, says_figures, tmp_path, capsys,
                                                       monkeypatch):
    monkeypatch.setattr("uvms_qp.sim.comparison_figures.plot_comparison", lambda *a, **k: [])
    scenario = tmp_path / "short.toml"
    body = resolve_scenario("paper001_circle").read_text().replace("duration = 10.0",
                                                                    "duration = 0.2")
    scenario.write_text(body)
    assert main(["compare", str(scenario), "--out", str(tmp_path / "out"), *options]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    assert last.startswith("results, comparison.md")
    assert (" and figures in " in last) is says_figures


@pytest.mark.parametrize(("argv", "fragment"), [
    (["run", "bluerov2_demo"], "uvms-qp run: error: the following arguments are required: --out"),
    (["run", "x", "--out", "o", "--duration", "abc"],
     "uvms-qp run: error: argument --duration: invalid float value: 'abc'"),
    (["frob"], "uvms-qp: error: argument COMMAND: invalid choice: 'frob'"),
])
def test_argument_errors_are_one_line_and_exit_2(argv, fragment, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    err = capsys.readouterr().err
    assert info.value.code == 2
    assert err.startswith(fragment) and err.count("\n") == 1 and "usage:" not in err


# ---- --out that cannot be used, a misspelt solver: one line, exit 2, before any simulation
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


def test_cli_solver_typo_names_the_option(tmp_path, capsys, no_simulation):
    out = tmp_path / "out"
    code = main(["run", "paper000_quintic", "--out", str(out), "--quiet", "--solver", "foo"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("uvms-qp run: error: --solver: unknown solver 'foo'")
    assert err.count("known solvers:") == 1
    assert not out.exists()
