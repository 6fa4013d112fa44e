"""Certified-wrong ok answers per family and solver (run as a script; not collected by pytest).

    PYTHONPATH=$PWD python -m tests.support.oracle.before_table [--count 60] [--families ...]
        [--solvers ...] [--uncertified] [--time-cap SECONDS] [--jobs 2] [--out FILE]

For every problem of every family (:mod:`uvms_qp.bench.problems`) and every installed solver
(as a user gets it: :class:`~uvms_qp.hqp.HierarchySolver` with its defaults, i.e. the
optimality certificate asked and the repair on; ``--uncertified`` switches both off, which is how
the library answered before the certificate was on by default; ``--time-cap`` gives every solve
a deadline [s]), an answer with an ok status
(``optimal``; ``level_infeasible`` in older versions) is judged by the oracle; it is
*certified-wrong* when a
verified point of some level's frozen set improves that level by more than 1e-6 (relative to the
level's scale). Prints one line per (family, solver): wrong / unproven / ok / problems, the other
statuses, the worst improvement, the slowest solve and the largest ``|x|`` of an ok answer.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from uvms_qp.bench.problems import CONTROLLER_FAMILIES, MATRIX_FAMILIES, family
from uvms_qp.hqp import HierarchySolver, available_solvers, normalize_problem

from .lexicographic import TOL, Oracle, first_wrong

OK = ("optimal", "level_infeasible")


def run_one(args):
    fam, seed, solvers, uncertified, time_cap = args
    p = family(fam, 1, seed)[0]
    orc = Oracle(*p.stacked())
    eq_only = all(np.all(b[1] == b[2]) for b in p.levels)
    rows = []
    for solver in solvers:
        if solver == "nullspace" and not eq_only:
            continue
        hs = HierarchySolver(solver, deadline=time_cap)
        if uncertified:
            hs.certify, hs.repair = None, False
        t0 = time.perf_counter()
        try:
            problem = normalize_problem(p.levels_rows(), p.lower, p.upper, None, p.hard_rows())
            res = hs.solve_problem(problem)
            status, x = res.status.value, res.x
        except Exception as exc:
            status, x = f"raised {type(exc).__name__}", None
        dt = time.perf_counter() - t0
        wrong = worst = None
        if status in OK:
            judged = orc.judge(x, met=TOL)
            wrong = first_wrong(judged) is not None
            worst = max(j.improvement / j.scale for j in judged)
        rows.append((fam, p.name, solver, status, wrong, worst, dt,
                     float(np.abs(x).max()) if x is not None else float("nan")))
    return rows


def table(results):
    out = {}
    for fam, _, solver, status, wrong, worst, dt, xmax in results:
        t = out.setdefault((fam, solver), {"n": 0, "ok": 0, "wrong": 0, "unproven": 0,
                                           "other": {}, "worst": 0.0, "slow": 0.0, "xmax": 0.0})
        t["n"] += 1
        t["slow"] = max(t["slow"], dt)
        if status in OK:
            t["ok"] += 1
            t["wrong"] += bool(wrong)
            t["worst"] = max(t["worst"], worst or 0.0)
            t["xmax"] = max(t["xmax"], xmax)
        elif status == "unproven":
            t["unproven"] += 1
        else:
            t["other"][status] = t["other"].get(status, 0) + 1
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--families", nargs="*", default=list(MATRIX_FAMILIES + CONTROLLER_FAMILIES))
    ap.add_argument("--solvers", nargs="*", default=list(available_solvers()))
    ap.add_argument("--uncertified", action="store_true")
    ap.add_argument("--time-cap", type=float, default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    jobs = [(f, s, tuple(a.solvers), a.uncertified, a.time_cap)
            for f in a.families for s in range(a.count)]
    with ProcessPoolExecutor(a.jobs) as ex:
        results = [r for rs in ex.map(run_one, jobs, chunksize=4) for r in rs]
    if a.out:
        with open(a.out, "w") as fh:
            json.dump(results, fh)
    print(f"{'family':16s} {'solver':18s} {'wrong/unproven/ok/n':>20s} {'other':24s} "
          f"{'worst':>9s} {'slowest[s]':>10s} {'max|x|':>9s}")
    for (fam, solver), t in table(results).items():
        other = ",".join(f"{k}:{v}" for k, v in sorted(t["other"].items())) or "-"
        print(f"{fam:16s} {solver:18s} {t['wrong']:>4d}/{t['unproven']:>4d}/{t['ok']:>4d}/"
              f"{t['n']:>4d}  {other:24s} {t['worst']:9.2e} {t['slow']:10.3f} {t['xmax']:9.2e}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
