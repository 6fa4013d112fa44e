"""``uvms-qp bench``: every solver and scheme on scenarios, random UVMS problems, raw hierarchies.

Sets: ``scenarios`` (every bundled scenario in closed loop, each control step a trial),
``random`` (seeded random UVMS control problems), ``raw`` (``solve_hierarchy`` problems with
levels [6, 3, 1, 4] at n = 10, 13, 30). Solvers: ``daqp``, every installed ``cascade:*``,
``nullspace`` (the closed form, saturated into the box), ``weighted`` (one weighted QP),
``scheme:*`` (the papers' closed-form schemes) and ``pink`` (when ``pin-pink`` is installed; on a
scenario it solves its own, smaller problem: its row is marked ``*`` and has no time ratio). A
success is verified: finite, status optimal, damped or blended, hard rows within
1e-7; every failure is counted with its reason. A closed loop's first step is a warm-up (verified,
not timed); a p95 / p99 from fewer than 20 / 100 timed samples is printed n/a.

``--json``/``--csv`` append to existing files and skip the (set, problem, solver) rows already
there, so an interrupted run resumes. The terminal table has the main columns and fits 100
characters; ``--markdown`` and ``--csv`` have every column. Progress goes to standard error: a bar
on a terminal, otherwise (a log, a pipe) a line per set and every 10 s. Examples::

    uvms-qp bench --quick
    uvms-qp bench --json out/bench.json --csv out/bench.csv --plot out/bench.png
    uvms-qp bench --sets raw --solvers daqp 'cascade:*' --repetitions 50
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any

from ..errors import InputError
from ._common import plain

#: Longest silence of the progress lines printed when standard error is not a terminal [s].
PROGRESS_EVERY = 10.0


class _LineProgress:
    """Progress as plain lines, for CI logs and pipes.

    A line for the first row of each set, then every :data:`PROGRESS_EVERY` seconds, and for the
    last row.
    """

    def __init__(self, console: Any) -> None:
        self.console = console
        self.start = time.perf_counter()
        self.last = -math.inf
        self.set = ""

    def update(self, done: int, total: int, label: str) -> None:
        now = time.perf_counter()
        current = label.split("/", 1)[0]
        if current != self.set or done == total or now - self.last >= PROGRESS_EVERY:
            self.set = current
            self.last = now
            self.console.print(f"bench: {done}/{total} rows, {now - self.start:.0f} s: {label}",
                               markup=False, highlight=False, soft_wrap=True)


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``bench`` sub-command to the ``uvms-qp`` parser."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "bench",
        help="benchmark solvers and schemes (scenarios, random UVMS problems, raw hierarchies)",
        description=plain(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--sets", nargs="+", metavar="SET",
                        help="test sets: scenarios random raw (default: all)")
    parser.add_argument("--solvers", nargs="+", metavar="NAME",
                        help="solvers/schemes, shell globs allowed (default: every available)")
    parser.add_argument("--repetitions", type=int, default=None,
                        help="timed solves per random/raw problem (default 10, quick 3)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random problems")
    parser.add_argument("--scenarios", nargs="+", metavar="NAME",
                        help="bundled scenarios of the scenarios set (default: all)")
    parser.add_argument("--max-steps", type=int, default=None,
                        help="control steps per scenario (default 200, quick 15)")
    parser.add_argument("--random-count", type=int, default=None,
                        help="number of random UVMS problems (default 40, quick 6)")
    parser.add_argument("--raw-count", type=int, default=None,
                        help="raw problems per (n, bounds) case (default 6, quick 1)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke run in well under a minute (CI)")
    parser.add_argument("--json", metavar="FILE", help="append rows to this JSON file (resumable)")
    parser.add_argument("--csv", metavar="FILE", help="append rows to this CSV file (resumable)")
    parser.add_argument("--plot", metavar="FILE", help="write a PNG of the times")
    parser.add_argument("--markdown", metavar="FILE", help="write the table as markdown")
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bar (on a terminal) or progress lines (otherwise)")
    parser.set_defaults(func=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Run the benchmark, print the table, write the requested files; 0 unless input is bad."""
    from dataclasses import replace

    from rich.console import Console

    from ..bench import SetConfig, run_benchmark
    from ..bench.report import TERMINAL_WIDTH, markdown_table, plot, print_table

    config = SetConfig.quick() if args.quick else SetConfig()
    for option, attr in (("max_steps", "max_steps"), ("random_count", "random_count"),
                         ("raw_count", "raw_per_case")):
        value = getattr(args, option)
        if value is not None:
            if value < 1:
                raise InputError(f"--{option.replace('_', '-')}: expected a positive integer, "
                                 f"got {value}")
            config = replace(config, **{attr: value})
    if args.scenarios:
        config = replace(config, scenarios=tuple(args.scenarios))
    repetitions = args.repetitions if args.repetitions is not None else (3 if args.quick else 10)
    console = Console(stderr=True)
    bar: Any = None
    task: Any = None
    lines = _LineProgress(console)

    def progress(done: int, total: int, label: str) -> None:
        nonlocal bar, task
        if args.no_progress:
            return
        if not console.is_terminal:  # a log: a line now and then instead of a bar
            lines.update(done, total, label)
            return
        if bar is None:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
            )

            bar = Progress(TextColumn("bench"), BarColumn(), MofNCompleteColumn(),
                           TimeElapsedColumn(), TextColumn("{task.description}"),
                           console=console, transient=True)
            bar.start()
            task = bar.add_task("", total=total)
        bar.update(task, completed=done, description=label)

    try:
        outcome = run_benchmark(args.sets, args.solvers, repetitions=repetitions, seed=args.seed,
                                config=config, json_path=args.json, csv_path=args.csv,
                                progress=progress)
    finally:
        if bar is not None:
            bar.stop()
    out = Console(width=TERMINAL_WIDTH)
    if out.is_terminal:
        out = Console(width=min(TERMINAL_WIDTH, out.size.width))
    machine = outcome.machine
    title = (f"uvms-qp bench: {machine.get('nproc')} CPUs ({machine.get('cpu')}), load "
             f"{' '.join(f'{v:.2f}' for v in machine.get('loadavg', []))}; "
             f"{outcome.new_rows} rows run, {outcome.skipped_rows} resumed, "
             f"{outcome.wall_time:.0f} s")
    print_table(outcome.summaries, out, title)
    for note in outcome.notes:
        out.print(f"note: {note}", markup=False)
    if args.plot:
        out.print(f"plot: {plot(outcome.summaries, args.plot)}", markup=False)
    if args.markdown:
        from pathlib import Path

        path = Path(args.markdown)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(markdown_table(outcome.summaries) + "\n")
        out.print(f"markdown: {path}", markup=False)
    sys.stdout.flush()
    return 0
