"""The mission's physical tasks measured on the floating vehicle (docs/dynamics.md).

Station keeping, current alignment and the payload moment exist for physical reasons, and
arm-vehicle coordination for a physical lag: their benefit shows only on a plant that does not
realise the command exactly. Each comparison runs the bundled demo (``bluerov2_demo``) on the
dynamic plant twice, with and without one feature, everything else equal:

- **station keeping** under the demo's current: vehicle drift while the tool works within reach
  (the ``within_reach`` phase) and the thrust energy;
- **current alignment** with the demo's current (0.2 rad off the bow) and with a beam current
  (the same 0.2 m/s at pi/2 rad): the thrust energy to hold station while the tool works within
  reach (``within_reach``; later the path and the payload's place on the vehicle depend on its
  heading, which would mix other effects in);
- **payload moment** after the 20 N pick-up (the ``after_pickup`` phase): pitch disturbance,
  energy;
- **coordination** (the arm's levels re-solved with the vehicle's measured velocity, Simetti et
  al. (2014)): the tool's error along the whole run.

Run it with ``python -m uvms_qp.sim.physical_tasks --out DIR`` (a few minutes: ten runs of 30 s
of simulated time); it prints the table in Markdown and writes ``physical_tasks.json`` and
``physical_tasks.md`` into ``DIR``.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ._files import write_atomic
from .config import read_toml
from .runner import SimulationResult, simulate
from .scenario import resolve_scenario, scenario_from_dict

#: The scenario every comparison edits.
BASE = "bluerov2_demo"

Edit = Callable[[dict[str, Any]], None]


def _drop_task(name: str) -> Edit:
    """Remove the task ``name`` (and its level when it empties, and events that update it)."""

    def edit(data: dict[str, Any]) -> None:
        levels = []
        for level in data["levels"]:
            tasks = [t for t in level["tasks"] if t.get("name", t["type"]) != name]
            if tasks:
                levels.append({**level, "tasks": tasks})
        data["levels"] = levels
        data["events"] = [e for e in data.get("events", []) if e["task"] != name]

    return edit


def _set(path: tuple[str, ...], value: Any) -> Edit:
    def edit(data: dict[str, Any]) -> None:
        table = data
        for key in path[:-1]:
            table = table.setdefault(key, {})
        table[path[-1]] = value

    return edit


def _both(*edits: Edit) -> Edit:
    def edit(data: dict[str, Any]) -> None:
        for e in edits:
            e(data)

    return edit


@dataclass(frozen=True)
class Comparison:
    """One feature on and off: what is measured, over which window.

    Attributes:
        name: Short name (the table's first column).
        feature: What is switched.
        on: Edit of the base scenario with the feature on (None: the base as it is).
        off: Edit with the feature off.
        phase: Scenario phase the figures are taken over (None: the whole run).
        metrics: ``(key, label, unit)`` of the numbers compared.
    """

    name: str
    feature: str
    on: Edit | None
    off: Edit
    phase: str | None
    metrics: tuple[tuple[str, str, str], ...]


_BEAM = _set(("current", "direction"), math.pi / 2)
COMPARISONS: tuple[Comparison, ...] = (
    Comparison("station keeping", "station_keeping task", None, _drop_task("station_keeping"),
               "within_reach", (("vehicle_displacement_max", "vehicle drift", "m"),
                                ("energy", "thrust energy", "J"))),
    Comparison("current alignment (demo current, 0.2 rad)", "current_alignment task", None,
               _drop_task("current_alignment"), "within_reach",
               (("energy", "thrust energy", "J"), ("power_mean", "mean power", "W"))),
    Comparison("current alignment (beam current, pi/2 rad)", "current_alignment task", _BEAM,
               _both(_BEAM, _drop_task("current_alignment")), "within_reach",
               (("energy", "thrust energy", "J"), ("power_mean", "mean power", "W"))),
    Comparison("payload moment", "payload_moment task", None, _drop_task("payload"),
               "after_pickup", (("pitch_max", "pitch disturbance, peak", "rad"),
                                ("pitch_rms", "pitch disturbance, RMS", "rad"),
                                ("energy", "thrust energy", "J"))),
    Comparison("coordination", "plant coordination", _set(("plant", "coordination"), True),
               _set(("plant", "coordination"), False), None,
               (("ee_error_rms", "tool error RMS", "m"), ("ee_error_max", "tool error max",
                                                         "m"))),
)


def _run(edit: Edit | None, duration: float | None) -> SimulationResult:
    path = resolve_scenario(BASE)
    data = copy.deepcopy(read_toml(path))
    data.setdefault("plant", {})["type"] = "dynamic"
    if edit is not None:
        edit(data)
    scenario = scenario_from_dict(data, source=path, name=BASE)
    if duration is not None:
        scenario = scenario.with_duration(duration)
    return simulate(scenario)


def _numbers(result: SimulationResult, comparison: Comparison) -> dict[str, float | None]:
    metrics = (result.metrics() if comparison.phase is None
               else result.phase_metrics().get(comparison.phase, {}))
    return {key: metrics.get(key) for key, _, _ in comparison.metrics}


def run_study(duration: float | None = None, names: Sequence[str] | None = None,
              progress: Callable[[str], None] | None = None) -> list[dict[str, Any]]:
    """Run the comparisons; one record per comparison with the numbers on and off.

    Args:
        duration: Simulated time of every run [s] (default the demo's 30 s).
        names: Comparisons to run (default all, :data:`COMPARISONS`).
        progress: Called with a line as each run starts.
    """
    records = []
    for comparison in COMPARISONS:
        if names is not None and comparison.name not in names:
            continue
        numbers = {}
        for label, edit in (("on", comparison.on), ("off", comparison.off)):
            if progress is not None:
                progress(f"{comparison.name}: {comparison.feature} {label}")
            numbers[label] = _numbers(_run(edit, duration), comparison)
        records.append({"name": comparison.name, "feature": comparison.feature,
                        "phase": comparison.phase or "whole run",
                        "metrics": [{"key": key, "label": label, "unit": unit,
                                     "on": numbers["on"][key], "off": numbers["off"][key]}
                                    for key, label, unit in comparison.metrics]})
    return records


def _cell(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"


def markdown(records: list[dict[str, Any]]) -> str:
    """The study as a Markdown table: one row per compared number."""
    lines = ["| comparison | window | measure | on | off | off / on |",
             "|---|---|---|---|---|---|"]
    for record in records:
        for m in record["metrics"]:
            on, off = m["on"], m["off"]
            ratio = (f"{off / on:.2f}" if on not in (None, 0.0) and off is not None else "-")
            unit = f" [{m['unit']}]" if m["unit"] else ""
            lines.append(f"| {record['name']} | {record['phase']} | {m['label']}{unit} | "
                         f"{_cell(on)} | {_cell(off)} | {ratio} |")
    if any(m["on"] is None or m["off"] is None for r in records for m in r["metrics"]):
        lines.append("\n-: the run did not reach that window (a shorter --duration).")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m uvms_qp.sim.physical_tasks --out DIR [--duration S]``."""
    parser = argparse.ArgumentParser(prog="python -m uvms_qp.sim.physical_tasks",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--duration", type=float, help="simulated time of each run [s]")
    args = parser.parse_args(argv)
    records = run_study(args.duration, progress=lambda line: print(line, file=sys.stderr))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table = markdown(records)
    write_atomic(out / "physical_tasks.json", json.dumps(records, indent=1))
    write_atomic(out / "physical_tasks.md", table + "\n")
    print(table)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
