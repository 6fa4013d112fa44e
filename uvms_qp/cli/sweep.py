"""``uvms-qp sweep FILE --out DIR``: many closed-loop runs of a scenario over drawn parameters.

``FILE`` is a sweep file (TOML, see docs/sweeps.md) or the name of a bundled one
(``bluerov2_demo_sweep``). Each run's record is appended to ``DIR/runs.jsonl`` as it completes;
the same command resumes an interrupted sweep and runs only what is missing. At the end:
``DIR/runs.csv`` (one row per run), ``DIR/summary.json`` (success rate with its 95 % Wilson
interval, metric percentiles, success by parameter) and two figures.

Runs execute on ``--workers`` local processes (default: the usable CPUs), or on a Dask cluster
with ``--scheduler tcp://host:8786`` (needs ``pip install 'uvms-qp[cluster]'``). ``--replay SEED``
re-runs one run alone from the seed in its record and writes its ``results.json`` and figures
into ``DIR``. ``--model-path FILE`` registers a model file's model for the base scenario, in
this process and in every worker (a Dask worker must see the file at the same path). A bad
sweep file or option exits with status 2 and one line, before any run.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any

from ..errors import ConfigError
from ._common import (
    add_model_path,
    output_directory,
    plain,
    print_warnings,
    register_model_paths,
    run_warnings,
    writing_output,
)

#: Longest silence of the progress lines printed when standard error is not a terminal [s].
PROGRESS_EVERY = 10.0


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``sweep`` sub-command to the ``uvms-qp`` parser."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "sweep",
        help="Monte-Carlo sweep of a scenario over drawn parameters, on local cores or Dask",
        description=plain(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("sweep", metavar="FILE",
                        help="sweep file (.toml) or bundled sweep name")
    parser.add_argument("--out", required=True, help="output directory (resumed if it holds "
                                                     "this sweep's records)")
    parser.add_argument("--runs", type=int, help="override the file's number of runs")
    parser.add_argument("--workers", type=int,
                        help="local worker processes (default: the usable CPUs)")
    parser.add_argument("--scheduler", metavar="ADDR",
                        help="run on the Dask cluster of this scheduler (tcp://host:8786)")
    parser.add_argument("--replay", type=int, metavar="SEED",
                        help="re-run the one run of this seed (from runs.csv) and write its "
                             "results.json and figures")
    add_model_path(parser)
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    parser.add_argument("--quiet", action="store_true", help="no progress, no summary")
    parser.set_defaults(func=run)
    return parser


class _Progress:
    """Runs done, failures and the time left: a bar on a terminal, else a line now and then."""

    def __init__(self, enabled: bool) -> None:
        from rich.console import Console

        self.console = Console(stderr=True)
        self.enabled = enabled
        self.bar: Any = None
        self.task: Any = None
        self.last = -math.inf
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int, failures: int) -> None:
        if not self.enabled:
            return
        if not self.console.is_terminal:
            now = time.perf_counter()
            if done == total or now - self.last >= PROGRESS_EVERY:
                self.last = now
                self.console.print(f"sweep: {done}/{total} runs, {failures} failures, "
                                   f"{now - self.start:.0f} s", markup=False, highlight=False)
            return
        if self.bar is None:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self.bar = Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(),
                                TextColumn("{task.fields[failures]} failures"),
                                TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                                console=self.console, transient=True)
            self.bar.start()
            self.task = self.bar.add_task("", total=total, completed=done, failures=failures)
        self.bar.update(self.task, completed=done, failures=failures)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()


def _percent(value: float | None) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{100.0 * value:.1f} %"


def summary_lines(summary: dict[str, Any]) -> list[str]:
    """The terminal summary of a sweep's report."""
    from ..sweep.report import all_bins, bin_label

    low_high = summary["success_interval"] or [None, None]
    lines = [f"success: {summary['successes']}/{summary['recorded']} = "
             f"{_percent(summary['success_rate'])} ({int(summary['confidence'] * 100)} % Wilson "
             f"interval {_percent(low_high[0])} to {_percent(low_high[1])})",
             "statuses: " + ", ".join(f"{k} {v}" for k, v in summary["statuses"].items())]
    for entry in summary["criteria"]:
        lines.append(f"  missed {entry['criterion']}: {entry['missed']} runs")
    shown = [m for m in dict.fromkeys(e["metric"] for e in summary["criteria"])
             if m in summary["metrics"]]
    if shown:
        lines.append(f"  {'metric':<32} {'p5':>10} {'p50':>10} {'p95':>10} {'max':>10}")
        for name in shown:
            row = summary["metrics"][name]
            lines.append(f"  {name:<32} " + " ".join(
                f"{row[k]:>10.4g}" for k in ("p5", "p50", "p95", "max")))
    if summary["parameters"]:
        lines.append("  success by parameter, per value or bin of the values drawn: "
                     "rate (runs); -: no run")
    for name, entry in summary["parameters"].items():
        bins = all_bins(entry)
        rates = ", ".join(f"{bin_label(b, i, len(bins))}: {_rate(b['rate'])} ({b['runs']})"
                          for i, b in enumerate(bins))
        unit = f" [{entry['unit']}]" if entry.get("unit") else ""
        norm = " (norm)" if entry.get("binned_by") == "norm" else ""
        lines.append(f"  {name}{norm}{unit} ({entry['law']}): {rates}")
    return lines


def _rate(value: float | None) -> str:
    return "-" if value is None else f"{100.0 * value:.0f} %"


def _replay(args: argparse.Namespace, spec: Any) -> int:
    from ..sim.plots import plot_results
    from ..sim.results import write_results
    from ..sweep.outcome import run_outcome
    from ..sweep.records import simulate_run

    seed = args.replay
    if seed < 0 or seed >= 2**63:
        raise ConfigError(f"expected a run seed from runs.csv (0 <= seed < 2**63), got {seed}",
                          "--replay")
    with output_directory(args.out):
        parameters, result = simulate_run(spec, seed)
        with writing_output(args.out):
            path = write_results(result, args.out)
            figures = [] if args.no_plots else plot_results(result, args.out, progress=False)
    if not args.quiet:
        outcome = run_outcome(result)
        print(f"{spec.name}: run of seed {seed} -> {path}"
              + (f" and {len(figures)} figures" if figures else ""))
        for name, value in parameters.items():
            variable = spec.variable(name)
            unit = f" [{variable.unit}]" if variable is not None and variable.unit else ""
            print(f"  {name:<40} {value}{unit}")
        for criterion in spec.criteria:
            value = outcome["metrics"].get(criterion.metric)
            verdict = "met" if criterion.holds(outcome["metrics"]) else "MISSED"
            print(f"  {criterion.describe():<40} {value} {verdict}")
        if getattr(result, "stopped", None):
            print(f"  stopped early: {result.stopped}")
    print_warnings(run_warnings(result))
    return 0


def run(args: argparse.Namespace) -> int:
    """Load the sweep, run what is missing, write the report; 0 unless the input is bad."""
    from ..sweep.engine import run_sweep
    from ..sweep.executors import check_workers
    from ..sweep.report import write_report
    from ..sweep.spec import load_sweep

    register_model_paths(args)
    spec = load_sweep(args.sweep).with_model_files(args.model_path)
    if args.runs is not None:
        spec = spec.with_runs(args.runs)
    if args.workers is not None:
        check_workers(args.workers)
        if args.scheduler is not None:
            raise ConfigError("give --workers or --scheduler, not both (the cluster's workers "
                              "are its own)", "--workers")
    if args.replay is not None:
        return _replay(args, spec)
    progress = _Progress(not args.quiet)
    with output_directory(args.out):
        try:
            outcome = run_sweep(spec, args.out, workers=args.workers, scheduler=args.scheduler,
                                progress=progress)
        except KeyboardInterrupt:
            progress.close()
            print(f"uvms-qp sweep: interrupted; the finished runs are in {args.out}; the same "
                  "command resumes", file=sys.stderr)
            return 130
        finally:
            progress.close()
        with writing_output(args.out):
            summary = write_report(spec, outcome.records, args.out, plots=not args.no_plots)
    if not args.quiet:
        print(f"{spec.name}: {spec.runs} runs ({outcome.new} new, {outcome.resumed} resumed, "
              f"{outcome.retried} retried) on {outcome.pool} in {outcome.wall_time:.1f} s "
              f"-> {args.out}")
        print("\n".join(summary_lines(summary)))
    return 0
