"""The benchmark table: cells, footnotes and failure lines say what the numbers are."""

from __future__ import annotations

import io

from rich.console import Console

from uvms_qp.bench.metrics import summarize
from uvms_qp.bench.record import OWN_PROBLEM, SATURATED, Record
from uvms_qp.bench.report import (
    HEADERS,
    TERMINAL_WIDTH,
    failure_lines,
    footnotes,
    markdown_table,
    print_table,
    table_rows,
)


def _rec(solver, problem, times, set_="raw", note=""):
    return Record(set_, problem, solver, trials=len(times), successes=len(times),
                  times_us=[float(t) for t in times], note=note)


def _cells(line):
    return dict(zip(HEADERS, table_rows([line])[0], strict=True))


def test_a_tail_percentile_from_too_few_samples_is_not_printed():
    few, many = summarize([_rec("daqp", "p1", range(1, 31))])[0], summarize(
        [_rec("daqp", "p1", range(1, 101))])[0]
    assert _cells(few)["p99 us"] == "n/a" and _cells(few)["p95 us"] == "28.5"
    assert _cells(few)["timed"] == "30"
    assert _cells(many)["p99 us"] == "99.0"
    assert any("a p99 100" in note for note in footnotes([few]))
    assert footnotes([many]) == []


def test_a_row_of_its_own_problem_is_marked_and_explained():
    lines = summarize([_rec("daqp", "s1", [100, 100], "scenarios"),
                       _rec("pink", "s1", [50, 50], "scenarios", note=OWN_PROBLEM)])
    daqp, pink = (_cells(line) for line in lines)
    assert pink["solver"] == "pink*" and pink["x daqp"] == "-" and pink["SGM"] == "-"
    assert daqp["x pink"] == "-" and daqp["SGM"] == "1.00"
    notes = footnotes(lines)
    assert any(n.startswith("* scenarios/pink solves its own, smaller problem") for n in notes)
    table = markdown_table(lines)
    assert "| scenarios | pink* |" in table and "- * scenarios/pink" in table


def test_failure_line_names_the_saturated_closed_form():
    rec = _rec("nullspace", "p1", [5, 5], note=SATURATED)
    rec.successes, rec.failures = 0, {"unproven": 2}
    line = summarize([rec, _rec("nullspace", "p2", [5, 5])])[0]
    assert failure_lines([line]) == [
        "raw/nullspace: 2 failed of 4 (unproven x2; closed form saturated into the hard box on "
        "1 of 2 problems)"]


def test_terminal_table_folds_a_long_scheme_name_and_cuts_no_number():
    """The longest scheme names do not fit the solver column of a 100-wide terminal: the name
    folds onto a second line, and no cell is cut with an ellipsis."""
    long_name = "scheme:wang_fuzzy_gradient_projection_euclidean"
    rec = _rec(long_name, "s1", [123456.7] * 150, "scenarios")
    rec.trials, rec.successes, rec.failures = 1800, 937, {"unproven": 863}
    lines = summarize([_rec("daqp", "s1", [100.0] * 150, "scenarios"), rec])
    console = Console(width=TERMINAL_WIDTH, file=io.StringIO(), record=True)
    print_table(lines, console)
    text = console.export_text()
    assert "\u2026" not in text
    assert max(len(line) for line in text.splitlines()) <= TERMINAL_WIDTH
    assert "937/1800 863u" in text and "123456.7" in text
    assert long_name in "".join(line.split()[0] for line in text.splitlines() if line.split())
