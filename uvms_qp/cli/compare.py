"""``uvms-qp compare SCENARIO --out DIR``: run a scenario under every scheme it names.

Runs the scenario's HQP stack and each closed-form scheme listed in its ``schemes`` (the papers'
redundancy resolutions, see :mod:`uvms_qp.schemes`), writes ``DIR/<scheme>/results.json`` per
scheme, ``DIR/comparison.md`` and ``DIR/comparison.json`` (the side-by-side metrics table, its
first row the plant each run drove) and PNG figures with the schemes overlaid, and prints the table
within the terminal's width (``COLUMNS`` when set, 80 characters in a pipe): the schemes that do
not fit follow in a second table. A run that breaks the scenario's hard bounds is marked
``(exceeded)`` in the table and named in a warning: the closed-form schemes ignore the bounds,
although each of their steps reports status ``optimal``. The runs' own warnings (a payload beyond
the arm's rated payload) are printed once each, naming the runs that gave them, and kept under
``warnings`` in ``comparison.json``. An invalid scenario, an unknown scheme, a ``--duration`` out
of the scenario's limits or an unusable ``--out`` (checked before anything runs) exits with
status 2 and a one-line message. ``--plant dynamic`` runs every scheme on the floating vehicle
(``docs/dynamics.md``; the table then adds its roll, pitch and thrust energy), ``--plant
kinematic`` on the exact plant, whatever the scenario's ``[plant]`` says.
"""

from __future__ import annotations

import argparse
from typing import Any

from ._common import (
    output_directory,
    print_warnings,
    register_model_paths,
    scenario_command,
    writing_output,
)


def _options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--schemes", help="comma-separated subset of the scenario's schemes (default: all)"
    )
    parser.add_argument("--duration", type=float,
                        help="override the simulated time [s] (at least one control period)")
    parser.add_argument("--plant", choices=("kinematic", "dynamic"),
                        help="override the scenario's plant for every scheme: 'dynamic' runs "
                             "them on a floating vehicle (thrusters, hydrodynamics, the arm's "
                             "reaction)")


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``compare`` sub-command to the ``uvms-qp`` parser."""
    return scenario_command(
        subparsers, "compare",
        help="run a scenario under each scheme it names: results.json per scheme + table",
        description=__doc__, func=run, quiet_help="no progress bar, no table",
        options=_options,
    )


def _table(comparison: Any, columns: list[int], title: str | None) -> Any:
    """The metrics of the runs ``columns`` (indices into ``comparison.runs``) as a rich table."""
    from rich.table import Table

    table = Table(title=title)
    table.add_column("metric", overflow="fold")  # on a very narrow console, not the numbers
    table.add_column("unit", no_wrap=True)
    for i in columns:
        table.add_column(comparison.runs[i].name, justify="right", no_wrap=True)
    for key, unit, texts in comparison.cells():
        table.add_row(key, unit, *(texts[i] for i in columns))
    return table


def print_table(comparison: Any, console: Any) -> None:
    """Print the metrics table within the console's width.

    The schemes that fit beside the metric and unit columns share a table; the others follow in
    tables of their own, each repeating the metric and unit columns (a scheme wider than the
    console on its own still gets a whole table).
    """
    unbounded = console.options.update_width(1_000_000)  # the tables' natural widths
    groups: list[list[int]] = []
    for i in range(len(comparison.runs)):
        table = _table(comparison, groups[-1] + [i], None) if groups else None
        if table is not None and console.measure(table, options=unbounded).maximum \
                <= console.width:
            groups[-1].append(i)
        else:
            groups.append([i])
    title = f"{comparison.scenario}: {comparison.description}"
    for k, group in enumerate(groups):
        if k:
            console.print()
        console.print(_table(comparison, group, title if k == 0 else None))


def run(args: argparse.Namespace) -> int:
    """Run the comparison and write results, table and figures into ``args.out``."""
    from ..sim.comparison import compare
    from ..sim.comparison_figures import plot_comparison
    from ..sim.scenario import load_scenario

    register_model_paths(args)
    scenario = load_scenario(args.scenario)
    if args.duration is not None:
        scenario = scenario.with_duration(args.duration, "--duration")
    if args.plant is not None:
        scenario = scenario.with_plant(args.plant, "--plant")
    subset = None
    if args.schemes:
        subset = [name.strip() for name in args.schemes.split(",") if name.strip()]
    with output_directory(args.out):
        comparison = compare(scenario, subset, progress=not args.quiet)
        with writing_output(args.out):
            comparison.write(args.out)
            if not args.no_plots:
                plot_comparison(comparison, scenario.model, args.out, progress=not args.quiet)
    if not args.quiet:
        from rich.console import Console

        print_table(comparison, Console())
        figures = "" if args.no_plots else " and figures"
        print(f"results, comparison.md{figures} in {args.out}")
    print_warnings(comparison.notes() + comparison.warning_lines())
    return 0
