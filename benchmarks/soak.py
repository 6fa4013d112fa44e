"""Soak benchmark: the bundled demo for many steps with re-randomised targets and injected faults.

Run by hand (10^6 steps take a while; figures go in the reliability notes)::

    python benchmarks/soak.py --steps 1000000
    python benchmarks/soak.py --steps 100000 --fault-rate 0.05 --solver cascade:quadprog

Prints unsafe outputs (must be 0), joint-limit excursions (must be 0), steps per fallback stage,
statuses, injected faults, tracemalloc growth after the warm-up (target <= 1 MiB) and the
step-time medians of the first and last cycles after the warm-up (no drift; n/a below 10^4
steps). Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import sys

from uvms_qp.testing.soak import run_soak


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fault-rate", type=float, default=0.01)
    parser.add_argument("--solver", default="daqp")
    parser.add_argument("--deadline", type=float, default=0.02, help="[s]")
    parser.add_argument("--no-trace", action="store_true", help="skip tracemalloc (faster)")
    args = parser.parse_args()
    report = run_soak(args.steps, seed=args.seed, fault_rate=args.fault_rate,
                      solver=args.solver, deadline=args.deadline,
                      trace_memory=not args.no_trace, progress=True)
    print("\n".join(report.lines()))
    failed = (report.unsafe or report.limit_excursions  # a figure not measured misses nothing
              or (report.memory_growth or 0) > 1024 * 1024 or (report.drift or 0.0) > 0.25)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
