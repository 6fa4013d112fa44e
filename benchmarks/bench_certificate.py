"""Cost of the run-time optimality certificate (:class:`uvms_qp.hqp.certificate.Certifier`).

Three measurements:

1. **Wall clock per call** on the demo stack's real control problems (BlueROV2 Heavy + Reach Alpha
   5, n = 10, four levels, box bounds; rows and box from today's controller at random states and
   targets, answers from ``daqp`` with the certificate off): median and p99 of one call (best of
   ``--repeat`` per problem), by the number of unmet levels, and a least-squares fit
   ``t = fixed + per_level * unmet``; the same on the ``well`` family of
   :mod:`uvms_qp.bench.problems` (n = 6..30).
2. **Instructions per call** (``--instructions``, valgrind): the calls of (1), grouped by the
   number of unmet levels, each group counted in a fresh process (``--passes`` passes minus
   none, the problems read from a file), and the same fit in instructions.
3. **The control step** (``--instructions``): instructions of one closed-loop tick of
   ``bench_controller.py``'s demo loop with the certificate on (the default) and off, and its
   wall-clock median both ways (interleaved).

    PYTHONPATH=$PWD python benchmarks/bench_certificate.py [--states 300] [--random 100]
        [--repeat 20] [--instructions] [--passes 20]
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from uvms_qp.bench.problems import family  # noqa: E402
from uvms_qp.bench.stacks import demo_stack  # noqa: E402
from uvms_qp.controller import Controller  # noqa: E402
from uvms_qp.hqp import HierarchySolver, Problem, normalize_problem  # noqa: E402
from uvms_qp.hqp.backends.daqp_binding import open_daqp  # noqa: E402
from uvms_qp.hqp.certificate import Certifier, slacks  # noqa: E402
from uvms_qp.model import load_model  # noqa: E402


def demo_cases(count: int, seed: int = 0) -> list:
    """``(problem, x, s, residuals, unmet)`` of the demo stack at ``count`` random states."""
    model = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        state = model.state(model.random_configuration(rng))
        target = state.position("tool") + rng.normal(scale=0.3, size=3)
        ctrl = Controller(model, demo_stack(position=list(target)), dt=0.05)
        ctrl.safe.primary.certify = None
        result = ctrl.step(state, 0.0)
        out.append(_case(ctrl.assembler.problem.copy(), result.zeta.copy()))
    return out


def family_cases(name: str, count: int) -> list:
    """The same for a plain-matrix family (answers from ``daqp``, certificate off)."""
    solver = HierarchySolver("daqp")
    solver.certify, solver.repair = None, False
    out = []
    for p in family(name, count):
        problem = normalize_problem(p.levels_rows(), p.lower, p.upper, None, p.hard_rows())
        result = solver.solve_problem(problem)
        if result.ok:
            out.append(_case(problem, result.x))
    return out


def _case(problem, x):
    s = slacks(problem, x)
    residuals = [float(v) for v in np.sqrt(problem.G[1:].dot(s * s))]
    cert = Certifier(open_daqp)(problem, x, s, residuals)
    unmet = sum(c.verdict != "met" for c in cert.levels)
    return problem, x, s, residuals, unmet, cert


def timed(cases, repeat: int):
    """Best-of-``repeat`` wall time of one call per case [us], each case written into one
    problem of its shape (the controller's situation: one problem, filled every tick)."""
    certifier = Certifier(open_daqp)
    shared: dict = {}
    times, unmet, verdicts = [], [], Counter()
    for problem, x, s, residuals, u, cert in cases:
        key = (problem.n, problem.mh, problem.sizes)
        if key not in shared:
            shared[key] = problem.copy()
        target = shared[key]
        np.copyto(target.A, problem.A)
        np.copyto(target.sides, problem.sides)
        target.set_weights(problem.w)
        certifier(target, x, s, residuals)
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            certifier(target, x, s, residuals)
            best = min(best, time.perf_counter() - t0)
        times.append(best * 1e6)
        unmet.append(u)
        verdicts.update(c.verdict for c in cert.levels)
    return np.array(times), np.array(unmet), verdicts


def fit(unmet, values):
    """``(fixed, per unmet level)`` of a least-squares line through the answers with u >= 1."""
    use = unmet > 0
    A = np.vstack((np.ones(int(use.sum())), unmet[use])).T
    return np.linalg.lstsq(A, values[use], rcond=None)[0]


def report(name, times, unmet, verdicts):
    fixed, per = fit(unmet, times)
    by = ", ".join(f"{u}: {np.median(times[unmet == u]):.1f} us ({(unmet == u).sum()})"
                   for u in sorted(set(unmet.tolist())))
    print(f"{name}: one call median {np.median(times):.1f} us, p99 {np.percentile(times, 99):.1f}"
          f" us; by unmet levels {by}; fit {fixed:.1f} us + {per:.1f} us per unmet level; "
          f"verdicts {dict(verdicts)}")


# ------------------------------------------------------------------------------ valgrind
def save_cases(cases, path: Path) -> None:
    """The problems and answers of ``cases`` as plain arrays (for the counted processes)."""
    data = {}
    for i, (problem, x, *_rest) in enumerate(cases):
        data[f"A{i}"], data[f"sides{i}"], data[f"w{i}"] = problem.A, problem.sides, problem.w
        data[f"W{i}"], data[f"x{i}"] = problem.W, x
        data[f"shape{i}"] = np.array([problem.n, problem.mh, *problem.sizes])
    np.savez(path, count=len(cases), **data)


def load_cases(path: Path) -> list:
    """Inverse of :func:`save_cases`: ``(problem, x)`` pairs."""
    data = np.load(path)
    out = []
    for i in range(int(data["count"])):
        n, mh, *sizes = (int(v) for v in data[f"shape{i}"])
        problem = Problem(n, mh, sizes, data[f"W{i}"], A=data[f"A{i}"].copy(),
                          sides=data[f"sides{i}"].copy(), w=data[f"w{i}"].copy())
        out.append((problem, data[f"x{i}"].copy()))
    return out


def run_calls(path: str, passes: int, certify: bool) -> None:
    """The process valgrind counts: ``passes`` rounds over the saved cases, each written into
    one problem's buffers (as a controller fills its problem every tick) and, with ``certify``,
    certified with the measurement's slacks and residuals (as the solver asks)."""
    cases = [_case(problem, x)[:4] for problem, x in load_cases(Path(path))]
    shared = cases[0][0].copy()
    certifier = Certifier(open_daqp)
    certifier(shared, cases[0][1])  # the workspace of the shared problem
    for _ in range(passes):
        for problem, x, s, residuals in cases:
            np.copyto(shared.A, problem.A)
            np.copyto(shared.sides, problem.sides)
            shared.set_weights(problem.w)
            if certify:
                certifier(shared, x, s, residuals)


def run_steps(certify: bool, warmup: int, ticks: int) -> None:
    """The process valgrind counts: the demo loop of ``bench_controller.py``."""
    import bench_controller as bc

    model = load_model("bluerov2_heavy_alpha5")
    q0 = model.home()
    traj = bc.Circle(model.frame_pose(q0, "tool")[:3, 3])
    tick, _, box, ctrl = bc.ours_stepper(model, q0, traj, "daqp")
    if not certify:
        ctrl.safe.primary.certify = None
    for k in range(warmup + ticks):
        tick(k)
    print(dict(box["statuses"]))


def count(args: list[str]) -> tuple[int, str]:
    """Instructions valgrind counts for this script run with ``args``, and its output."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        proc = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
             __file__, *args], capture_output=True, text=True, check=False,
            env={**os.environ, "PYTHONHASHSEED": "0"})
    match = re.search(r"Collected\s*:\s*(\d+)", proc.stderr)
    if proc.returncode != 0 or match is None:
        raise SystemExit(f"valgrind run failed:\n{proc.stderr[-2000:]}")
    return int(match.group(1)), proc.stdout.strip()


def instructions(cases: list, passes: int, ticks: int, warmup: int) -> None:
    per_call = {}
    with tempfile.TemporaryDirectory() as tmp:
        for u in sorted({c[4] for c in cases}):
            chosen = [c for c in cases if c[4] == u]
            if len(chosen) < 5:
                continue
            path = Path(tmp) / f"cases{u}.npz"
            save_cases(chosen, path)
            base, _ = count(["--run-calls", str(path), str(passes), "0"])
            total, _ = count(["--run-calls", str(path), str(passes), "1"])
            per_call[u] = (total - base) / (passes * len(chosen))
            print(f"certificate, {u} unmet level(s): {per_call[u] / 1e3:.1f} k instructions per"
                  f" call ({len(chosen)} problems x {passes})")
    us = np.array(sorted(per_call), dtype=float)
    if us.size >= 2:
        fixed, per = np.linalg.lstsq(np.vstack((np.ones(us.size), us)).T,
                                     np.array([per_call[u] for u in sorted(per_call)]),
                                     rcond=None)[0]
        print(f"certificate: {fixed / 1e3:.1f} k + {per / 1e3:.1f} k instructions per unmet "
              "level")
    steps = {}
    for label, flag in (("on", "1"), ("off", "0")):
        base, _ = count(["--run-steps", flag, str(warmup), "0"])
        total, statuses = count(["--run-steps", flag, str(warmup), str(ticks)])
        steps[label] = (total - base) / ticks
        print(f"demo loop, certificate {label}: {steps[label] / 1e3:.1f} k instructions per tick"
              f" (statuses {statuses})")
    print(f"certificate on / off: {steps['on'] / steps['off']:.3f}")


def step_wall(ticks: int) -> None:
    """Wall-clock median of the demo loop's tick with the certificate on and off (interleaved)."""
    import bench_controller as bc

    model = load_model("bluerov2_heavy_alpha5")
    q0 = model.home()
    traj = bc.Circle(model.frame_pose(q0, "tool")[:3, 3])
    on = bc.ours_stepper(model, q0, traj, "daqp")
    off = bc.ours_stepper(model, q0, traj, "daqp")
    off[3].safe.primary.certify = None
    times = {"on": [], "off": []}
    for k in range(ticks):
        times["on"].append(on[0](k))
        times["off"].append(off[0](k))
    med = {k: 1e6 * float(np.median(v)) for k, v in times.items()}
    p99 = {k: 1e6 * float(np.percentile(v, 99)) for k, v in times.items()}
    print(f"demo loop wall clock per tick: certificate on {med['on']:.1f} us (p99 "
          f"{p99['on']:.1f}), off {med['off']:.1f} us (p99 {p99['off']:.1f}); "
          f"on / off {med['on'] / med['off']:.3f}; statuses on {on[2]['statuses']}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=300)
    ap.add_argument("--random", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--ticks", type=int, default=2000)
    ap.add_argument("--warmup", type=int, default=50)
    ap.add_argument("--passes", type=int, default=20)
    ap.add_argument("--instructions", action="store_true")
    ap.add_argument("--run-calls", nargs=3, help=argparse.SUPPRESS)
    ap.add_argument("--run-steps", nargs=3, type=int, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.run_calls:
        run_calls(a.run_calls[0], int(a.run_calls[1]), bool(int(a.run_calls[2])))
        return
    if a.run_steps:
        run_steps(bool(a.run_steps[0]), a.run_steps[1], a.run_steps[2])
        return
    demo = demo_cases(a.states)
    report("demo stack", *timed(demo, a.repeat))
    report("random (well)", *timed(family_cases("well", a.random), max(1, a.repeat // 4)))
    step_wall(a.ticks)
    if a.instructions:
        if shutil.which("valgrind") is None:
            raise SystemExit("valgrind not found (Debian: apt-get install valgrind)")
        instructions(demo, a.passes, a.ticks, a.warmup)


if __name__ == "__main__":
    main()
