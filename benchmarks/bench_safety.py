"""Cost of the reliability layer on the happy path (verification, saturation, stage bookkeeping).

Solves the same problems (the demo stack at states of a short closed loop) with the bare
:class:`uvms_qp.hqp.HierarchySolver` and with :class:`uvms_qp.safety.SafeSolver` (same back-end)
interleaved, and prints the medians and the overhead per step.

Run: ``python benchmarks/bench_safety.py``.
"""

from __future__ import annotations

import time

import numpy as np

from uvms_qp.controller import Controller
from uvms_qp.hqp import HierarchySolver
from uvms_qp.safety import SafeSolver
from uvms_qp.safety.verify import verify_result
from uvms_qp.sim.scenario import load_scenario


def main(rounds: int = 3000) -> None:
    sc = load_scenario("bluerov2_demo")
    ctrl = Controller(sc.model, sc.build_stack(), dt=sc.dt, metric=sc.metric)
    q = np.array(sc.q0)
    problems = []
    for k in range(50):
        res = ctrl.step(sc.model.state(q), k * sc.dt)
        problems.append(ctrl._new_problem())  # views: copy the arrays of this tick
        problems[-1] = _copy(problems[-1])
        q = sc.model.integrate(q, res.zeta, sc.dt)
    bare = HierarchySolver("daqp", sc.metric)
    safe = SafeSolver("daqp", sc.metric)
    t_bare, t_safe, t_check = [], [], []
    for i in range(rounds):
        p = problems[i % len(problems)]
        t0 = time.perf_counter()
        r = bare.solve_problem(p)
        t1 = time.perf_counter()
        safe.solve(p, t1)
        t2 = time.perf_counter()
        verify_result(p, r, 1e-9 * p.hard_scale)
        t3 = time.perf_counter()
        t_bare.append(t1 - t0)
        t_safe.append(t2 - t1)
        t_check.append(t3 - t2)
    mb, ms, mc = (float(np.median(t)) * 1e6 for t in (t_bare, t_safe, t_check))
    print(f"demo stack, daqp, {rounds} solves (medians):")
    print(f"  HierarchySolver.solve_problem   {mb:8.1f} us")
    print(f"  SafeSolver.solve                {ms:8.1f} us  (overhead {ms - mb:+.1f} us)")
    print(f"  verify_result (incl. saturate)  {mc:8.1f} us")
    print(f"  stages: {dict(safe.stage_counts)}")


def _copy(problem):
    from dataclasses import replace

    from uvms_qp.hqp.problem import Block

    def cb(b):
        return Block(b.A.copy(), b.lo.copy(), b.hi.copy(), b.w.copy(), b.eq.copy(), b.names)

    return replace(problem, levels=tuple(cb(b) for b in problem.levels), hard=cb(problem.hard),
                   lower=problem.lower.copy(), upper=problem.upper.copy())


if __name__ == "__main__":
    main()
