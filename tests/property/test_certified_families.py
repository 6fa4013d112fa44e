"""Every ok answer is the lexicographic optimum: the degenerate families against the oracle.

For each fast back-end, 2016 problems of the six plain-matrix families of
:mod:`uvms_qp.bench.problems` (336 each: well-conditioned; a higher row repeated in a lower
level; zero and tiny rows; near-singular levels; ill-conditioned levels; a repeated row with no
box on some variables) are solved as a user solves them: the certificate asked, the repair on.
Every answer with an ok status (``optimal``) is judged by the independent
oracle (``tests/support/oracle/lexicographic.py``: Clarabel on each unmet level's frozen set, every
witness verified in NumPy): no level may be improvable by more than 1e-6 of its scale. An
answer the certificate cannot prove is ``unproven`` (never an ok status); on the degenerate
families that, and a truthful failure of the back-end, are allowed and counted; on the others
unproven answers must stay rare and failures absent. The
oracle's judgement of an answer is shared by the back-ends that return the same point.
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from tests.support.oracle.lexicographic import TOL, Oracle, first_wrong
from uvms_qp.bench.problems import MATRIX_FAMILIES, family
from uvms_qp.hqp import HierarchySolver, Status, available_solvers, normalize_problem

FAST = [s for s in ("daqp", "cascade:quadprog", "cascade:daqp", "cascade:proxqp",
                    "cascade:piqp") if s in available_solvers()]
PER_FAMILY = 336
#: families without a degenerate level: an answer there is proven, bar a rare ill-posed level
WELL_POSED = ("well", "repeated", "zero_row", "no_box_repeat")


class Case:
    """One problem with its oracle and the judgements made so far (by answer)."""

    def __init__(self, p):
        self.family, self.name = p.family, p.name
        self.problem = normalize_problem(p.levels_rows(), p.lower, p.upper, None, p.hard_rows())
        self.oracle = Oracle(*p.stacked())
        self.judged: list[tuple[np.ndarray, list]] = []

    def judge(self, x):
        for seen, judgement in self.judged:
            if np.abs(seen - x).max() <= 1e-10 * (1.0 + np.abs(x).max()):
                return judgement
        judgement = self.oracle.judge(x, met=TOL)
        self.judged.append((x.copy(), judgement))
        return judgement


@pytest.fixture(scope="module")
def cases():
    return [Case(p) for name in MATRIX_FAMILIES for p in family(name, PER_FAMILY, seed=5000)]


@pytest.mark.slow
@pytest.mark.parametrize("solver", FAST)
def test_no_ok_answer_is_improvable(solver, cases):
    hs = HierarchySolver(solver)
    wrong, unproven, other = [], Counter(), Counter()
    for case in cases:
        result = hs.solve_problem(case.problem)
        assert np.all(np.isfinite(result.x)), case.name
        if result.ok:
            assert result.hard_violation <= 1e-9 * case.problem.hard_scale, case.name
            judged = case.judge(result.x)
            k = first_wrong(judged)
            if k is not None:
                wrong.append((case.name, result.status.value, k, judged[k].improvement))
        elif result.status is Status.UNPROVEN:
            assert result.certificate is not None and not result.certificate.ok
            unproven[case.family] += 1
        else:
            other[(case.family, result.status.value)] += 1
    print(f"\n{solver}: unproven by family {dict(unproven)}, other {dict(other)}")
    assert not wrong, f"{solver}: {len(wrong)} ok answers the oracle improves: {wrong[:5]}"
    # a failed solve (truthful, never an ok status) only where a level is degenerate
    assert all(fam not in WELL_POSED for fam, _ in other), other
    assert sum(unproven[f] for f in WELL_POSED) <= 0.01 * len(WELL_POSED) * PER_FAMILY
