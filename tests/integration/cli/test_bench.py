"""``uvms-qp bench`` end to end on tiny sets: well-formed files, every solver, resumable append."""

from __future__ import annotations

import csv
import json

import pytest

from uvms_qp.bench.pink_adapter import pink_available
from uvms_qp.bench.record import CSV_COLUMNS
from uvms_qp.bench.report import HEADERS, TERMINAL_HEADERS, TERMINAL_WIDTH
from uvms_qp.bench.runners import runner_names
from uvms_qp.cli import main

TINY = ["--scenarios", "paper001_circle", "--max-steps", "3", "--random-count", "2",
        "--raw-count", "1", "--repetitions", "1", "--no-progress"]


def _json_rows(path):
    data = json.loads(path.read_text())
    assert data["format"] == "uvms-qp-bench/1"
    return data, data["records"]


def _csv_rows(path):
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames) == CSV_COLUMNS
        return list(reader)


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    js, cs, png = out / "b.json", out / "b.csv", out / "b.png"
    code = main(["bench", *TINY, "--json", str(js), "--csv", str(cs), "--plot", str(png)])
    return code, js, cs, png


def test_tiny_run_writes_every_solver_to_json_and_csv(tiny_run):
    code, js, cs, png = tiny_run
    assert code == 0
    data, records = _json_rows(js)
    names, _ = runner_names()
    # one row per (set, problem, solver), every available solver present (n/a rows included)
    keys = [(r["set"], r["problem"], r["solver"]) for r in records]
    assert len(keys) == len(set(keys))
    assert {r["solver"] for r in records} == set(names)
    problems = {(r["set"], r["problem"]) for r in records}
    assert len(records) == len(problems) * len(names)
    assert {s for s, _ in problems} == {"scenarios", "random", "raw"}
    # trials are fully accounted for: successes + counted failures
    for r in records:
        assert r["trials"] == r["successes"] + sum(r["failures"].values()), r
        assert len(r["times_us"]) <= max(r["trials"], 0) or r["trials"] == 0
    # daqp runs everything and the machine facts are recorded
    daqp = [r for r in records if r["solver"] == "daqp"]
    assert all(r["trials"] > 0 for r in daqp)
    run = data["runs"][-1]
    assert run["machine"]["nproc"] >= 1 and "versions" in run["machine"]
    rows = _csv_rows(cs)
    assert {(r["set"], r["problem"], r["solver"]) for r in rows} == set(keys)
    assert png.stat().st_size > 1000


def test_second_run_resumes_and_appends_only_missing_rows(tiny_run, tmp_path):
    _, js, cs, _ = tiny_run
    js2, cs2 = tmp_path / "b.json", tmp_path / "b.csv"
    js2.write_text(js.read_text())
    cs2.write_text(cs.read_text())
    n_json, n_csv = len(_json_rows(js2)[1]), len(_csv_rows(cs2))
    assert main(["bench", *TINY, "--json", str(js2), "--csv", str(cs2)]) == 0
    assert len(_json_rows(js2)[1]) == n_json and len(_csv_rows(cs2)) == n_csv
    # a new seed draws new random problems: only their rows are added, old ones kept
    assert main(["bench", *TINY, "--sets", "random", "--seed", "7", "--solvers", "daqp",
                 "--json", str(js2), "--csv", str(cs2)]) == 0
    records = _json_rows(js2)[1]
    assert len(records) == n_json + 2
    assert len(_csv_rows(cs2)) == n_csv + 2
    assert len(_json_rows(js2)[0]["runs"]) == 3


def test_rows_only_in_the_csv_are_copied_into_a_new_json(tiny_run, tmp_path):
    _, _, cs, _ = tiny_run
    cs2, js2 = tmp_path / "b.csv", tmp_path / "new.json"
    cs2.write_text(cs.read_text())
    assert main(["bench", *TINY, "--sets", "raw", "--solvers", "daqp", "--csv", str(cs2),
                 "--json", str(js2)]) == 0
    # the raw rows of the CSV (every solver of the earlier run) now also live in the JSON
    records = _json_rows(js2)[1]
    raw_csv = {(r["problem"], r["solver"]) for r in _csv_rows(cs2) if r["set"] == "raw"}
    assert {(r["problem"], r["solver"]) for r in records} == raw_csv
    assert all(r["set"] == "raw" for r in records)
    daqp = [r for r in records if r["solver"] == "daqp"]
    assert len(daqp) == 9 and all(r["successes"] == r["trials"] == 1 for r in daqp)


def test_quick_smoke_run_fits_100_columns_with_progress_lines_when_piped(capsys, tmp_path):
    markdown = tmp_path / "table.md"
    assert main(["bench", "--quick", "--markdown", str(markdown)]) == 0
    captured = capsys.readouterr()
    out = captured.out
    for name in ("daqp", "cascade:quadprog", "nullspace", "weighted"):
        assert name in out
    assert "scenarios" in out and "random" in out and "raw" in out
    # the terminal table: its main columns, whole (no cell cut with an ellipsis), 100 wide
    assert max(len(line) for line in out.splitlines()) <= TERMINAL_WIDTH
    assert "\u2026" not in out and "..." not in out
    header = next(line for line in out.splitlines() if line.startswith("solver"))
    assert header.split() == " ".join(TERMINAL_HEADERS).split()
    # every column in the markdown table
    assert markdown.read_text().splitlines()[0] == "| " + " | ".join(HEADERS) + " |"
    # 15 steps per scenario, 3 solves per problem: too few samples for a p99 anywhere
    def cell(cells, header):  # counted from the right: "9/27 18u" is two words
        return cells[TERMINAL_HEADERS.index(header) - len(TERMINAL_HEADERS)]

    rows = [line.split() for line in out.splitlines()
            if line.split() and line.split()[0] in ("daqp", "nullspace")]
    assert len(rows) == 6 and all(cell(r, "p99 us") == "n/a" for r in rows)
    assert "a p99 100" in out
    # the closed form's answers clipped into the box are unproven, not back-end errors
    null_raw = next(line for line in out.splitlines() if "raw/nullspace:" in line)
    assert "unproven x" in null_raw and "backend_error" not in out
    assert "saturated into the hard box" in out
    if pink_available():  # Pink's own, smaller problem on the scenarios: marked, no ratio
        pink = next(line.split() for line in out.splitlines() if line.startswith("pink*"))
        assert cell(pink, "x daqp") == "-"
        assert "* scenarios/pink solves its own, smaller problem" in " ".join(out.split())
    # no terminal: progress as lines on stderr, the first row and the last one included
    lines = [line for line in captured.err.splitlines() if line.startswith("bench: ")]
    assert lines[0].startswith("bench: 1/") and "scenarios/" in lines[0]
    total = lines[0].split()[1].split("/")[1]
    assert lines[-1].startswith(f"bench: {total}/{total} rows")
    assert {line.split(": ")[2].split("/")[0] for line in lines} == {"scenarios", "random",
                                                                    "raw"}


def test_bad_options_are_clean_errors(capsys, tmp_path):
    assert main(["bench", "--sets", "nope"]) == 2
    assert "unknown set 'nope'" in capsys.readouterr().err
    assert main(["bench", "--solvers", "cascade:nothing"]) == 2
    assert "matches nothing" in capsys.readouterr().err
    bad = tmp_path / "x.json"
    bad.write_text("{not json")
    assert main(["bench", "--sets", "raw", "--json", str(bad)]) == 2
    assert "not valid JSON" in capsys.readouterr().err
