"""Instructions per control step of uvms-qp and Pink, counted by valgrind (repeatable).

Wall-clock medians on a shared virtual machine move by tens of percent between runs; the number
of instructions a step executes hardly does. This script runs each loop of
``bench_controller.py`` (our 4-level stack, our stack with Pink's content, Pink) in a fresh
Python process under ``valgrind --tool=callgrind`` twice, with ``W`` warm-up ticks and then with
``W + N`` ticks, and reports ``(I(W + N) - I(W)) / N``: the instructions of one closed-loop tick,
start-up and warm-up subtracted. Start-up itself varies by about 0.5 % between processes (some
ten million instructions), hence the default of 2000 counted ticks; two runs of the same code
then agree within about 1 %. Instructions are not seconds (work in C retires more instructions
per cycle than the interpreter), so read the ratio next to the wall-clock ratio of
``bench_controller.py``, not instead of it. The loops follow their motion for ``W + N`` ticks,
so a different ``N`` measures a different stretch of it. Our controllers run without a deadline
here: under valgrind a step is some 50 times slower, and a wall-clock deadline (the period,
50 ms, by default) would skip stages on a loaded machine, so the count would follow the load.

Needs valgrind (Debian: ``apt-get install valgrind``) and Pink (``pip install -e ".[pink]"``).
Each loop takes about a minute under valgrind.

    python benchmarks/bench_instructions.py [--ticks 2000] [--warmup 50] [--parts] [--solves]

``--parts`` first splits our tick (at the states of the closed loop's first ``W`` ticks, then held):
``model.state``, the assembler's rows, box, weights and checks, the fallback ladder (DAQP,
measurement, the hierarchy result) and the step result, cumulatively. ``bare`` is our loop with
the optimality certificate and the damping screen switched off. ``--solves`` also counts one
``solve_hierarchy`` call against ``daqp.Model.update`` + ``solve`` on ``bench_hqp.py``'s problem
at n = 10 (per solve).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
LOOPS = {
    "ours": "uvms-qp, 4-level stack + all bounds",
    "bare": "uvms-qp, the same without certificate and damping",
    "small": "uvms-qp, Pink's content (tool + posture, 1 level)",
    "pink": "Pink, FrameTask + PostureTask + limits",
}
#: one solve of ``bench_hqp.py``'s problem (n = 10, levels [6, 3, 1, 4], wide box), per "tick"
SOLVES = {
    "api10": "solve_hierarchy, n = 10 (validation, DAQP, measurement, certificate)",
    "model10": "daqp.Model update + solve, the same data",
}
#: cumulative parts of our tick, for ``--parts`` (each loop runs the previous one and more)
PARTS = {
    "state": "model.state(q)",
    "fill": "+ rows, box, weights, checks (assembler.fill)",
    "solve": "+ fallback ladder: DAQP, measurement, result (safe.solve)",
    "step": "+ StepResult (the whole step: controller.step)",
}


def run_loop(which: str, warmup: int, ticks: int) -> None:
    """Run ``warmup + ticks`` closed-loop ticks of one loop (the process valgrind counts)."""
    sys.path.insert(0, str(HERE))
    import bench_controller as bc

    from uvms_qp.model import load_model

    model = load_model("bluerov2_heavy_alpha5")
    q0 = model.home()
    traj = bc.Circle(model.frame_pose(q0, "tool")[:3, 3])
    if which in PARTS:
        # the first ticks of the full loop give realistic states; then one part per tick
        tick, _, box, ctrl = bc.ours_stepper(model, q0, traj, "daqp", deadline=None)
        for k in range(warmup):
            tick(k)
        q, assembler, safe = box["q"], ctrl.assembler, ctrl.safe
        for k in range(ticks):
            state = model.state(q)
            t = (warmup + k) * bc.DT
            if which == "step":
                ctrl.step(state, t)
            elif which != "state":
                assembler.fill(state, t)
                if which == "solve":
                    safe.solve(assembler.problem)
        return
    if which == "pink":
        tick = bc.pink_stepper(model, q0, traj, "daqp")[0]
    elif which == "bare":
        tick, _, _, ctrl = bc.ours_stepper(model, q0, traj, "daqp", deadline=None)
        ctrl.safe.primary.certify = None  # no optimality certificate
        ctrl.assembler.damping = None  # no damping screen
    else:
        stack = bc.small_stack(traj) if which == "small" else None
        tick = bc.ours_stepper(model, q0, traj, "daqp", stack, deadline=None)[0]
    for k in range(warmup + ticks):
        tick(k)


def run_solves(which: str, warmup: int, ticks: int) -> None:
    """``warmup + ticks`` solves of ``bench_hqp.py``'s problem at n = 10 (the counted process)."""
    sys.path.insert(0, str(HERE))
    import bench_hqp as bh
    import daqp
    import numpy as np

    from uvms_qp.hqp import solve_hierarchy

    n = 10
    pairs = bh.make(n)
    lo, hi = -np.full(n, bh.BOXES["wide"]), np.full(n, bh.BOXES["wide"])
    if which == "api10":
        levels = [[pair] for pair in pairs]
        for _ in range(warmup + ticks):
            solve_hierarchy(levels, lo, hi, solver="daqp")
        return
    A = np.vstack([A for A, _ in pairs])
    b = np.concatenate([b for _, b in pairs])
    bu, bl = np.concatenate((hi, b)), np.concatenate((lo, b))
    model = daqp.Model()
    model.setup(np.eye(n), np.zeros(n), A, bu, bl, np.zeros(bu.size, dtype=np.intc),
                break_points=np.cumsum([n, *bh.SIZES]).astype(np.intc))
    settings = model.settings
    settings.update(rho_soft=1e-8, primal_tol=1e-10)
    model.settings = settings
    for _ in range(warmup + ticks):
        model.update(A=A, bupper=bu, blower=bl)
        model.solve()


def count(which: str, warmup: int, ticks: int) -> int:
    """Instructions valgrind counts for one process running ``warmup + ticks`` ticks."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        proc = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable,
             __file__, "--run", which, "--warmup", str(warmup), "--ticks", str(ticks)],
            capture_output=True, text=True, check=False,
            env={**os.environ, "PYTHONHASHSEED": "0"})  # the same dict layouts every run
    match = re.search(r"Collected\s*:\s*(\d+)", proc.stderr)
    if proc.returncode != 0 or match is None:
        raise SystemExit(f"valgrind run of {which!r} failed:\n{proc.stderr[-2000:]}")
    return int(match.group(1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=2000, help="counted ticks per loop")
    parser.add_argument("--warmup", type=int, default=50, help="ticks before counting")
    parser.add_argument("--parts", action="store_true",
                        help="also split our tick into state, rows, ladder and result")
    parser.add_argument("--solves", action="store_true",
                        help="also count solve_hierarchy against daqp.Model at n = 10")
    parser.add_argument("--run", choices=sorted({*LOOPS, *PARTS, *SOLVES}),
                        help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.run:
        if args.run in SOLVES:
            run_solves(args.run, args.warmup, args.ticks)
        else:
            run_loop(args.run, args.warmup, args.ticks)
        return
    if shutil.which("valgrind") is None:
        raise SystemExit("valgrind not found: install it (Debian: apt-get install valgrind)")
    if args.parts:
        previous = 0.0
        for which, label in PARTS.items():
            base = count(which, args.warmup, 0)
            total = (count(which, args.warmup, args.ticks) - base) / args.ticks
            print(f"{label:<60} {total / 1e3:9.1f} k cumulative, {(total - previous) / 1e3:9.1f} k")
            previous = total
    per_tick = {}
    for which, label in LOOPS.items():
        base = count(which, args.warmup, 0)
        total = count(which, args.warmup, args.ticks)
        per_tick[which] = (total - base) / args.ticks
        print(f"{label:<52} {per_tick[which] / 1e3:9.1f} k instructions per tick")
    pink = per_tick["pink"]
    print(f"ratio ours / Pink (instructions): 4-level stack {per_tick['ours'] / pink:.2f}, "
          f"without certificate and damping {per_tick['bare'] / pink:.2f}, "
          f"same content {per_tick['small'] / pink:.2f}")
    if args.solves:
        per_solve = {}
        for which, label in SOLVES.items():
            base = count(which, args.warmup, 0)
            per_solve[which] = (count(which, args.warmup, args.ticks) - base) / args.ticks
            print(f"{label:<72} {per_solve[which] / 1e3:9.1f} k instructions per solve")
        print(f"ratio solve_hierarchy / daqp.Model (instructions): "
              f"{per_solve['api10'] / per_solve['model10']:.2f}")


if __name__ == "__main__":
    main()
