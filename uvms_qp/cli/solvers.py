"""``uvms-qp solvers``: list the lexicographic solvers, their capabilities and availability."""

from __future__ import annotations

import argparse
from typing import Any


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``solvers`` sub-command to ``subparsers``."""
    parser = subparsers.add_parser(
        "solvers",
        help="list usable solvers",
        description="List the solver names accepted by solve_hierarchy(..., solver=NAME).",
    )
    parser.add_argument("--all", action="store_true",
                        help="also list solvers whose back-end is not installed")
    parser.set_defaults(func=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Print one line per solver: name, capabilities, tolerance, availability."""
    from ..hqp.registry import SOLVERS

    print(f"{'solver':<18} {'levels':<11} {'bounds':<8} {'agreement':<10} status")
    for spec in SOLVERS:
        available = spec.available
        if not available and not args.all:
            continue
        levels = "eq + ineq" if spec.inequality_levels else "eq only"
        bounds = "enforced" if spec.bounds else "checked"
        status = "installed" if available else f"missing: pip install {spec.pip}"
        print(f"{spec.name:<18} {levels:<11} {bounds:<8} {spec.agreement_tol:<10.0e} {status}")
    return 0
