"""Certified-wrong ok answers per family and solver (run as a script; not collected by pytest).

    PYTHONPATH=$PWD python -m tests.support.oracle.before_table [--count 60] [--families ...]

For every problem of every family (:mod:`uvms_qp.bench.problems`) and every installed solver,
an answer with an ok status (``optimal`` or ``level_infeasible``) is judged by the oracle; it is
*certified-wrong* when a verified point of some level's frozen set improves that level by more
than 1e-6 (relative to the level's scale). The certificate's verdict on the same answer is
tallied beside it. Prints one line per (family, solver): wrong / ok / problems, the worst
improvement, the slowest solve, and how often the certificate agreed with the oracle.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from uvms_qp.bench.problems import CONTROLLER_FAMILIES, MATRIX_FAMILIES, family
from uvms_qp.hqp import HierarchySolver, available_solvers
from uvms_qp.hqp.certificate import certify

from .lexicographic import Oracle, first_wrong

OK = ("optimal", "level_infeasible")


def run_one(args):
    fam, seed = args
    p = family(fam, 1, seed)[0]
    arr = p.stacked()
    orc = Oracle(*arr)
    eq_only = all(np.all(b[1] == b[2]) for b in p.levels)
    rows = []
    for solver in available_solvers():
        if solver == "nullspace" and not eq_only:
            continue
        t0 = time.perf_counter()
        try:
            res = HierarchySolver(solver).solve(p.levels_rows(), p.lower, p.upper, p.hard_rows())
            status, x = res.status.value, res.x
        except Exception as exc:
            status, x = f"raised {type(exc).__name__}", None
        dt = time.perf_counter() - t0
        wrong = worst = None
        verdict = None
        if status in OK:
            cert = certify(*arr, x)
            verdict = cert.ok
            better = [c.better for c in cert.levels if c.better is not None]
            judged = orc.judge(x, candidates=better)
            k = first_wrong(judged)
            wrong = k is not None
            worst = max(j.improvement / j.scale for j in judged)
        rows.append((fam, p.name, solver, status, wrong, worst, verdict, dt,
                     float(np.abs(x).max()) if x is not None else np.nan))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--families", nargs="*", default=list(MATRIX_FAMILIES + CONTROLLER_FAMILIES))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    jobs = [(f, s) for f in a.families for s in range(a.count)]
    with ProcessPoolExecutor(a.jobs) as ex:
        results = [r for rs in ex.map(run_one, jobs, chunksize=4) for r in rs]
    if a.out:
        import json
        with open(a.out, "w") as fh:
            json.dump(results, fh)
    table = {}
    for fam, _, solver, status, wrong, worst, verdict, dt, xmax in results:
        t = table.setdefault((fam, solver), {"n": 0, "ok": 0, "wrong": 0, "worst": 0.0,
                                             "slow": 0.0, "agree": 0, "xmax": 0.0,
                                             "cert_ok_wrong": 0, "cert_no_right": 0})
        t["n"] += 1
        t["slow"] = max(t["slow"], dt)
        if status in OK:
            t["ok"] += 1
            t["wrong"] += bool(wrong)
            t["worst"] = max(t["worst"], worst or 0.0)
            t["agree"] += verdict == (not wrong)
            t["cert_ok_wrong"] += bool(verdict and wrong)
            t["cert_no_right"] += bool((not verdict) and (not wrong))
            t["xmax"] = max(t["xmax"], xmax)
    print(f"{'family':16s} {'solver':18s} {'wrong/ok/n':>12s} {'worst':>9s} {'slowest[s]':>10s}"
          f" {'cert=oracle':>11s} {'cert ok,wrong':>13s} {'cert no,right':>13s} {'max|x|':>9s}")
    for (fam, solver), t in table.items():
        print(f"{fam:16s} {solver:18s} {t['wrong']:>3d}/{t['ok']:>3d}/{t['n']:>3d}  "
              f"{t['worst']:9.2e} {t['slow']:10.3f} {t['agree']:>5d}/{t['ok']:<5d} "
              f"{t['cert_ok_wrong']:>13d} {t['cert_no_right']:>13d} {t['xmax']:9.2e}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
