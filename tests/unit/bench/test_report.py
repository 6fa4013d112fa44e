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


def _printed(lines, width):
    console = Console(width=width, file=io.StringIO(), record=True)
    print_table(lines, console)
    return console.export_text()


def test_terminal_table_never_splits_a_scheme_name_and_cuts_no_number():
    """The longest scheme names do not fit beside the numbers in a 100-wide terminal: such a name
    takes a line of its own, whole, its numbers the next line; no line is wider than the console,
    no cell is cut with an ellipsis, and a name that fits stays on its numbers' line."""
    long_name = "scheme:wang_fuzzy_gradient_projection_euclidean"
    rec = _rec(long_name, "s1", [123456.7] * 150, "scenarios")
    rec.trials, rec.successes, rec.failures = 1800, 937, {"unproven": 863}
    lines = summarize([_rec("daqp", "s1", [100.0] * 150, "scenarios"), rec])
    for width in (TERMINAL_WIDTH, 80):
        text = _printed(lines, width)
        rows = text.splitlines()
        assert "\u2026" not in text
        assert max(len(row) for row in rows) <= width
        at = rows.index(long_name)  # the whole name, alone on its line
        assert rows[at + 1].split() == ["937/1800", "863u", "123456.7", "123456.7", "1234.57",
                                        "0.0e+00", "-", "0"]
        assert rows[at + 1].index("937/1800") > len("daqp")
        daqp = next(row for row in rows if row.startswith("daqp"))
        assert daqp.split()[:3] == ["daqp", "150/150", "100.0"]
        header = next(row for row in rows if row.startswith("solver"))
        success = "937/1800 863u"  # right-aligned under its header
        assert (header.index("success") + len("success")
                == rows[at + 1].index(success) + len(success))


def test_terminal_table_keeps_a_scheme_name_beside_its_numbers_when_it_fits():
    long_name = "scheme:wang_fuzzy_gradient_projection_euclidean"
    lines = summarize([_rec("daqp", "s1", [100.0] * 150, "scenarios"),
                       _rec(long_name, "s1", [50.0] * 150, "scenarios")])
    rows = _printed(lines, 140).splitlines()
    row = next(row for row in rows if row.startswith(long_name))
    assert row.split()[:3] == [long_name, "150/150", "50.0"]
    assert max(len(row) for row in rows) <= 140
