"""The report of a sweep: how often it succeeded, how its metrics spread, what made runs fail.

Written into the sweep's output folder next to ``runs.jsonl``:

- ``runs.csv``: one row per run and one column per field (``index``, ``seed``, ``status``,
  ``success``, ``failed``, ``error``, ``attempts``, each drawn parameter (a vector one as
  ``name[i]``), each metric, ``status_counts.*``, ``stage_counts.*``, ``timing.*``), read by
  ``pandas.read_csv`` as it is;
- ``summary.json``: the success rate with its 95 % Wilson score interval, the runs per status,
  each criterion with the number of runs that missed it, the percentiles of every numeric
  metric and, per varied parameter, its law, its unit, the success rate in each of its
  non-empty bins (``bins``; ``binned_by``: ``norm`` for a vector perturbation) and what
  defines every bin, empty ones too (``options``: a choice's values; ``edges``: the bin edges
  of numbers; :func:`all_bins` puts the two together);
- ``metrics.png``: histograms of the criteria's metrics (and a few headline ones), successes and
  failures stacked, each criterion's bound drawn;
- ``success_by_parameter.png``: per varied parameter, the success rate (with its Wilson
  interval) over bins of the parameter's values; a vector perturbation is binned by its norm.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import binomtest

from ..sim._figures import pyplot, save
from ..sim._files import write_atomic
from .spec import SweepSpec, Variable

TABLE_FILE = "runs.csv"
SUMMARY_FILE = "summary.json"
METRICS_FIGURE = "metrics.png"
PARAMETERS_FIGURE = "success_by_parameter.png"
#: Confidence level of the success-rate intervals.
CONFIDENCE = 0.95
#: Percentiles reported for each metric.
PERCENTILES = (5, 25, 50, 75, 95)
#: Bins of a numeric parameter in the success-by-parameter figure and summary.
PARAMETER_BINS = 6
#: Metrics shown in ``metrics.png`` after the criteria's, when the runs report them.
HEADLINE_METRICS = ("ee_error_max", "ee_error_final", "bound_violation_max",
                    "vehicle_displacement_max", "joint_margin_min", "level_met_share.0",
                    "pitch_max", "energy", "saturation_share_max")
#: Most histograms in ``metrics.png``.
MAX_HISTOGRAMS = 9


def wilson_interval(successes: int, runs: int, confidence: float = CONFIDENCE
                    ) -> tuple[float, float]:
    """The Wilson score interval of a success rate (``(nan, nan)`` without runs)."""
    if runs == 0:
        return (math.nan, math.nan)
    ci = binomtest(successes, runs).proportion_ci(confidence_level=confidence,
                                                   method="wilson")
    return (float(ci.low), float(ci.high))


def parameter_value(variable: Variable, value: Any) -> Any:
    """A parameter as one value: a number, a string, or the norm of a vector perturbation."""
    if isinstance(value, list):
        return float(np.linalg.norm(np.asarray(value, dtype=float)))
    return value


def _numbers(records: Sequence[dict[str, Any]], metric: str) -> np.ndarray:
    values = [r["metrics"].get(metric) for r in records]
    return np.array([v for v in values if isinstance(v, int | float) and not isinstance(v, bool)
                     and v is not None and math.isfinite(v)], dtype=float)


def metric_summary(records: Sequence[dict[str, Any]]) -> dict[str, dict[str, float | int]]:
    """Count, mean, min, percentiles and max of every numeric metric over the runs."""
    names = sorted({k for r in records for k, v in r["metrics"].items()
                    if isinstance(v, int | float) and not isinstance(v, bool)})
    out: dict[str, dict[str, float | int]] = {}
    for name in names:
        values = _numbers(records, name)
        if not values.size:
            continue
        row: dict[str, float | int] = {"count": int(values.size), "mean": float(values.mean()),
                                       "min": float(values.min())}
        for p, v in zip(PERCENTILES, np.percentile(values, PERCENTILES).tolist(), strict=True):
            row[f"p{p}"] = float(v)
        row["max"] = float(values.max())
        out[name] = row
    return out


def _choice_options(variable: Variable) -> list[Any] | None:
    """The options of a one-value choice law, in the file's order (None for other laws)."""
    if variable.dist.kind != "choice" or variable.count != 1:
        return None
    return list(dict.fromkeys(getattr(variable.dist, "options", ())))


def _bin_table(variable: Variable, records: Sequence[dict[str, Any]]
               ) -> tuple[list[dict[str, Any]], dict[str, list[Any]]]:
    """Every bin of one varied parameter, empty ones included, and what defines the bins."""
    pairs = [(parameter_value(variable, r["parameters"].get(variable.name)), bool(r["success"]))
             for r in records if variable.name in r["parameters"]]
    if not pairs:
        return [], {}
    bins: list[dict[str, Any]] = []
    options = _choice_options(variable)
    if options is not None or isinstance(pairs[0][0], str) or variable.dist.kind == "choice":
        drawn = sorted({v for v, _ in pairs}, key=str)
        values = (options or []) + [v for v in drawn if v not in (options or [])]
        for value in values:
            hits = [ok for v, ok in pairs if v == value]
            bins.append({"value": value, "runs": len(hits), "successes": sum(hits)})
        defined: dict[str, list[Any]] = {"options": values}
    else:
        numbers = np.array([v for v, _ in pairs], dtype=float)
        ok = np.array([s for _, s in pairs], dtype=bool)
        count = min(PARAMETER_BINS, len(set(numbers.tolist())))  # no more bins than values
        edges = np.linspace(numbers.min(), numbers.max(), count + 1)
        which = np.clip(np.searchsorted(edges, numbers, side="right") - 1, 0, count - 1)
        for b in range(count):
            mask = which == b
            bins.append({"low": float(edges[b]), "high": float(edges[b + 1]),
                         "runs": int(mask.sum()), "successes": int(ok[mask].sum())})
        defined = {"edges": edges.tolist()}
    for entry in bins:
        runs = entry["runs"]
        entry["rate"] = entry["successes"] / runs if runs else None
        entry["ci"] = list(wilson_interval(entry["successes"], runs)) if runs else None
    return bins, defined


def parameter_bins(variable: Variable, records: Sequence[dict[str, Any]]
                   ) -> list[dict[str, Any]]:
    """Success rate of the runs in each non-empty bin of one varied parameter's values.

    Numbers fall into :data:`PARAMETER_BINS` equal-width bins over the values drawn (a vector
    perturbation by its norm; no more bins than distinct values drawn); a choice (of names
    or numbers) gets one bin per option, in the file's order.

    Returns:
        One entry per non-empty bin: ``low``, ``high`` (numbers) or ``value``, ``runs``,
        ``successes``, ``rate``, ``ci`` (Wilson, :data:`CONFIDENCE`). :func:`all_bins` adds
        the empty ones back.
    """
    return [b for b in _bin_table(variable, records)[0] if b["runs"]]


def all_bins(entry: dict[str, Any]) -> list[dict[str, Any]]:
    """Every bin of a parameter's entry in ``summary.json``, the empty ones too.

    The empty bins (no run drew a value in them: an option never drawn, a range between the
    values drawn) have ``runs`` 0 and ``rate`` and ``ci`` None. An entry without ``options`` or
    ``edges`` (no recorded run drew the parameter) has no bin.
    """
    bins = entry["bins"]
    if "options" in entry:
        return [next((b for b in bins if b["value"] == v),
                     {"value": v, "runs": 0, "successes": 0, "rate": None, "ci": None})
                for v in entry["options"]]
    if "edges" in entry:
        edges = entry["edges"]
        by_low = {(b["low"], b["high"]): b for b in bins}
        return [by_low.get((low, high), {"low": low, "high": high, "runs": 0, "successes": 0,
                                         "rate": None, "ci": None})
                for low, high in itertools.pairwise(edges)]
    return list(bins)


def bin_label(entry: dict[str, Any], index: int, count: int) -> str:
    """A bin's value (a choice) or range (numbers: ``[low, high)``, the last one closed)."""
    if "value" in entry:
        return str(entry["value"])
    close = "]" if index == count - 1 else ")"
    return f"[{entry['low']:.3g}, {entry['high']:.3g}{close}"


def _parameter_entry(variable: Variable, records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    bins, defined = _bin_table(variable, records)
    return {"law": variable.dist.describe(), "unit": variable.unit,
            "bins": [b for b in bins if b["runs"]], **defined,
            **({"binned_by": "norm"} if variable.count > 1 else {})}


def summarise(spec: SweepSpec, records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The content of ``summary.json`` (see the module docstring)."""
    runs = len(records)
    successes = sum(1 for r in records if r["success"])
    statuses: dict[str, int] = {}
    for r in records:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
    criteria = [{"criterion": c.describe(), "metric": c.metric, "min": c.low, "max": c.high,
                 "missed": sum(1 for r in records if c.describe() in r["failed"])}
                for c in spec.criteria]
    return {
        "sweep": spec.name, "scenario": spec.scenario, "plant": spec.plant, "seed": spec.seed,
        "runs": spec.runs, "recorded": runs, "successes": successes,
        "success_rate": successes / runs if runs else None,
        "success_interval": list(wilson_interval(successes, runs)) if runs else None,
        "confidence": CONFIDENCE,
        "statuses": statuses, "criteria": criteria,
        "metrics": metric_summary(records),
        "parameters": {v.name: _parameter_entry(v, records) for v in spec.varied},
    }


def table_columns(records: Sequence[dict[str, Any]]) -> list[str]:
    """The columns of ``runs.csv``, in order."""
    params: dict[str, None] = {}
    for r in records:
        for name, value in r["parameters"].items():
            if isinstance(value, list):
                params.update({f"{name}[{i}]": None for i in range(len(value))})
            else:
                params[name] = None
    metrics = sorted({k for r in records for k in r["metrics"]})
    extra = sorted({f"{group}.{k}" for r in records
                    for group in ("status_counts", "stage_counts", "timing")
                    for k in r.get(group, {})})
    return ["index", "seed", "status", "success", "failed", "error", "attempts",
            *params, *metrics, *extra]


def table_row(record: dict[str, Any]) -> dict[str, Any]:
    """One run as a flat row of ``runs.csv`` (None becomes an empty cell)."""
    row: dict[str, Any] = {key: record.get(key) for key in ("index", "seed", "status", "success",
                                                             "error", "attempts")}
    row["failed"] = "; ".join(record["failed"])
    for name, value in record["parameters"].items():
        if isinstance(value, list):
            row.update({f"{name}[{i}]": v for i, v in enumerate(value)})
        else:
            row[name] = value
    row.update(record["metrics"])
    for group in ("status_counts", "stage_counts", "timing"):
        row.update({f"{group}.{k}": v for k, v in record.get(group, {}).items()})
    return row


def write_table(records: Sequence[dict[str, Any]], path: Path) -> Path:
    """Write ``runs.csv`` atomically, rows by run index."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=table_columns(records), restval="",
                            lineterminator="\n")
    writer.writeheader()
    for record in sorted(records, key=lambda r: r["index"]):
        writer.writerow({k: ("" if v is None else v) for k, v in table_row(record).items()})
    return write_atomic(path, buffer.getvalue())


def _histograms(spec: SweepSpec, records: Sequence[dict[str, Any]]) -> Any:
    plt = pyplot()
    names = list(dict.fromkeys([c.metric for c in spec.criteria] + [
        m for m in HEADLINE_METRICS if _numbers(records, m).size]))[:MAX_HISTOGRAMS]
    names = [n for n in names if _numbers(records, n).size] or ["(no numeric metric)"]
    cols = min(3, len(names))
    rows = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.0 * rows), squeeze=False,
                             layout="constrained")
    good = [r for r in records if r["success"]]
    bad = [r for r in records if not r["success"]]
    for ax, name in zip(axes.flat, names, strict=False):
        both = _numbers(records, name)
        if both.size:
            bins = np.histogram_bin_edges(both, bins=min(30, max(5, both.size // 4)))
            ax.hist([_numbers(good, name), _numbers(bad, name)], bins=bins, stacked=True,
                    color=["tab:green", "tab:red"], label=["success", "failure"])
        for c in spec.criteria:
            if c.metric == name:
                for bound in (c.low, c.high):
                    if bound is not None:
                        ax.axvline(bound, color="black", linestyle="--", linewidth=1)
        ax.set_title(name, fontsize=9)
        ax.set_ylabel("runs")
    for ax in list(axes.flat)[len(names):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8)
    fig.suptitle(f"{spec.name}: metrics over {len(records)} runs (dashed: success bounds)")
    return fig


def _parameter_panels(spec: SweepSpec, records: Sequence[dict[str, Any]],
                      summary: dict[str, Any]) -> Any:
    plt = pyplot()
    varied: list[Variable | None] = [*spec.varied] or [None]
    cols = min(3, len(varied))
    rows = math.ceil(len(varied) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.0 * rows), squeeze=False,
                             layout="constrained")
    overall = summary["success_rate"]
    for ax, variable in zip(axes.flat, varied, strict=False):
        if variable is None:
            ax.text(0.5, 0.5, "no parameter varies", ha="center", va="center")
            ax.set_axis_off()
            continue
        every = all_bins(summary["parameters"][variable.name])
        x = np.arange(len(every))
        ranges = bool(every) and "low" in every[0]  # bins of numbers: their ranges, slanted
        ax.set_xticks(x, [bin_label(b, i, len(every)) for i, b in enumerate(every)],
                      fontsize=7, rotation=30 if ranges else 0, ha="right" if ranges else "center")
        full = [i for i, b in enumerate(every) if b["runs"]]
        rate = np.array([every[i]["rate"] for i in full], dtype=float)
        low = rate - np.array([every[i]["ci"][0] for i in full], dtype=float)
        high = np.array([every[i]["ci"][1] for i in full], dtype=float) - rate
        ax.bar(x[full], rate, width=0.8, color="tab:blue", alpha=0.6)
        ax.errorbar(x[full], rate, yerr=[low, high], fmt="none", ecolor="black", capsize=3)
        for xi, b in zip(x, every, strict=True):
            ax.text(xi, 1.02, str(b["runs"]), ha="center", fontsize=7)
        if overall is not None:
            ax.axhline(overall, color="tab:gray", linestyle="--", linewidth=1)
        label = variable.name + (" (norm)" if variable.count > 1 else "")
        ax.set_xlabel(f"{label} [{variable.unit}]" if variable.unit else label, fontsize=8)
        ax.set_ylabel("success rate")
        ax.set_ylim(0.0, 1.1)
    for ax in list(axes.flat)[len(varied):]:
        ax.set_visible(False)
    fig.suptitle(f"{spec.name}: success rate by parameter ({int(CONFIDENCE * 100)} % Wilson "
                 "intervals; runs per bin on top; dashed: overall)")
    return fig


def write_report(spec: SweepSpec, records: Sequence[dict[str, Any]], out: str | Path, *,
                 plots: bool = True) -> dict[str, Any]:
    """Write ``runs.csv``, ``summary.json`` and (with ``plots``) the two figures into ``out``.

    Returns:
        The summary (the content of ``summary.json``).
    """
    directory = Path(out)
    summary = summarise(spec, records)
    write_table(records, directory / TABLE_FILE)
    write_atomic(directory / SUMMARY_FILE, json.dumps(summary, indent=1, allow_nan=False) + "\n")
    if plots and records:
        save(_histograms(spec, records), directory / METRICS_FIGURE)
        save(_parameter_panels(spec, records, summary), directory / PARAMETERS_FIGURE)
    return summary
