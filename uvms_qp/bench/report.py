"""Benchmark output: resumable JSON/CSV stores, the terminal table, a markdown table, a PNG plot.

Both files APPEND: rows already present (same ``(set, problem, solver)``) are kept and skipped by
the next run, so an interrupted run resumes where it stopped and runs with other solvers add
columns to the same table.

* JSON: one document ``{"format": "uvms-qp-bench/1", "runs": [machine info per run...],
  "records": [row...]}``, rewritten atomically after every problem.
* CSV: one line per row (:data:`~uvms_qp.bench.record.CSV_COLUMNS`), appended after every
  problem; lists are space-separated.
"""

from __future__ import annotations

import csv
import json
import math
import os
import platform
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..errors import InputError
from .metrics import TIERS, Summary
from .record import CSV_COLUMNS, HARD_TOL, OWN_PROBLEM, Record, tail_samples

JSON_FORMAT = "uvms-qp-bench/1"


# ----------------------------------------------------------------------------- machine facts


def machine_info() -> dict[str, Any]:
    """CPU count and model, load average, Python and package versions of this run."""
    from importlib import metadata

    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        load = list(os.getloadavg())
    except OSError:
        load = []
    versions: dict[str, str | None] = {}
    for dist in ("uvms-qp", "numpy", "scipy", "pin", "daqp", "qpsolvers", "quadprog",
                 "proxsuite", "piqp", "osqp", "clarabel", "highspy", "pin-pink"):
        try:
            versions[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            versions[dist] = None
    return {"nproc": os.cpu_count(), "cpu": cpu, "loadavg": load,
            "python": platform.python_version(), "platform": platform.platform(),
            "versions": versions}


# ------------------------------------------------------------------------------------ stores


class JsonStore:
    """A JSON results document that grows by appending rows (see the module docstring)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.data: dict[str, Any] = {"format": JSON_FORMAT, "runs": [], "records": []}
        if self.path.exists() and self.path.stat().st_size:
            try:
                data = json.loads(self.path.read_text())
            except json.JSONDecodeError as exc:
                raise InputError(f"--json: {self.path} is not valid JSON ({exc})") from exc
            if not isinstance(data, dict) or data.get("format") != JSON_FORMAT:
                raise InputError(f"--json: {self.path} is not a uvms-qp bench file "
                                 f"(format {JSON_FORMAT!r})")
            self.data = data

    def records(self) -> list[Record]:
        """Rows stored so far."""
        return [Record.from_dict(r) for r in self.data["records"]]

    def start_run(self, info: dict[str, Any]) -> None:
        """Record the machine facts and options of a new run."""
        self.data["runs"].append(info)
        self._write()

    def append(self, records: Iterable[Record]) -> None:
        """Add rows and rewrite the file atomically."""
        self.data["records"].extend(r.to_dict() for r in records)
        self._write()

    def finish_run(self, info: dict[str, Any]) -> None:
        """Complete the last run's entry (end time, load, totals)."""
        if self.data["runs"]:
            self.data["runs"][-1].update(info)
        self._write()

    def _write(self) -> None:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_suffix(self.path.suffix + ".tmp")
        tmp.write_text(json.dumps(self.data, indent=1, allow_nan=False, default=_plain))
        tmp.replace(self.path)


def _plain(value: Any) -> Any:
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


class CsvStore:
    """A CSV file of rows, appended line by line."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)

    def records(self) -> list[Record]:
        """Rows stored so far (none when the file does not exist)."""
        if not self.path.exists() or not self.path.stat().st_size:
            return []
        with self.path.open(newline="") as fh:
            reader = csv.DictReader(fh)
            if tuple(reader.fieldnames or ()) != CSV_COLUMNS:
                raise InputError(f"--csv: {self.path} has other columns than a uvms-qp bench "
                                 f"file: {reader.fieldnames}")
            return [Record.from_row(row) for row in reader]

    def append(self, records: Iterable[Record]) -> None:
        """Append rows (writing the header first for a new file)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        new = not self.path.exists() or not self.path.stat().st_size
        with self.path.open("a", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(CSV_COLUMNS))
            if new:
                writer.writeheader()
            for r in records:
                writer.writerow(r.to_row())


# ------------------------------------------------------------------------------------- tables


def _fmt(value: float, spec: str = ".3g") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, float) and math.isinf(value):
        return "inf"
    return format(value, spec)


HEADERS: tuple[str, ...] = (
    "set", "solver", "success", "unproven", "timed", "median us", "p95 us", "p99 us", "max us",
    "C us", "SGM", "x daqp", "x pink", "hard viol", "gap best", "gap null", "acc hi/lo", "NaN",
)
#: Marker after the name of a row that solved its own, smaller problem (see :func:`footnotes`).
OWN_MARK = "*"
#: A tail percentile from fewer samples than it needs.
TOO_FEW = "n/a"


def _tail(value: float, timed: int) -> str:
    """A tail percentile: NaN with timed samples means too few of them (``tail_percentile``)."""
    return TOO_FEW if timed and math.isnan(value) else _fmt(value, ".1f")


def table_rows(summaries: list[Summary]) -> list[list[str]]:
    """The table as strings (one list per line, columns of :data:`HEADERS`)."""
    rows = []
    for s in summaries:
        if not s.trials:
            continue
        tiers = "/".join(_fmt(100 * s.tiers[t], ".0f") for t in TIERS) if s.tiers else "-"
        rows.append([
            s.set, s.solver + (OWN_MARK if s.own_problem else ""),
            f"{s.success_rate:.3f} ({s.successes}/{s.trials})",
            str(s.failures.get("unproven", 0)), str(s.timed),
            _fmt(s.median_us, ".1f"), _tail(s.p95_us, s.timed), _tail(s.p99_us, s.timed),
            _fmt(s.max_us, ".0f"), _fmt(s.backend_us, ".1f"), _fmt(s.sgm_ratio, ".2f"),
            _fmt(s.vs_daqp, ".2f"), _fmt(s.vs_pink, ".2f"),
            _fmt(s.claimed_violation, ".1e"), _fmt(s.gap, ".1e"), _fmt(s.gap_nullspace, ".1e"),
            tiers, str(s.nan_count),
        ])
    return rows


def failure_lines(summaries: list[Summary]) -> list[str]:
    """One line per (set, solver) with failures: ``set/solver: reason xN, ...``.

    A closed form whose answers were clipped into the box says on how many problems: its
    ``unproven`` failures are those clipped answers, which the certificate could not prove.
    """
    out = []
    for s in summaries:
        if s.failures:
            parts = ", ".join(f"{k} x{v}" for k, v in sorted(s.failures.items(),
                                                             key=lambda kv: -kv[1]))
            if s.saturated:
                parts += (f"; closed form saturated into the hard box on {s.saturated} of "
                          f"{s.problems} problems")
            out.append(f"{s.set}/{s.solver}: {s.trials - s.successes} failed of {s.trials} "
                       f"({parts})")
    return out


def footnotes(summaries: list[Summary]) -> list[str]:
    """Notes the table needs: percentiles left out for want of samples, rows of another problem."""
    notes = []
    shown = [s for s in summaries if s.trials]
    if any(0 < s.timed < tail_samples(99) for s in shown):
        notes.append(f"{TOO_FEW}: a p95 needs {tail_samples(95)} timed samples, a p99 "
                     f"{tail_samples(99)} (fewer give the maximum); a closed loop's first step "
                     f"is a warm-up, verified but not timed.")
    for s in shown:
        if s.own_problem:
            notes.append(f"{OWN_MARK} {s.set}/{s.solver} solves its own, smaller problem there "
                         f"({OWN_PROBLEM[len('own problem: '):]}, not the stack of the set's "
                         f"other rows): its success is on that problem, and it has no time ratio "
                         f"to them.")
    return notes


#: Columns of the terminal table (of :data:`HEADERS`): it fits :data:`TERMINAL_WIDTH` columns;
#: the full table goes to ``--markdown`` / ``--csv``.
TERMINAL_HEADERS: tuple[str, ...] = (
    "solver", "success", "median us", "p99 us", "x daqp", "hard viol", "gap best", "NaN",
)
#: Width of the terminal table [characters].
TERMINAL_WIDTH = 100


def _terminal_cells(row: list[str]) -> list[str]:
    cells = dict(zip(HEADERS, row, strict=True))
    cells["success"] = cells["success"].split(" ")[-1].strip("()")  # "1.000 (30/30)" -> "30/30"
    if cells["unproven"] != "0":  # "28/30 2u": two of the failures not proven optimal
        cells["success"] += f" {cells['unproven']}u"
    return [cells[h] for h in TERMINAL_HEADERS]


#: Space between two columns of the terminal table.
_GAP = "  "


def _row_lines(name: str, numbers: str, name_width: int) -> list[str]:
    """One row of the terminal table as lines.

    The name and its numbers on one line, or, for a name longer than the solver column, the
    whole name on a line of its own and the numbers on the next one.
    """
    if len(name) <= name_width:
        return [f"{name.ljust(name_width)}{_GAP}{numbers}"]
    return [name, f"{' ' * name_width}{_GAP}{numbers}"]


def print_table(summaries: list[Summary], console: Any = None, title: str = "") -> None:
    """Print the compact terminal table (one section per set) and the attributed failures.

    The table has the columns :data:`TERMINAL_HEADERS` and fits the console's width (at most
    :data:`TERMINAL_WIDTH` characters from the command line); :func:`markdown_table` and the CSV
    store have every column. A name is never split: one longer than the room the numbers leave
    takes a line of its own, its numbers the next line.
    """
    from rich.console import Console
    from rich.text import Text

    console = console or Console(width=TERMINAL_WIDTH)
    shown = [s for s in summaries if s.trials]
    cells = [_terminal_cells(row) for row in table_rows(summaries)]
    widths = [max([len(h), *(len(c[i]) for c in cells)]) for i, h in enumerate(TERMINAL_HEADERS)]
    numbers_width = sum(widths[1:]) + len(_GAP) * (len(widths) - 2)
    room = console.width - numbers_width - len(_GAP)
    name_width = max([len(TERMINAL_HEADERS[0]), *(len(s.set) for s in shown),
                      min(widths[0], room)])

    def numbers(row: list[str]) -> str:
        return _GAP.join(cell.rjust(w) for cell, w in zip(row[1:], widths[1:], strict=True))

    console.print(title or "uvms-qp bench", markup=False, highlight=False)
    console.print(Text(_row_lines(TERMINAL_HEADERS[0], numbers(list(TERMINAL_HEADERS)),
                                  name_width)[0], style="bold"))
    console.print("\u2500" * (name_width + len(_GAP) + numbers_width), markup=False)
    previous = None
    for row, s in zip(cells, shown, strict=True):
        if s.set != previous:
            if previous is not None:
                console.print()
            console.print(Text(s.set, style="bold"))
        previous = s.set
        style = ""
        if s.success_rate < 1.0:
            style = "yellow"
        if s.claimed_violation > HARD_TOL or s.nan_count:
            style = "red"
        for line in _row_lines(row[0], numbers(row), name_width):
            console.print(Text(line, style=style), soft_wrap=True)
    console.print("success = verified/trials (Nu: N failures are answers inside the hard set that "
                  "the optimality certificate could not prove); x daqp = "
                  "per-problem time ratio to daqp (median); "
                  "hard viol = largest hard-row violation of a claimed success; gap best = "
                  "largest per-level optimality gap to the best answer. All columns: "
                  "--markdown FILE or --csv FILE.", markup=False, highlight=False)
    for note in footnotes(summaries):
        console.print(note, markup=False, highlight=False)
    lines = failure_lines(summaries)
    if lines:
        console.print("[bold]failures (counted, by reason)[/bold]")
        for line in lines:
            console.print(f"  {line}", markup=False, highlight=False)


def markdown_table(summaries: list[Summary]) -> str:
    """The table in GitHub markdown (for ``benchmarks/README.md``)."""
    lines = ["| " + " | ".join(HEADERS) + " |", "|" + "---|" * len(HEADERS)]
    lines += ["| " + " | ".join(row) + " |" for row in table_rows(summaries)]
    notes = footnotes(summaries)
    if notes:
        lines += [""] + [f"- {note}" for note in notes]
    return "\n".join(lines)


def plot(summaries: list[Summary], path: str | Path) -> Path:
    """Median time per solver and set (bars, log scale) with the p95 as a whisker; a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sets = list(dict.fromkeys(s.set for s in summaries if s.trials))
    fig, axes = plt.subplots(len(sets), 1, figsize=(11, 3.2 * max(1, len(sets))), squeeze=False)
    for ax, set_name in zip(axes[:, 0], sets, strict=True):
        lines = [s for s in summaries if s.set == set_name and s.trials]
        names = [s.solver for s in lines]
        med = [s.median_us for s in lines]
        err = [max(0.0, s.p95_us - s.median_us) for s in lines]
        colors = ["tab:green" if s.success_rate == 1.0 else "tab:orange" for s in lines]
        ax.bar(range(len(lines)), med, yerr=[[0] * len(lines), err], color=colors, capsize=3)
        ax.set_yscale("log")
        ax.set_xticks(range(len(lines)), names, rotation=35, ha="right", fontsize=8)
        ax.set_ylabel("time [us]")
        ax.set_title(f"{set_name}: median (bar) and p95 (whisker); orange = success < 1")
        ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
