"""Degenerate problems fed to the solve path's compiled code, each case in a child process.

A controller must never take its host process down: a native library that aborts (a double
free, a failed assertion) is no exception Python can catch. This module draws degenerate
lexicographic problems and runs, on each, the parts of the solve path that call compiled code
directly: the optimality certificate (DAQP's least-distance solver and the non-negative least
squares), the repair (the exact active-set solver's least squares), the damping screen (LAPACK's
Cholesky factorisation and SVD) and one solve by a back-end. Cases run in a worker process; a
worker that dies is recorded with the case that killed it and a new worker carries on, so
``10^5`` cases cost about one interpreter start per abort, not per case.

The draws (:func:`draw`): ``n`` from 1 to 60, one to four levels of zero, tiny (norm 1e-16 to
1e-8), repeated (a row of the same or a higher level, possibly scaled) and scaled rows (norms
from 1e-8 to 1e8), empty levels, equality, two-sided, one-sided and free sides, a box that is
absent, partial, wide, tight or pinned (equal bounds), sometimes hard rows; the point ``x`` is a
back-end's answer or a random point.

Run it from the command line (``python -m uvms_qp.testing.fuzz --cases 100000``) or through
:func:`run` (the test suite runs a few hundred cases).
"""

from __future__ import annotations

import argparse
import json
import os
import select
import subprocess
import sys
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..hqp import HierarchySolver, Problem, available_solvers
from ..hqp.backends.daqp_binding import open_daqp
from ..hqp.certificate import Certifier, repair
from ..hqp.damping import level_damping

#: What a case runs, in order.
PARTS = ("solve", "certify", "repair", "damping")
#: Seconds each part of a case may take (its deadline) [s].
BUDGET = 2.0


@dataclass
class Case:
    """One drawn problem in the stacked layout, and a point to judge."""

    seed: int
    n: int
    mh: int
    sizes: tuple[int, ...]
    A: FloatArray
    lo: FloatArray
    hi: FloatArray
    w: FloatArray
    x: FloatArray
    solver: str


def _row(rng: np.random.Generator, n: int, earlier: list[FloatArray]) -> FloatArray:
    kind = rng.choice(("plain", "zero", "tiny", "repeat", "scaled", "sparse"),
                      p=(0.35, 0.12, 0.12, 0.16, 0.15, 0.10))
    if kind == "zero":
        return np.zeros(n)
    if kind == "repeat" and earlier:
        base = earlier[int(rng.integers(len(earlier)))]
        return base * (1.0 if rng.random() < 0.5 else 10.0 ** rng.uniform(-8, 8))
    a = rng.standard_normal(n)
    if kind == "sparse":
        a *= rng.random(n) < 2.0 / n
    a /= max(float(np.linalg.norm(a)), 1e-300)
    if kind == "tiny":
        return a * 10.0 ** rng.uniform(-16, -8)
    if kind == "scaled":
        return a * 10.0 ** rng.uniform(-8, 8)
    return a


def _sides(rng: np.random.Generator, a: FloatArray) -> tuple[float, float]:
    scale = max(1.0, float(np.linalg.norm(a))) * 10.0 ** rng.uniform(-3, 3)
    t = float(rng.standard_normal()) * scale
    kind = rng.choice(("eq", "two", "lower", "upper", "free", "eq0"), p=(0.4, 0.2, 0.15, 0.1,
                                                                          0.05, 0.1))
    if kind == "eq":
        return t, t
    if kind == "eq0":
        return 0.0, 0.0
    if kind == "two":
        width = abs(float(rng.standard_normal())) * scale * rng.choice((0.0, 1e-12, 1.0))
        return t, t + width
    if kind == "lower":
        return t, np.inf
    if kind == "upper":
        return -np.inf, t
    return -np.inf, np.inf


def draw(seed: int, solvers: tuple[str, ...] | None = None) -> Case:
    """The degenerate problem of ``seed`` (see the module docstring).

    ``solvers``: the back-ends a case may name (default: every installed one, DAQP on half the
    cases).
    """
    if solvers is None:
        others = tuple(s for s in available_solvers() if s != "daqp")
        solvers = ("daqp",) * len(others) + others
    rng = np.random.default_rng(seed)
    n = int(rng.choice((1, 2, 3, int(rng.integers(1, 13)), int(rng.integers(1, 61)))))
    box = rng.choice(("none", "partial", "wide", "tight", "pinned"))
    lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    if box != "none":
        half = 10.0 ** rng.uniform(-2, 1) if box != "tight" else 10.0 ** rng.uniform(-8, -2)
        centre = rng.uniform(-0.5, 0.5, n) * half
        lower, upper = centre - half, centre + half
        if box == "partial":
            off = rng.random(n) < 0.5
            lower[off], upper[off] = -np.inf, np.inf
        if box == "pinned":
            pin = rng.random(n) < 0.5
            upper[pin] = lower[pin]
    earlier: list[FloatArray] = []
    mh = int(rng.choice((0, 0, 0, 1, 2)))
    hard = [(_row(rng, n, earlier)) for _ in range(mh)]
    hard_sides = []
    for a in hard:
        lo, hi = _sides(rng, a)
        if box != "none" and np.isfinite(lower).all():  # keep a point of the box feasible
            c = float(a.dot(0.5 * (lower + upper)))
            lo, hi = (c, c) if lo == hi else (min(lo, c), max(hi, c))
        hard_sides.append((lo, hi))
    sizes, rows, sides = [], [], []
    for _ in range(int(rng.integers(1, 5))):
        m = int(rng.choice((0, 1, 1, 2, 3, int(rng.integers(1, 9)))))
        sizes.append(m)
        for _ in range(m):
            a = _row(rng, n, earlier)
            earlier.append(a)
            rows.append(a)
            sides.append(_sides(rng, a))
    A = np.vstack([np.eye(n), *[h[None] for h in hard], *[r[None] for r in rows]])
    lows = np.concatenate([lower, [v[0] for v in hard_sides], [v[0] for v in sides]])
    highs = np.concatenate([upper, [v[1] for v in hard_sides], [v[1] for v in sides]])
    w = 10.0 ** rng.uniform(-3, 3, len(rows)) if rng.random() < 0.3 else np.ones(len(rows))
    x = np.clip(rng.standard_normal(n) * 10.0 ** rng.uniform(-3, 3), lower, upper)
    return Case(seed, n, mh, tuple(sizes), A, lows, highs, w, x,
                str(solvers[int(rng.integers(len(solvers)))]))


def _problem(case: Case) -> Problem:
    problem = Problem(case.n, case.mh, case.sizes)
    problem.A[...] = case.A
    problem.lo[...] = case.lo
    problem.hi[...] = case.hi
    problem.set_weights(case.w)
    return problem


def run_case(case: Case, solvers: dict[str, Any], budget: float = BUDGET
             ) -> tuple[dict[str, str], dict[str, tuple[float, float]]]:
    """Every part of :data:`PARTS` on one case, each with ``budget`` seconds.

    Returns:
        The outcome of each part (``ok``, a status, or what it raised: a typed error is an
        answer; anything else is a finding, but not a crash) and its times ``(wall, CPU)``
        [s] (:func:`time.perf_counter`, :func:`time.thread_time`: a part whose wall time
        far exceeds its CPU time waited for a core).
    """
    problem = _problem(case)
    out: dict[str, str] = {}
    times: dict[str, tuple[float, float]] = {}
    x = case.x
    clock, cpu = time.perf_counter, time.thread_time
    began, used = clock(), cpu()
    try:
        solver = solvers.get(case.solver)
        if solver is None:
            solver = solvers[case.solver] = HierarchySolver(case.solver)
        result = solver.solve_problem(problem, began + budget)
        x = result.x if result.hard_violation == 0.0 else x
        out["solve"] = str(result.status.value)
    except Exception as exc:
        out["solve"] = "raised " + type(exc).__name__
    times["solve"] = (clock() - began, cpu() - used)
    certifier = Certifier(open_daqp)
    began, used = clock(), cpu()
    certifier.end = began + budget
    try:
        cert = certifier(problem, x)
        out["certify"] = "ok"
    except Exception as exc:
        cert = None
        out["certify"] = "raised " + type(exc).__name__
    times["certify"] = (clock() - began, cpu() - used)
    began, used = clock(), cpu()
    try:
        repair(problem, x, cert, certifier=certifier, deadline=began + budget)
        out["repair"] = "ok"
    except Exception as exc:
        out["repair"] = "raised " + type(exc).__name__
    times["repair"] = (clock() - began, cpu() - used)
    began, used = clock(), cpu()
    try:
        level_damping(problem, x, (0.05,) * len(case.sizes), 0.05, end=began + budget)
        out["damping"] = "ok"
    except Exception as exc:
        out["damping"] = "raised " + type(exc).__name__
    times["damping"] = (clock() - began, cpu() - used)
    return out, times


def worker(first: int, last: int) -> None:
    """Run cases ``first .. last - 1``; one line on stdout before and after each (JSON)."""
    import warnings

    warnings.simplefilter("ignore")
    solvers: dict[str, Any] = {}
    for seed in range(first, last):
        sys.stdout.write(f"start {seed}\n")
        sys.stdout.flush()
        out, times = run_case(draw(seed), solvers)
        sys.stdout.write("done " + json.dumps([seed, out, times]) + "\n")
        sys.stdout.flush()


@dataclass
class Report:
    """What :func:`run` saw."""

    cases: int = 0
    aborts: list[tuple[int, int]] = field(default_factory=list)  # (seed, exit status)
    hangs: list[int] = field(default_factory=list)
    outcomes: Counter[str] = field(default_factory=Counter)
    raised: list[tuple[int, str, str]] = field(default_factory=list)  # (seed, part, what)
    seconds: float = 0.0
    #: the slowest parts seen: (wall [s], CPU [s], seed, part), slowest first
    slowest: list[tuple[float, float, int, str]] = field(default_factory=list)
    #: parts that ran past their budget by more than ``late_by`` of wall time:
    #: (seed, part, wall [s], CPU [s])
    late: list[tuple[int, str, float, float]] = field(default_factory=list)


def run(first: int, count: int, timeout: float = 30.0, progress: bool = False,
        late_by: float = 0.5) -> Report:
    """Run ``count`` cases from seed ``first``, each worker in a child process (see above).

    Args:
        first: First seed.
        count: Number of cases.
        timeout: Seconds a case may run before its worker is killed (a hang).
        progress: Print a line every 1000 cases.
        late_by: Wall time past its budget (:data:`BUDGET`) after which a part is reported
            ``late`` [s].
    """
    report = Report()
    start = time.perf_counter()
    seed, last = first, first + count
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    while seed < last:
        proc = subprocess.Popen(
            [sys.executable, "-c",
             f"from uvms_qp.testing.fuzz import worker; worker({seed}, {last})"],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env)
        assert proc.stdout is not None
        current: int | None = None
        while True:
            ready, _, _ = select.select([proc.stdout], [], [], timeout)
            if not ready:  # a case that never ends
                proc.kill()
                proc.wait()
                if current is not None:
                    report.hangs.append(current)
                    seed = current + 1
                break
            line = proc.stdout.readline()
            if not line:
                code = proc.wait()
                if current is not None:  # died inside a case
                    report.aborts.append((current, code))
                    seed = current + 1
                else:
                    seed = last if code == 0 else seed + 1
                break
            word, _, rest = line.partition(" ")
            if word == "start":
                current = int(rest)
            elif word == "done":
                done, out, times = json.loads(rest)
                for part, (wall, used) in times.items():
                    report.slowest.append((wall, used, done, part))
                    if wall > BUDGET + late_by:
                        report.late.append((done, part, wall, used))
                if len(report.slowest) > 100:
                    report.slowest = sorted(report.slowest, reverse=True)[:10]
                current = None
                seed = done + 1
                report.cases += 1
                for part, what in out.items():
                    report.outcomes[f"{part}: {what}"] += 1
                    if what.startswith("raised") and what != "raised InputError":
                        report.raised.append((done, part, what))
                if progress and report.cases % 1000 == 0:
                    print(f"{report.cases} cases, {len(report.aborts)} aborts, "
                          f"{len(report.hangs)} hangs, {time.perf_counter() - start:.0f} s",
                          flush=True)
        proc.stdout.close()
    report.seconds = time.perf_counter() - start
    report.slowest = sorted(report.slowest, reverse=True)[:10]
    return report


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m uvms_qp.testing.fuzz --cases N [--first S]``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=1000)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=30.0)
    args = parser.parse_args(argv)
    report = run(args.first, args.cases, args.timeout, progress=True)
    print(f"{report.cases} cases in {report.seconds:.0f} s: {len(report.aborts)} aborts "
          f"{report.aborts[:20]}, {len(report.hangs)} hangs {report.hangs[:20]}, "
          f"{len(report.late)} parts past their {BUDGET:g} s budget {report.late[:20]}")
    for wall, used, seed, part in report.slowest:
        print(f"  slowest: seed {seed} {part} {wall:.3f} s wall, {used:.3f} s CPU")
    for key, value in sorted(report.outcomes.items()):
        print(f"  {key}: {value}")
    for seed, part, what in report.raised[:30]:
        print(f"  seed {seed}: {part} {what}")
    return 1 if report.aborts or report.hangs else 0


if __name__ == "__main__":
    raise SystemExit(main())
