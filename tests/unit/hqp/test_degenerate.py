"""Reduction of level rows that are constant over the higher levels' optimal set."""

import daqp
import numpy as np
import pytest

from tests.support.oracle.lexicographic import Oracle, first_wrong
from uvms_qp.bench.problems import family
from uvms_qp.hqp import HierarchySolver
from uvms_qp.hqp.backends.daqp import DaqpBackend
from uvms_qp.hqp.degenerate import Reduction, dependent_rows, reduce_levels
from uvms_qp.hqp.problem import Problem
from uvms_qp.hqp.registry import get_spec
from uvms_qp.rows import Rows


def stacked(levels, n, box=np.inf):
    A = np.vstack([np.eye(n), *[L[0] for L in levels]])
    lo = np.concatenate([np.full(n, -box), *[L[1] for L in levels]])
    hi = np.concatenate([np.full(n, box), *[L[2] for L in levels]])
    return A, lo, hi, n, 0, tuple(L[0].shape[0] for L in levels)


def test_repeated_scaled_and_combined_equality_rows_are_dependent():
    a, b = np.array([1.0, 2.0, 0.0]), np.array([0.0, 1.0, 1.0])
    top = (np.vstack((a, b)), np.array([1.0, 2.0]), np.array([1.0, 2.0]))
    low = (np.vstack((-2 * a, a + 3 * b, [1.0, 0.0, 0.0], np.zeros(3))),
           np.array([5.0, 0.0, 0.0, 1.0]), np.array([5.0, 0.0, np.inf, 1.0]))
    mask = dependent_rows(*stacked([top, low], 3))
    assert mask.tolist() == [False, False, True, True, False, True]


def test_rows_repeating_an_inequality_row_are_kept():
    a = np.array([[1.0, 2.0]])
    top = (a, np.array([-1.0]), np.array([1.0]))  # a satisfied slab leaves a x free inside it
    low = (a.copy(), np.array([0.5]), np.array([0.5]))
    assert not dependent_rows(*stacked([top, low], 2)).any()


def daqp_hierarchy(levels, n):
    G = np.vstack([L[0] for L in levels])
    bu = np.concatenate((np.full(n, 1e30), *[L[2] for L in levels]))
    bl = np.concatenate((np.full(n, -1e30), *[L[1] for L in levels]))
    bp = np.cumsum([L[0].shape[0] for L in levels]).astype(np.intc)
    x, _, flag, _ = daqp.solve(np.eye(n), np.zeros(n), G, bu, bl, np.zeros(bu.size, np.intc),
                               break_points=bp, rho_soft=1e-8)
    return x, flag


@pytest.mark.xfail(strict=True, reason="upstream: DAQP 0.11's hierarchical mode drops a level "
                   "whose row repeats a higher one and reports success (exit flag 1)")
def test_upstream_daqp_keeps_a_level_whose_row_repeats_a_higher_one():
    a = np.array([[0.0, 1.0]])
    x, flag = daqp_hierarchy([(a, np.array([5.0]), np.array([5.0])),
                              (a.copy(), np.array([3.0]), np.array([3.0]))], 2)
    assert flag == 1
    np.testing.assert_allclose(x, [0.0, 5.0], atol=1e-9)  # DAQP 0.11 returns [0, 0]


def test_the_reduction_gives_daqp_the_exact_answer_on_the_upstream_case():
    a = np.array([[0.0, 1.0]])
    levels = [(a, np.array([5.0]), np.array([5.0])), (a.copy(), np.array([3.0]),
                                                      np.array([3.0]))]
    A, lo, hi, n, mh, sizes = stacked(levels, 2)
    Ar, lor, hir, sz, _, drop = reduce_levels(A, lo, hi, n, mh, sizes, np.ones(2))
    assert drop.tolist() == [False, True] and sz == (1, 0)
    x, flag = daqp_hierarchy([(Ar[2:3], lor[2:3], hir[2:3])], 2)
    assert flag == 1
    np.testing.assert_allclose(x, [0.0, 5.0], atol=1e-9)


@pytest.mark.parametrize("fam", ["repeated", "no_box_repeat"])
def test_daqp_on_reduced_problems_passes_the_oracle(fam):
    for p in family(fam, 30, seed=0):
        arr = p.stacked()
        n, mh = arr[3], arr[4]
        Ar, lor, hir, sz, wr, _ = reduce_levels(*arr)
        levels, start = [], 0
        for m in sz:
            sl = slice(n + mh + start, n + mh + start + m)
            levels.append([Rows(Ar[sl], lor[sl], hir[sl], wr[start:start + m])] if m else [])
            start += m
        res = HierarchySolver("daqp").solve(levels, lor[:n], hir[:n])
        assert res.status.value == "optimal"
        assert first_wrong(Oracle(*arr).judge(res.x)) is None, p.name


def test_daqp_solves_a_reduced_problem_on_its_current_sides_tick_after_tick():
    # level 1 repeats level 0's row (left out by the reduction); the box moves between solves,
    # as a command-rate window does: every solve must see the box of its own tick
    problem = Problem(2, 0, (1, 1, 1))
    problem.A[2:] = [[0.0, 1.0], [0.0, 1.0], [1.0, 0.0]]
    problem.lo[2:] = problem.hi[2:] = [5.0, 3.0, 1.0]
    backend = DaqpBackend(get_spec("daqp"))
    assert backend.reduce(problem)
    for upper in (10.0, 0.5, 0.25, 10.0):
        problem.lo[:2], problem.hi[:2] = -10.0, [upper, 10.0]
        answer = backend.solve(problem)
        assert answer.status.value == "optimal", answer.message
        np.testing.assert_allclose(answer.x, [min(upper, 1.0), 5.0], atol=1e-9)
        assert answer.info["iterations"] < 50  # one warm DAQP call, no rho_soft ladder


def test_a_reduced_problem_keeps_contiguous_sides():
    problem = Problem(2, 0, (1, 1))
    problem.A[2:] = [[0.0, 1.0], [0.0, 2.0]]
    reduced = Reduction(problem, np.array([False, True])).problem
    assert reduced.lo.flags.c_contiguous and reduced.hi.flags.c_contiguous
