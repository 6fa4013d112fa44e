"""Benchmark the lexicographic solver back-ends (median wall time per solve, in microseconds).

Problem: n variables, levels of sizes [6, 3, 1, 4] of random equality rows, box bounds on every
variable that are wide (inactive), tight (some active) or saturated (most active). For "daqp" the
table shows, from the same interleaved runs (every variant is called once per round, so all see
the same machine load), DAQP's own reported C time next to the wall time of

* ``solve_hierarchy`` on ``(A, b)`` tuples (public entry: validation, DAQP, measurement, result),
* a reused ``HierarchySolver`` fed ``Rows``,
* ``solve_problem`` on a filled :class:`~uvms_qp.hqp.Problem` (what a controller calls),
* a reused ``daqp.Model`` (``update`` + ``solve``) on the same data, and the direct C calls of
  the binding (``refresh`` + ``solve``): the floor of any Python wrapper.

The ratio column is the median wall time over ``daqp.Model``'s ``update + solve``. Cascades and
the closed form follow.

Run: ``python benchmarks/bench_hqp.py [--repeat N] [--cascade-repeat M] [--sizes 10 13 30]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from uvms_qp.hqp import HierarchySolver, Rows, available_solvers, normalize_problem, solve_hierarchy
from uvms_qp.hqp.backends.daqp_binding import NativeDaqp

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


def interleaved(fns: dict[str, Callable[[], Any]], repeat: int) -> dict[str, tuple[float, Any]]:
    """Median wall time [us] of each function and its last output, called round-robin."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    last: dict[str, Any] = {}
    for _ in range(repeat):
        for k, fn in fns.items():
            t = time.perf_counter()
            last[k] = fn()
            times[k].append(time.perf_counter() - t)
    return {k: (float(np.median(v) * 1e6), last[k]) for k, v in times.items()}


def bench(n: int, box: str, repeat: int, cascade_repeat: int) -> list[tuple[str, float, str]]:
    import daqp

    pairs = make(n)
    levels = [[pair] for pair in pairs]
    rows = [[Rows(A, b, b)] for A, b in pairs]
    lo, hi = -np.full(n, BOXES[box]), np.full(n, BOXES[box])
    problem = normalize_problem(levels, lo, hi)
    by_rows, by_problem = HierarchySolver("daqp"), HierarchySolver("daqp")

    A = np.vstack([A for A, _ in pairs])
    b = np.concatenate([b for _, b in pairs])
    bu, bl = np.concatenate((hi, b)), np.concatenate((lo, b))
    sense = np.zeros(bu.size, dtype=np.intc)
    bp = np.cumsum([n, *SIZES]).astype(np.intc)
    H, f = np.eye(n), np.zeros(n)
    model = daqp.Model()
    model.setup(H, f, A, bu, bl, sense, break_points=bp)
    settings = model.settings
    settings.update(rho_soft=1e-8, primal_tol=1e-10)
    model.settings = settings

    def model_call():
        model.update(A=A, bupper=bu, blower=bl)
        return model.solve()

    fns: dict[str, Callable[[], Any]] = {}
    native = NativeDaqp()
    native.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), bp)
    native.settings = {"rho_soft": 1e-8, "primal_tol": 1e-10}

    def native_call():
        native.refresh()
        return native.solve()

    fns["native"] = native_call

    c_times: list[float] = []

    def api():
        result = solve_hierarchy(levels, lo, hi, solver="daqp")
        c_times.append(result.info["daqp_solve_time"] + result.info["daqp_setup_time"])
        return result

    runs = interleaved({
        "api": api,
        "rows": lambda: by_rows.solve(rows, lo, hi),
        "prob": lambda: by_problem.solve_problem(problem),
        "model": model_call,
        **fns,
    }, repeat)
    c_us = float(np.median(c_times) * 1e6)
    ref = runs["model"][0]

    def ratio(key: str) -> str:
        return f"{runs[key][0] / ref:.2f}x daqp.Model"

    out = [
        ("daqp: DAQP-reported C time", c_us, str(runs["api"][1].status)),
        ("daqp: solve_hierarchy (tuples)", runs["api"][0], ratio("api")),
        ("daqp: HierarchySolver(Rows)", runs["rows"][0], ratio("rows")),
        ("daqp: solve_problem (filled Problem)", runs["prob"][0], ratio("prob")),
        ("daqp.Model update+solve (wall)", ref, ratio("model")),
    ]
    if "native" in runs:
        out.append(("direct C refresh+solve (wall)", runs["native"][0], ratio("native")))
    for name in available_solvers():
        if name == "daqp" or (name == "nullspace" and box != "wide"):
            continue
        s = HierarchySolver(name)
        t, res = median_us(lambda s=s: s.solve_problem(problem), cascade_repeat)
        out.append((name, t, str(res[-1].status)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2000)
    parser.add_argument("--cascade-repeat", type=int, default=40)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 13, 30])
    args = parser.parse_args()
    for n in args.sizes:
        for box in BOXES:
            print(f"\nn = {n}, levels {list(SIZES)}, {box} box (|x| <= {BOXES[box]:g})")
            print(f"  {'solver':<38} {'median us':>10}  note")
            for name, t, note in bench(n, box, args.repeat, args.cascade_repeat):
                print(f"  {name:<38} {t:>10.1f}  {note}")


if __name__ == "__main__":
    main()
