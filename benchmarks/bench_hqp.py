"""Benchmark the lexicographic solver back-ends (median wall time per solve, in microseconds).

Problem: n variables, levels of sizes [6, 3, 1, 4] of random equality rows, box bounds on every
variable that are wide (inactive), tight (some active) or saturated (most active). For "daqp" the
table shows, from the same interleaved runs (every variant is called once per round, so all see
the same machine load), DAQP's own reported C time next to the wall time of

* ``solve_hierarchy`` on ``(A, b)`` tuples (public entry, validation included),
* a reused ``HierarchySolver`` fed ``Rows``,
* ``solve_problem`` on a normalised problem (the trusted entry a controller uses),
* the same two entries on the reference path (``lean=False``: full normalisation, stacking and
  evaluation on the ``Problem``; this is what every call cost before the lean path),
* :class:`~uvms_qp.hqp.inplace.InPlaceDaqp` on the same structure, the caller writing the rows
  and sides into its buffers every call (what the controller does each tick): verified answer
  and full result, no validation;
* a bare ``daqp.solve`` call, a reused ``daqp.Model`` (``update`` + ``solve``) and the direct C
  calls of :class:`~uvms_qp.hqp.daqp_native.NativeDaqp` (``refresh`` + ``solve_in_place``) on
  the same data: the floor of any Python wrapper.

The ratio column is the median wall time over the median DAQP C time of the lean
``solve_hierarchy`` runs (the issue's target is <= 2x). Cascades and the closed form follow.

Run: ``python benchmarks/bench_hqp.py [--repeat N] [--cascade-repeat M] [--sizes 10 13 30]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from uvms_qp.hqp import HierarchySolver, Rows, available_solvers, solve_hierarchy
from uvms_qp.hqp.daqp_native import NativeDaqp, native_available
from uvms_qp.hqp.inplace import InPlaceDaqp
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
    rows = [[Rows(A, b, b)] for A, b in pairs]  # trusted construction, as a controller does
    lo, hi = -np.full(n, BOXES[box]), np.full(n, BOXES[box])
    problem = normalize_problem(levels, lo, hi)
    lean_rows, lean_prob = HierarchySolver("daqp"), HierarchySolver("daqp")
    ref_api, ref_prob = HierarchySolver("daqp", lean=False), HierarchySolver("daqp", lean=False)

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

    inplace = InPlaceDaqp(n, 0, SIZES, np.ones(n), {"rho_soft": 1e-8, "primal_tol": 1e-10},
                          level_tol=1e-6, hard_tol=1e-9)
    in_rows, in_lo, in_hi = inplace.ws.A[n:], inplace.lo, inplace.hi

    def inplace_call():
        in_rows[...] = A  # the caller's per-call writes
        in_lo[:n], in_hi[:n] = lo, hi
        in_lo[n:] = b
        in_hi[n:] = b
        return inplace.solve()

    fns = {"native": None}
    if native_available():
        native = NativeDaqp()
        native.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), bp)
        settings = native.settings
        settings.update(rho_soft=1e-8, primal_tol=1e-10)
        native.settings = settings

        def native_call():
            native.refresh()
            return native.solve_in_place()

        fns["native"] = native_call

    c_times: list[float] = []

    def api():
        result = solve_hierarchy(levels, lo, hi, solver="daqp")
        c_times.append(result.info["daqp_solve_time"] + result.info["daqp_setup_time"])
        return result

    runs = interleaved({
        "api": api,
        "rows": lambda: lean_rows.solve(rows, lo, hi),
        "prob": lambda: lean_prob.solve_problem(problem),
        "ref_api": lambda: ref_api.solve(levels, lo, hi),
        "ref_prob": lambda: ref_prob.solve_problem(problem),
        "bare": lambda: daqp.solve(H, f, A, bu, bl, sense, break_points=bp, rho_soft=1e-8),
        "model": model_call,
        "inplace": inplace_call,
        **{k: v for k, v in fns.items() if v is not None},
    }, repeat)
    c_us = float(np.median(c_times) * 1e6)

    def ratio(key: str) -> str:
        return f"{runs[key][0] / c_us:.1f}x C"

    out = [
        ("daqp: DAQP-reported C time", c_us, str(runs["api"][1].status)),
        ("daqp: solve_hierarchy (tuples)", runs["api"][0], ratio("api")),
        ("daqp: HierarchySolver(Rows)", runs["rows"][0], ratio("rows")),
        ("daqp: solve_problem (trusted)", runs["prob"][0], ratio("prob")),
        ("daqp reference: solve (tuples)", runs["ref_api"][0], ratio("ref_api")),
        ("daqp reference: solve_problem", runs["ref_prob"][0], ratio("ref_prob")),
        ("bare daqp.solve (wall)", runs["bare"][0], ratio("bare")),
        ("daqp.Model update+solve (wall)", runs["model"][0], ratio("model")),
        ("in-place, fixed structure (verified)", runs["inplace"][0], ratio("inplace")),
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
            print(f"  {'solver':<34} {'median us':>10}  note")
            for name, t, note in bench(n, box, args.repeat, args.cascade_repeat):
                print(f"  {name:<34} {t:>10.1f}  {note}")


if __name__ == "__main__":
    main()
