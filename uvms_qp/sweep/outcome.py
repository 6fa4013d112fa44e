"""What a sweep keeps of one run: its metrics as flat, named numbers.

A run's :class:`~uvms_qp.sim.runner.SimulationResult` gives the metrics of ``results.json``
(:mod:`uvms_qp.sim.metrics`), nested by axis, task, unit and phase. A sweep keeps them flat, one
column each, named by their path with dots: ``ee_error_final``,
``command_reversals_per_s.axis_d``, ``settling_time.tool``, ``phases.after_pickup.ee_error_max``;
strings (the worst reversal axis) stay strings, non-finite numbers become None. One metric is the
sweep's own:

- ``level_met_share.K`` (per level ``K``, 0 the highest): the share of control steps whose level
  residual is at most :data:`~uvms_qp.hqp.certificate.LEVEL_TOL` (``top level met on >= 99 % of
  steps`` is ``"level_met_share.0" = { min = 0.99 }``).

The metrics that measure the machine rather than the run (the controller's step times, the steps
over a deadline) are kept apart under ``timing``: the rest are the same bit for bit wherever a run
is computed.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..hqp.certificate import LEVEL_TOL
from ..sim.runner import SimulationResult, simulate
from ..sim.scenario import Scenario

#: Metrics that depend on the machine's speed, kept under ``timing``.
TIMING_METRICS = ("step_time_median_us", "step_time_p99_us", "deadline_missed_steps")
#: Counts kept whole under their own keys rather than flattened.
COUNT_METRICS = ("status_counts", "stage_counts")


def _flatten(value: Any, prefix: str, out: dict[str, Any]) -> None:
    if isinstance(value, dict):
        for key, item in value.items():
            _flatten(item, f"{prefix}.{key}" if prefix else str(key), out)
    elif isinstance(value, bool | str) or value is None:
        out[prefix] = value
    elif isinstance(value, int | np.integer):
        out[prefix] = int(value)
    elif isinstance(value, float | np.floating):
        out[prefix] = float(value) if math.isfinite(value) else None


def level_met_share(result: SimulationResult) -> dict[str, float | None]:
    """Share of steps whose residual is at most ``LEVEL_TOL``, by level index (as a string)."""
    residuals = result.level_residuals
    if residuals.shape[0] == 0:
        return {str(k): None for k in range(residuals.shape[1])}
    met = np.asarray(residuals <= LEVEL_TOL)  # NaN (not reported) counts as unmet
    return {str(k): float(share) for k, share in enumerate(met.mean(axis=0).tolist())}


def run_outcome(result: SimulationResult) -> dict[str, Any]:
    """The flat metrics, the timing figures and the counts of one run.

    Returns:
        ``{"metrics": {name: number or string or None}, "timing": {...}, "status_counts":
        {...}, "stage_counts": {...}}``.
    """
    nested = result.metrics()
    counts = {key: {str(k): int(v) for k, v in (nested.pop(key, None) or {}).items()}
              for key in COUNT_METRICS}
    timing = {key: nested.pop(key, None) for key in TIMING_METRICS}
    timing["wall_time_s"] = result.wall_time
    nested["level_met_share"] = level_met_share(result)
    nested["phases"] = result.phase_metrics()
    metrics: dict[str, Any] = {}
    _flatten(nested, "", metrics)
    flat_timing: dict[str, Any] = {}
    _flatten(timing, "", flat_timing)
    return {"metrics": metrics, "timing": flat_timing, **counts}


def metric_names(scenario: Scenario) -> set[str]:
    """The metric names the runs of ``scenario`` report, from a pilot run of two steps.

    Give the pilot phases inside its two steps to learn the phase metrics' names too.
    """
    pilot = scenario.with_duration(2.0 * scenario.dt)
    pilot = dataclasses.replace(pilot, events=())
    return set(run_outcome(simulate(pilot))["metrics"])
