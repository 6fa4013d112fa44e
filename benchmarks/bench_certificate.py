"""Cost of the per-level optimality certificate (:func:`uvms_qp.hqp.certificate.certify`).

Two sets: the demo stack's real control problems (BlueROV2 Heavy + Reach Alpha 5, n = 10, four
levels, box bounds; rows and box from today's controller at random states, answers from the
default ``daqp``), and the ``well`` family of :mod:`uvms_qp.bench.problems` (n = 6..30).
Prints the median and p99 of one ``certify`` call, of the daqp solve it follows, the number of
unmet levels, and the verdicts.

    PYTHONPATH=$PWD python benchmarks/bench_certificate.py [--states 500] [--random 200]
"""

from __future__ import annotations

import argparse
import time
from collections import Counter

import numpy as np

from uvms_qp.bench.problems import family
from uvms_qp.bench.stacks import demo_stack
from uvms_qp.controller import Controller
from uvms_qp.hqp import HierarchySolver
from uvms_qp.hqp.certificate import certify
from uvms_qp.model import load_model
from uvms_qp.rows import Rows


def demo_problems(count, seed=0):
    model = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        q = model.random_configuration(rng)
        state = model.state(q)
        target = state.position("tool") + rng.normal(scale=0.3, size=3)
        ctrl = Controller(model, demo_stack(position=list(target)), dt=0.05)
        rows = ctrl.level_rows(state, 0.0)
        lower, upper = ctrl.bounds(state)
        n = model.nv
        A = np.vstack([np.eye(n), *[r.A for r in rows]])
        lo = np.concatenate([lower, *[r.lower for r in rows]])
        hi = np.concatenate([upper, *[r.upper for r in rows]])
        w = np.concatenate([r.weights if r.weights is not None else np.ones(r.m) for r in rows])
        levels = [[Rows(r.A, r.lower, r.upper, r.weights)] for r in rows]
        out.append(((A, lo, hi, n, 0, tuple(r.m for r in rows), w), (levels, lower, upper)))
    return out


def timed(problems, repeat=20):
    solver = HierarchySolver("daqp")
    t_cert, t_solve, unmet, verdicts = [], [], Counter(), Counter()
    for arr, (levels, lower, upper) in problems:
        t0 = time.perf_counter()
        res = solver.solve(levels, lower, upper)
        t_solve.append(time.perf_counter() - t0)
        x = res.x
        cert = certify(*arr, x)
        unmet[sum(c.verdict != "met" for c in cert.levels)] += 1
        for c in cert.levels:
            verdicts[c.verdict] += 1
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            certify(*arr, x)
            best = min(best, time.perf_counter() - t0)
        t_cert.append(best)
    return np.array(t_cert) * 1e6, np.array(t_solve) * 1e6, unmet, verdicts


def report(name, t_cert, t_solve, unmet, verdicts):
    print(f"{name}: certify median {np.median(t_cert):.1f} us, p99 {np.percentile(t_cert, 99):.1f}"
          f" us; daqp solve median {np.median(t_solve):.1f} us; unmet levels {dict(unmet)};"
          f" verdicts {dict(verdicts)}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--states", type=int, default=500)
    ap.add_argument("--random", type=int, default=200)
    a = ap.parse_args()
    report("demo stack", *timed(demo_problems(a.states)))
    rand = []
    for p in family("well", a.random):
        levels, lower, upper = p.levels_rows(), p.lower, p.upper
        rand.append((p.stacked(), (levels, lower, upper)))
    report("random (well)", *timed(rand, repeat=5))


if __name__ == "__main__":
    main()
