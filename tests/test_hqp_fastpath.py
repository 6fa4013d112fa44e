"""The lean DAQP path gives the same answers as the reference (checked) path.

The reference is ``HierarchySolver("daqp", lean=False)``: full normalisation of the input,
stacking and verification on the :class:`Problem`, :func:`uvms_qp.hqp.evaluate.evaluate`. The lean
path (default) loads rows into preallocated buffers, validates them with a few reductions and
measures ``x`` on the stacked rows. Both make the same DAQP calls on the same data, so ``x``,
statuses, residuals, slacks, active masks and hard violations must agree to round-off on the
seeded sweeps of the other hqp tests, and every malformed input must raise the same error.
"""

import numpy as np
import pytest
from test_hqp_crossval import random_equality_problem
from test_hqp_lexicographic import random_mixed_inputs

from uvms_qp import BoundsError, InputError, NonFiniteError, ShapeError
from uvms_qp.hqp import HierarchySolver, Rows, Status
from uvms_qp.hqp.evaluate import evaluate
from uvms_qp.hqp.problem import normalize_problem

N_MIXED = 400
N_EQUALITY = 200
TOL = 1e-12


def assert_same(lean, ref, scale=1.0):
    """Same x, status, first unmet level, residuals, slacks, active masks, hard violation."""
    assert lean.status is ref.status, (lean.summary(), ref.summary())
    assert lean.infeasible_level == ref.infeasible_level
    assert lean.solver == ref.solver and lean.message == ref.message
    tol = TOL * max(1.0, scale, float(np.abs(ref.x).max()))
    assert np.abs(lean.x - ref.x).max() <= tol
    assert lean.level_residuals == pytest.approx(ref.level_residuals, rel=1e-9, abs=tol)
    assert len(lean.level_slacks) == len(ref.level_slacks)
    for a, b in zip(lean.level_slacks, ref.level_slacks, strict=True):
        assert a.shape == b.shape and np.abs(a - b).max(initial=0.0) <= tol
    assert np.array_equal(lean.active_lower, ref.active_lower)
    assert np.array_equal(lean.active_upper, ref.active_upper)
    assert lean.hard_violation == pytest.approx(ref.hard_violation, abs=tol)
    assert lean.info.keys() == ref.info.keys()
    assert lean.info["rho_soft"] == ref.info["rho_soft"]


@pytest.fixture(scope="module")
def mixed():
    rng = np.random.default_rng(7)  # the sweep of test_hqp_lexicographic
    return [random_mixed_inputs(rng) for _ in range(N_MIXED)]


def test_lean_equals_reference_on_mixed_sweep(mixed):
    """Active bounds, inequality levels, hard rows: public solve and solve_problem, both paths."""
    lean, ref = HierarchySolver("daqp"), HierarchySolver("daqp", lean=False)
    lean_p, ref_p = HierarchySolver("daqp"), HierarchySolver("daqp", lean=False)
    statuses = set()
    for levels, lower, upper, hard in mixed:
        a = lean.solve(levels, lower, upper, hard)
        b = ref.solve(levels, lower, upper, hard)
        assert_same(a, b)
        problem = normalize_problem(levels, lower, upper, None, hard)
        c = lean_p.solve_problem(problem)
        assert_same(c, ref_p.solve_problem(problem))
        assert_same(a, c)  # the same sequence of problems: the same warm starts
        statuses.add(a.status)
    assert {Status.OPTIMAL, Status.LEVEL_INFEASIBLE} <= statuses


def test_lean_equals_reference_on_weighted_equality_sweep():
    """Equality hierarchies with a metric W and row weights given as Rows."""
    rng = np.random.default_rng(20240501)
    for i in range(N_EQUALITY):
        levels, W = random_equality_problem(rng)
        if i % 3 == 0:  # weighted rows through Rows objects
            levels = [[Rows.equality(A, b, weights=rng.uniform(0.5, 2.0, b.size))]
                      for ((A, b),) in levels]
        n = (levels[0][0].A if isinstance(levels[0][0], Rows) else levels[0][0][0]).shape[1]
        box = np.full(n, 0.3 + 2.0 * rng.uniform())
        a = HierarchySolver("daqp", W).solve(levels, -box, box)
        b = HierarchySolver("daqp", W, lean=False).solve(levels, -box, box)
        assert_same(a, b)


def test_stacked_problem_loads_like_blocks(mixed):
    """A problem carrying its stacked rows (as a controller hands them over) gives the same."""
    lean, ref = HierarchySolver("daqp"), HierarchySolver("daqp", lean=False)
    for levels, lower, upper, hard in mixed[:100]:
        plain = normalize_problem(levels, lower, upper, None, hard)
        stacked = normalize_problem(levels, lower, upper, None, hard)
        stacked.__dict__["stacked"] = plain.stacked  # precomputed, as a controller does
        assert_same(lean.solve_problem(stacked), ref.solve_problem(plain))


def test_results_stay_valid_after_later_solves(mixed):
    """Lazy slacks and masks use arrays owned by the result, never reused buffers."""
    solver = HierarchySolver("daqp")
    kept = []
    for levels, lower, upper, hard in mixed[:30]:
        kept.append((normalize_problem(levels, lower, upper, None, hard),
                     solver.solve(levels, lower, upper, hard)))
    for problem, result in kept:
        again = evaluate(problem, result.x, "daqp", result.status, result.message,
                         level_tol=solver.level_tol, hard_tol=solver.hard_tol, solve_time=0.0)
        assert again.status is result.status
        for a, b in zip(result.level_slacks, again.level_slacks, strict=True):
            assert np.abs(a - b).max(initial=0.0) <= 1e-12
        assert np.array_equal(result.active_lower, again.active_lower)
        assert np.array_equal(result.active_upper, again.active_upper)


def test_structure_changes_between_calls():
    """Sizes, hard equality pattern and W change between calls: each answer is still right."""
    rng = np.random.default_rng(11)
    solver = HierarchySolver("daqp")
    for k in range(60):
        n = 4 + k % 3
        A1, b1 = rng.standard_normal((1 + k % 2, n)), rng.standard_normal(1 + k % 2)
        Ah = rng.standard_normal((1, n))
        hard = [(Ah, [0.1], [0.1 if k % 4 == 0 else 0.5])]  # equality on every 4th call
        solver.weights = rng.uniform(0.5, 2.0, n) if k % 5 == 0 else None
        levels = [[(A1, b1)], [(np.eye(n), np.zeros(n))]]
        a = solver.solve(levels, -np.ones(n), np.ones(n), hard)
        b = HierarchySolver("daqp", solver.weights, lean=False).solve(
            levels, -np.ones(n), np.ones(n), hard)
        assert_same(a, b)


@pytest.mark.parametrize(
    ("levels", "kwargs", "error"),
    [
        ([[(np.array([[1.0, np.nan]]), [1.0])]], {}, NonFiniteError),
        ([[(np.array([[1.0, np.inf]]), [1.0])]], {}, NonFiniteError),
        ([[(np.eye(2), [1.0, np.inf])]], {}, NonFiniteError),
        ([[(np.eye(2), [1.0, -np.inf])]], {}, NonFiniteError),
        ([[(np.eye(2), [np.nan, 0.0], [1.0, 1.0])]], {}, NonFiniteError),
        ([[(np.eye(2), [np.inf, 0.0], [np.inf, 1.0])]], {}, InputError),
        ([[(np.eye(2), [0.0, 0.0], [-np.inf, 1.0])]], {}, InputError),
        ([[(np.eye(2), [2.0, 0.0], [1.0, 1.0])]], {}, BoundsError),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [0.0, np.nan]}, NonFiniteError),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [np.inf, 0.0]}, InputError),
        ([[(np.eye(2), [1.0, 1.0])]], {"upper": [-np.inf, 0.0]}, InputError),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [1.0, 0.0], "upper": [0.0, 1.0]}, BoundsError),
        ([[(np.eye(2), [1.0, 1.0])]], {"hard": [(np.ones((1, 2)), [1.0], [0.0])]}, BoundsError),
        ([[(np.eye(2), [1.0, 1.0])]], {"hard": [(np.ones((1, 3)), [1.0])]}, ShapeError),
        ([[(np.eye(2), [1.0, 1.0])], [(np.eye(3), [1.0, 1.0, 1.0])]], {}, ShapeError),
        ([[(np.eye(2), [1.0, 1.0])]], {"weights": [1.0, 0.0]}, InputError),
    ],
)
@pytest.mark.parametrize("lean", [True, False])
def test_bad_input_raises_on_both_paths(levels, kwargs, error, lean):
    kwargs = dict(kwargs)
    weights = kwargs.pop("weights", None)
    with pytest.raises(error):
        HierarchySolver("daqp", weights, lean=lean).solve(levels, **kwargs)


def test_bad_input_after_good_calls_still_raises():
    """A reused workspace does not let a NaN through once the structure is known."""
    solver = HierarchySolver("daqp")
    A = np.eye(3)
    assert solver.solve([[(A, np.ones(3))]], -np.ones(3), np.ones(3)).ok
    A_bad = A.copy()
    A_bad[1, 2] = np.nan
    with pytest.raises(NonFiniteError, match=r"levels\[0\]\[0\]"):
        solver.solve([[(A_bad, np.ones(3))]], -np.ones(3), np.ones(3))
    assert solver.solve([[(A, np.ones(3))]], -np.ones(3), np.ones(3)).ok


def test_reference_continuation_from_first_answer(mixed, monkeypatch):
    """When the hot path declines DAQP's first answer, the reference path continues from it.

    Forcing the decline on every call must reproduce the reference path exactly (the retry
    ladder starts from the answer already computed, on the same model state).
    """
    from uvms_qp.hqp.backends.daqp_hierarchical import DaqpHierarchicalBackend

    monkeypatch.setattr(DaqpHierarchicalBackend, "_measure", staticmethod(lambda *args: None))
    lean, ref = HierarchySolver("daqp"), HierarchySolver("daqp", lean=False)
    for levels, lower, upper, hard in mixed[:150]:
        assert_same(lean.solve(levels, lower, upper, hard), ref.solve(levels, lower, upper, hard))


def test_stacked_slacks_are_the_level_slacks_end_to_end(mixed):
    for lean in (True, False):
        solver = HierarchySolver("daqp", lean=lean)
        for levels, lower, upper, hard in mixed[:20]:
            result = solver.solve(levels, lower, upper, hard)
            assert np.array_equal(result.stacked_slacks, np.concatenate(result.level_slacks))


def test_metric_changed_in_place_is_noticed():
    """The validated metric is cached, but an in-place change of the weights is honoured."""
    W = np.array([1.0, 1.0])
    solver = HierarchySolver("daqp", W)
    level = [[(np.array([[1.0, 1.0]]), [1.0])]]
    assert solver.solve(level).x == pytest.approx([0.5, 0.5], abs=1e-6)
    W[0] = 3.0  # x0 three times as expensive: x = (0.25, 0.75)
    assert solver.solve(level).x == pytest.approx([0.25, 0.75], abs=1e-6)
    W[1] = -1.0
    with pytest.raises(InputError, match="weights"):
        solver.solve(level)
