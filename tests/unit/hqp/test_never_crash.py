"""The solve path never takes its host process down: degenerate input gets a typed answer.

Each check runs in a child process, so that a native abort fails the test instead of ending
the test session.
"""

import json
import subprocess
import sys
import textwrap

import pytest

from uvms_qp.hqp import available_solvers
from uvms_qp.testing import fuzz

# level 0: a zero row with target 1; level 1: x0 = -1; judged at the origin, the level-1
# gradient is nonzero and the only side active above it is the zero row: SciPy's nnls was
# handed a matrix without columns and aborted (double free, exit status 134)
ZERO_ROW_ABOVE = """
import numpy as np
from uvms_qp.hqp import Problem, solve_hierarchy
from uvms_qp.hqp.backends.daqp_binding import open_daqp
from uvms_qp.hqp.certificate import Certifier
p = Problem(2, 0, [1, 1])
p.A[2:] = 0.0
p.A[3, 0] = 1.0
p.lo[:2], p.hi[:2] = -np.inf, np.inf
p.lo[2] = p.hi[2] = 1.0
p.lo[3] = p.hi[3] = -1.0
print(Certifier(open_daqp)(p, np.array([0.0, 0.0])).levels[1].verdict)
zero = np.zeros((1, 2))
r = solve_hierarchy([[(zero, [1.0])], [(zero, [0.0]), (np.array([[1.0, 0.0]]), [-1.0])]],
                    solver=SOLVER)
print(r.status.value, r.ok, r.x.tolist())
"""


def run_child(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=120)


@pytest.mark.parametrize("solver", available_solvers())
def test_zero_row_above_an_unmet_level_gets_a_typed_answer(solver):
    out = run_child(f"SOLVER = {solver!r}\n" + ZERO_ROW_ABOVE)
    assert out.returncode == 0, out.stderr[-2000:]
    verdict, answer = out.stdout.splitlines()[:2]
    assert verdict == "unproven"  # the origin is not the optimum of level 1, and not certified
    _, ok, x = answer.split(" ", 2)
    if solver != "nullspace":
        assert ok == "True", answer  # level 0 cannot be met; x0 = -1 is proven optimal
        assert json.loads(x)[0] == pytest.approx(-1.0, abs=1e-6)


def test_degenerate_problems_never_abort_the_process():
    # a few hundred draws of the fuzz harness (the benchmark runs 10^5): zero, tiny, repeated
    # and scaled rows, empty levels, pinned boxes, n from 1 to 60, on every back-end
    report = fuzz.run(first=0, count=300, timeout=60.0)
    assert report.cases == 300
    assert report.aborts == [] and report.hangs == []
    for part in ("certify", "repair", "damping"):
        assert report.outcomes[f"{part}: ok"] == 300, report.raised[:5]


def test_a_worker_that_dies_names_the_case_it_died_in():
    # the harness itself: the last line a dying worker wrote names its case
    code = "import os, sys\nfrom uvms_qp.testing import fuzz\n" \
           "orig = fuzz.run_case\n" \
           "def dying(case, solvers):\n" \
           "    if case.seed == 3:\n" \
           "        os.abort()\n" \
           "    return orig(case, solvers)\n" \
           "fuzz.run_case = dying\n"
    out = run_child(code + "fuzz.worker(0, 6)\n")
    assert out.returncode != 0
    assert out.stdout.splitlines()[-1] == "start 3"
