"""Monte-Carlo sweeps: many closed-loop runs of one scenario over drawn parameters.

A sweep file (:mod:`~uvms_qp.sweep.spec`, format in ``docs/sweeps.md``) names a base scenario,
what varies (plant parameters, current, sensor noise and delay, initial state, payload), the
number of runs, a master seed and the criteria of success. :func:`run_sweep`
(:mod:`~uvms_qp.sweep.engine`) executes the runs on a local process pool or a Dask cluster
(:mod:`~uvms_qp.sweep.executors`), appending each run's record (:mod:`~uvms_qp.sweep.records`)
as it completes, and resumes a sweep that was interrupted; :func:`write_report`
(:mod:`~uvms_qp.sweep.report`) turns the records into a table, a summary and figures.

Modules: ``distributions`` (the laws of the file), ``spec`` (the file), ``outcome`` (a run's
flat metrics), ``sampling`` (seeds and draws), ``realise`` (a run's scenario), ``records`` (one
run), ``executors``, ``engine``, ``report``.
"""

from __future__ import annotations

from .engine import SweepOutcome, run_sweep
from .executors import Pool
from .records import RunTask, run_one, simulate_run
from .report import summarise, wilson_interval, write_report
from .sampling import draw, run_seed
from .spec import Criterion, SweepSpec, Variable, bundled_sweeps, load_sweep, sweep_from_dict

__all__ = [
    "Criterion",
    "Pool",
    "RunTask",
    "SweepOutcome",
    "SweepSpec",
    "Variable",
    "bundled_sweeps",
    "draw",
    "load_sweep",
    "run_one",
    "run_seed",
    "run_sweep",
    "simulate_run",
    "summarise",
    "sweep_from_dict",
    "wilson_interval",
    "write_report",
]
