"""Replay every problem of the regression corpus (tests/regressions/*.npz) on every back-end.

For each saved problem and each installed solver (with the limits a 0.5 s step deadline gives):
the raw result is finite and its status is truthful (a solution status implies the hard set
holds), and the safe solver returns a command inside the box that a solver stage verified (the
saved problems all have a non-empty hard set), or, only after a missed deadline, a degraded one.
Add a problem with ``tests.regressions.corpus.save_problem(problem, name, note)``.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from tests.regressions.corpus import corpus_files, load_problem, save_problem
from uvms_qp.errors import InputError
from uvms_qp.hqp import HierarchySolver, available_solvers, hard_violation
from uvms_qp.hqp.hard_set import hard_feasible
from uvms_qp.hqp.registry import get_spec
from uvms_qp.safety import SOLVED_STAGES, SafeSolver, backend_limits

DEADLINE = 0.5  # [s]
FILES = corpus_files()
SOLVERS = available_solvers()


def test_corpus_is_not_empty():
    assert len(FILES) >= 5


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
@pytest.mark.parametrize("solver", SOLVERS)
def test_replay(path, solver):
    problem, note = load_problem(path)
    assert hard_feasible(problem), note
    all_equality = all(np.array_equal(lv.lower, lv.upper) for lv in problem.levels)
    if not get_spec(solver).inequality_levels and not all_equality:
        with pytest.raises(InputError, match="equality rows only"):  # a capability, stated
            HierarchySolver(solver).solve_problem(problem)
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        raw = HierarchySolver(solver, options=backend_limits(solver, DEADLINE)).solve_problem(
            problem)
        out = SafeSolver(solver, deadline=DEADLINE).solve(problem)
    assert np.all(np.isfinite(raw.x)), note
    if raw.ok:
        assert violation(problem, raw.x) <= raw_tol(problem), (solver, note)
    assert np.all(out.x >= problem.lower) and np.all(out.x <= problem.upper)
    assert out.stage in SOLVED_STAGES or out.deadline_missed, (solver, out.attempts, note)
    if out.stage in SOLVED_STAGES:
        assert violation(problem, out.x) <= raw_tol(problem)


def violation(problem, x):
    hard = problem.hard
    return hard_violation(x, problem.lower, problem.upper, hard.A, hard.lower, hard.upper)


def raw_tol(problem):
    return 1e-9 * problem.hard_scale


def test_save_and_load_round_trip(tmp_path):
    problem, note = load_problem(FILES[0])
    path = save_problem(problem, "copy", note, tmp_path)
    again, note2 = load_problem(path)
    assert note2 == note and again.n == problem.n and again.sizes == problem.sizes
    assert np.array_equal(again.A, problem.A) and np.array_equal(again.sides, problem.sides)
    assert np.array_equal(again.w, problem.w) and np.array_equal(again.W, problem.W)
    with pytest.raises(ValueError, match="name"):
        save_problem(problem, "../escape", note, tmp_path)
