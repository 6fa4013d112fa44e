"""Benchmark the lexicographic solver back-ends (median wall time per solve, in microseconds).

Problem: n variables, levels of sizes [6, 3, 1, 4] of random equality rows, box bounds on every
variable that are wide (inactive), tight (some active) or saturated (most active). For "daqp" the
table shows, from the same runs, DAQP's own reported C time (setup + solve) next to the wall
time of ``solve_hierarchy`` (validation included), of a reused ``HierarchySolver`` fed ``Rows``,
and of ``solve_problem`` on a normalised problem, plus a bare ``daqp.solve`` call on the same data.

Run: ``python benchmarks/bench_hqp.py [--repeat N] [--cascade-repeat M]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from uvms_qp.hqp import HierarchySolver, Rows, available_solvers, solve_hierarchy
from uvms_qp.hqp.problem import normalize_problem

SIZES = (6, 3, 1, 4)
BOXES = {"wide": 100.0, "tight": 0.5, "saturated": 0.02}


def make(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    return [(rng.standard_normal((m, n)), rng.standard_normal(m)) for m in SIZES]


def median_us(fn, repeat: int) -> tuple[float, list]:
    out = []
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out.append(fn())
        times.append(time.perf_counter() - t)
    return float(np.median(times) * 1e6), out


def bench(n: int, box: str, repeat: int, cascade_repeat: int) -> list[tuple[str, float, str]]:
    import daqp

    pairs = make(n)
    levels = [[pair] for pair in pairs]
    rows = [[Rows(A, b, b)] for A, b in pairs]  # trusted construction, as a controller does
    lo, hi = -np.full(n, BOXES[box]), np.full(n, BOXES[box])
    rows_out = []

    t_api, res = median_us(lambda: solve_hierarchy(levels, lo, hi, solver="daqp"), repeat)
    c_time = np.median([r.info["daqp_solve_time"] + r.info["daqp_setup_time"] for r in res])
    status = str(res[-1].status)
    solver = HierarchySolver("daqp")
    t_rows, _ = median_us(lambda: solver.solve(rows, lo, hi), repeat)
    problem = normalize_problem(levels, lo, hi)
    t_prob, _ = median_us(lambda: solver.solve_problem(problem), repeat)

    A = np.vstack([A for A, _ in pairs])
    b = np.concatenate([b for _, b in pairs])
    bu, bl = np.concatenate((hi, b)), np.concatenate((lo, b))
    sense = np.zeros(bu.size, dtype=np.intc)
    bp = np.cumsum([n, *SIZES]).astype(np.intc)
    H, f = np.eye(n), np.zeros(n)
    t_bare, bare = median_us(lambda: daqp.solve(H, f, A, bu, bl, sense, break_points=bp,
                                                rho_soft=1e-8), repeat)
    c_bare = np.median([r[3]["solve_time"] + r[3]["setup_time"] for r in bare])

    rows_out.append(("daqp: DAQP-reported C time", c_time * 1e6, status))
    rows_out.append(("daqp: solve_hierarchy (tuples)", t_api, f"{t_api / (c_time * 1e6):.1f}x C"))
    rows_out.append(("daqp: HierarchySolver(Rows)", t_rows, f"{t_rows / (c_time * 1e6):.1f}x C"))
    rows_out.append(("daqp: solve_problem", t_prob, f"{t_prob / (c_time * 1e6):.1f}x C"))
    rows_out.append(("bare daqp.solve (wall)", t_bare, f"C {c_bare * 1e6:.1f} us"))
    for name in available_solvers():
        if name == "daqp" or (name == "nullspace" and box != "wide"):
            continue
        s = HierarchySolver(name)
        t, res = median_us(lambda s=s: s.solve_problem(problem), cascade_repeat)
        rows_out.append((name, t, str(res[-1].status)))
    return rows_out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2000)
    parser.add_argument("--cascade-repeat", type=int, default=40)
    args = parser.parse_args()
    for n in (10, 13, 30):
        for box in BOXES:
            print(f"\nn = {n}, levels {list(SIZES)}, {box} box (|x| <= {BOXES[box]:g})")
            print(f"  {'solver':<34} {'median us':>10}  note")
            for name, t, note in bench(n, box, args.repeat, args.cascade_repeat):
                print(f"  {name:<34} {t:>10.1f}  {note}")


if __name__ == "__main__":
    main()
