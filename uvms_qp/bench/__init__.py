"""``uvms-qp bench``: every solver and scheme on scenarios, random UVMS problems, raw hierarchies.

Modules: :mod:`~uvms_qp.bench.sets` (test sets), :mod:`~uvms_qp.bench.stacks` (ready-made
stacks), :mod:`~uvms_qp.bench.runners` (solvers and schemes),
:mod:`~uvms_qp.bench.pink_adapter` (Pink side by side), :mod:`~uvms_qp.bench.metrics`
(aggregation and ranking), :mod:`~uvms_qp.bench.report` (stores, tables, plot) and
:mod:`~uvms_qp.bench.engine` (the resumable run). ``benchmarks/README.md`` explains how to
reproduce the published table.
"""

from __future__ import annotations

from .engine import BenchOutcome, run_benchmark
from .metrics import Summary, summarize
from .record import HARD_TOL, Record
from .sets import SET_NAMES, BenchProblem, SetConfig, build_sets, random_uvms_problem
from .stacks import demo_stack, random_bounds, random_stack, tool_posture_stack

__all__ = [
    "HARD_TOL",
    "SET_NAMES",
    "BenchOutcome",
    "BenchProblem",
    "Record",
    "SetConfig",
    "Summary",
    "build_sets",
    "demo_stack",
    "random_bounds",
    "random_stack",
    "random_uvms_problem",
    "run_benchmark",
    "summarize",
    "tool_posture_stack",
]
