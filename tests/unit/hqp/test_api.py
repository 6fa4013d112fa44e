"""Public surface of the lexicographic solver: results, statuses and semantics.

Its bad input is tested in ``test_validation.py``.
"""

import time

import numpy as np
import pytest

from uvms_qp import (
    InputError,
    solve_hierarchy,
)
from uvms_qp.hqp import HierarchySolver, Rows, Status, available_solvers, normalize_problem
from uvms_qp.hqp.registry import SOLVERS

QP = [s for s in available_solvers() if s != "nullspace"]
EXACT = ["daqp", "cascade:quadprog"]


def test_available_solvers_lists_installed_in_registry_order():
    names = available_solvers()
    assert names[:2] == ["daqp", "nullspace"]
    assert all(n.startswith("cascade:") for n in names[2:])
    assert names == [s.name for s in SOLVERS if s.available]


@pytest.mark.parametrize("name", QP)
def test_priority_and_bounds_hand_checked(name):
    """x0 + x1 = 1 first, then x = (5, 5, 5) inside |x| <= 1: x = (0.5, 0.5, 1)."""
    A1 = np.array([[1.0, 1.0, 0.0]])
    result = solve_hierarchy([[(A1, [1.0])], [(np.eye(3), [5.0, 5.0, 5.0])]],
                             lower=[-1.0] * 3, upper=[1.0] * 3, solver=name)
    assert result.status is Status.OPTIMAL and result.ok and result.unmet_levels
    assert result.infeasible_level == 1
    assert np.allclose(result.x, [0.5, 0.5, 1.0], atol=1e-6)
    assert result.active_upper.tolist() == [False, False, True]
    assert not result.active_lower.any()
    assert result.level_residuals[0] < 1e-6
    assert result.level_residuals[1] == pytest.approx(np.sqrt(2 * 4.5**2 + 16.0), rel=1e-6)
    text = result.summary()
    assert name in text and "level 1" in text and "NOT met" in text


@pytest.mark.parametrize("name", QP)
def test_inequality_level_keeps_freedom(name):
    """Level 1: x0 >= 1 (inequality); level 2: x0 = 3. Freezing slacks (not A x) gives x0 = 3."""
    result = solve_hierarchy([[(np.array([[1.0, 0.0]]), [1.0], [np.inf])],
                              [(np.array([[1.0, 0.0]]), [3.0])]], solver=name)
    assert result.status is Status.OPTIMAL
    assert result.x == pytest.approx([3.0, 0.0], abs=1e-6)


@pytest.mark.parametrize("name", QP)
def test_frozen_violation_of_infeasible_inequality_level(name):
    """Level 1: x0 >= 2 under x0 <= 1 (violation 1 frozen); level 2 x0 = 0 must not move x0."""
    result = solve_hierarchy([[(np.array([[1.0, 0.0]]), [2.0], [np.inf])],
                              [(np.array([[1.0, 1.0]]), [0.0])]],
                             lower=[-1.0, -1.0], upper=[1.0, 1.0], solver=name)
    assert result.infeasible_level == 0
    assert result.x == pytest.approx([1.0, -1.0], abs=1e-6)
    assert result.level_residuals == pytest.approx([1.0, 0.0], abs=1e-6)


@pytest.mark.parametrize("name", QP)
def test_hard_infeasible_is_reported(name):
    result = solve_hierarchy([[(np.eye(2), [0.0, 0.0])]], lower=[0.0, 0.0], upper=[1.0, 1.0],
                             solver=name, hard=[(np.array([[1.0, 1.0]]), [3.0], [np.inf])])
    assert result.status is Status.HARD_INFEASIBLE
    assert not result.ok
    assert np.all(np.isfinite(result.x))


@pytest.mark.parametrize("name", QP)
def test_hard_rows_hold(name):
    A = np.array([[1.0, 1.0, 1.0]])
    result = solve_hierarchy([[(np.eye(3), [1.0, 1.0, 1.0])]], solver=name,
                             hard=[(A, [-np.inf], [1.5])])
    assert result.ok and result.infeasible_level == 0
    assert (A @ result.x)[0] <= 1.5 + 1e-9
    assert result.x == pytest.approx([0.5, 0.5, 0.5], abs=1e-6)


@pytest.mark.parametrize("name", ["nullspace", *QP])
def test_rank_deficient_and_conflicting_levels(name):
    """Duplicated rows and a level conflicting with the first: least squares in the null space."""
    A1 = np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])  # rank 1, consistent
    A2 = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # first row conflicts with level 1
    result = solve_hierarchy([[(A1, [1.0, 2.0])], [(A2, [3.0, 2.0])]], solver=name)
    assert result.status is Status.OPTIMAL and result.infeasible_level == 1
    assert result.unmet_levels[0] == 1
    assert result.x == pytest.approx([1.0, 2.0, 0.0], abs=1e-6)
    assert result.level_residuals[1] == pytest.approx(2.0, abs=1e-6)


@pytest.mark.parametrize("name", ["nullspace", *QP])
def test_algorithmic_singularity_gives_finite_answer(name):
    """Two tasks that become parallel (a conflict of rank one): finite x, truthful status."""
    eps = 1e-9
    A1 = np.array([[1.0, 0.0]])
    A2 = np.array([[1.0, eps]])
    result = solve_hierarchy([[(A1, [0.0])], [(A2, [1.0])]], solver=name)
    assert np.all(np.isfinite(result.x))
    assert result.status is Status.OPTIMAL
    assert abs(result.x[0]) < 1e-6  # the first level is never traded for the second


@pytest.mark.parametrize("scale", [1e-6, 1e6])
@pytest.mark.parametrize("name", ["nullspace", *EXACT])
def test_scalings(name, scale):
    rng = np.random.default_rng(5)
    A1, A2 = rng.standard_normal((2, 5)), rng.standard_normal((2, 5))
    b1, b2 = rng.standard_normal(2), rng.standard_normal(2)
    base = solve_hierarchy([[(A1, b1)], [(A2, b2)]], solver="nullspace").x
    result = solve_hierarchy([[(A1, b1 * scale)], [(A2, b2 * scale)]], solver=name)
    assert result.status is Status.OPTIMAL
    assert result.x == pytest.approx(base * scale, rel=1e-6, abs=1e-6 * scale)


def test_daqp_weights_mean_what_they_mean_on_the_cascades():
    """An unmet level: DAQP minimises the weighted violation sum w_i s_i^2, like a cascade.

    Without per-row soft weights DAQP would return 0.5 here (it normalises rows: the compromise
    of weights 1/|a_i|^2, whatever w); its per-row soft weights give it the weighted one.
    """
    A = np.array([[1.0, 0.0], [10.0, 0.0]])
    b = np.array([0.0, 10.0])  # x0 = 0 and 10 x0 = 10 conflict
    for weights, expected in (([1.0, 1.0], 100.0 / 101.0), ([1.0, 7.0], 700.0 / 701.0),
                              ([100.0, 1.0], 100.0 / 200.0)):
        daqp = solve_hierarchy([[Rows.equality(A, b, weights=weights)]], solver="daqp")
        cascade = solve_hierarchy([[Rows.equality(A, b, weights=weights)]],
                                  solver="cascade:quadprog")
        assert cascade.x[0] == pytest.approx(expected, abs=1e-8)
        assert daqp.x[0] == pytest.approx(expected, abs=1e-8)
        assert daqp.level_residuals[0] == pytest.approx(cascade.level_residuals[0], rel=1e-8)
    # row scaling does not change the weighted compromise either
    scaled = solve_hierarchy([[Rows.equality(A * 1e3, b * 1e3, weights=[1.0, 7.0])]],
                             solver="daqp")
    assert scaled.x[0] == pytest.approx(700.0 / 701.0, abs=1e-8)


@pytest.mark.parametrize("name", ["nullspace", *EXACT])
def test_weights_agree_when_level_is_met(name):
    """Weights change nothing when the level can be met: every back-end gives the same x."""
    A = np.array([[1.0, 2.0, 0.0], [0.0, 3.0, 1.0]])
    b = np.array([1.0, 2.0])
    plain = solve_hierarchy([[(A, b)]], solver="nullspace").x
    weighted = solve_hierarchy([[Rows.equality(A, b, weights=[5.0, 0.1])]], solver=name).x
    assert weighted == pytest.approx(plain, abs=1e-7)


def test_cascade_weights_are_weighted_least_squares():
    A = np.array([[1.0, 0.0], [1.0, 0.0]])
    b = np.array([0.0, 1.0])
    result = solve_hierarchy([[Rows.equality(A, b, weights=[1.0, 3.0])]],
                             solver="cascade:quadprog")
    assert result.x[0] == pytest.approx(0.75, abs=1e-8)
    assert result.level_residuals[0] == pytest.approx(np.sqrt(0.75**2 + 3 * 0.25**2), abs=1e-8)


def test_nullspace_reports_violated_bound():
    result = solve_hierarchy([[(np.eye(2), [2.0, 0.0])]], lower=[-1, -1], upper=[1, 1],
                             solver="nullspace")
    assert result.status is Status.BACKEND_ERROR
    assert "upper bound 0" in result.message
    assert np.all(np.isfinite(result.x))


def test_solver_object_reuse_is_consistent():
    rng = np.random.default_rng(9)
    solver = HierarchySolver("daqp", weights=[1.0, 2.0, 3.0, 4.0])
    for _ in range(20):
        A1, b1 = rng.standard_normal((2, 4)), rng.standard_normal(2)
        A2, b2 = rng.standard_normal((1, 4)), rng.standard_normal(1)
        levels = [[(A1, b1)], [(A2, b2)]]
        again = solver.solve(levels, -np.full(4, 10.0), np.full(4, 10.0))
        fresh = solve_hierarchy(levels, solver="nullspace", weights=[1.0, 2.0, 3.0, 4.0])
        assert again.x == pytest.approx(fresh.x, abs=1e-7)
        assert again.solve_time > 0.0 and again.solver == "daqp"


def test_empty_and_all_equal_bounds():
    result = solve_hierarchy([[(np.eye(2), [3.0, 3.0])]], lower=[1.0, 1.0], upper=[1.0, 2.0])
    assert result.x == pytest.approx([1.0, 2.0])
    assert result.active_lower.tolist() == [True, False]
    assert result.active_upper.tolist() == [True, True]


def test_no_levels_gives_minimum_norm_point_of_box():
    result = solve_hierarchy([], lower=[1.0, -2.0], upper=[3.0, -1.0], solver="cascade:quadprog")
    assert result.x == pytest.approx([1.0, -1.0])
    assert result.level_residuals == []


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


def test_structure_changes_between_calls():
    """Sizes, hard equality pattern and W change between calls: a reused solver gives each
    problem the answer a fresh one gives."""
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
        b = HierarchySolver("daqp", solver.weights).solve(levels, -np.ones(n), np.ones(n), hard)
        assert a.status is b.status
        np.testing.assert_allclose(a.x, b.x, atol=1e-7)


def test_results_stay_valid_after_later_solves():
    """A result owns its slacks and box: later solves on the same buffers do not change it."""
    rng = np.random.default_rng(3)
    solver = HierarchySolver("daqp")
    kept = []
    for _ in range(20):
        levels = [[(rng.standard_normal((2, 5)), rng.standard_normal(2))],
                  [(np.eye(5), rng.standard_normal(5))]]
        box = (-np.full(5, 0.4), np.full(5, 0.4))
        result = solver.solve(levels, *box)
        kept.append((levels, box, result, result.slacks.copy(), result.active_upper.copy()))
    for levels, box, result, slacks, active in kept:
        again = normalize_problem(levels, *box)
        z = again.A @ result.x
        np.testing.assert_allclose(result.slacks, z - np.clip(z, again.lo, again.hi), atol=1e-12)
        assert np.array_equal(result.slacks, slacks) and np.array_equal(result.active_upper,
                                                                        active)
        assert np.array_equal(result.box, np.stack(box))


def test_cli_solvers_lists_installed(capsys):
    from uvms_qp.cli import main

    assert main(["solvers"]) == 0
    out = capsys.readouterr().out
    for name in available_solvers():
        assert name in out


@pytest.mark.skipif("cascade:proxqp" not in available_solvers(), reason="proxsuite missing")
def test_proxqp_is_bounded_on_a_badly_scaled_level():
    # BlueROV2 tool rows at home, target 1e6 m away with gain 10 (used to run for a minute)
    A = np.array([
        [1, 0, 0, 0, -0.058358470175360361, -0.099000330993482585, 3.3099348258069927e-07,
         0.017641529824639651, 0.054895711407959361, 0],
        [0, 1, 0, 0.058358470175360361, 0, 0.51461142773189239, -0.27461142773189240, 0,
         -1.3171897158927282e-07, 0],
        [0, 0, 1, 0.099000330993482585, -0.51461142773189239, 0, 0, -0.25461142773189238,
         0.12251131935048581, 0]])
    b = np.array([9.999994853885721e+06, -0.9900033099348259, 0.5835847017536036])
    lo = np.array([-1.5] + [-np.inf] * 5 + [-0.5] * 4)
    t0 = time.perf_counter()
    r = solve_hierarchy([[(A, b)]], lo, -lo, solver="cascade:proxqp")
    elapsed = time.perf_counter() - t0
    assert elapsed < 10.0  # was about 60 s; well under 1 s on an idle machine
    assert np.all(np.isfinite(r.x))
    if r.status == Status.OPTIMAL:  # an answer is only reported optimal when it is one
        assert np.max(np.abs(A @ r.x - b)) <= 1e-6 * np.max(np.abs(b))
    else:
        assert r.status == Status.BACKEND_ERROR


@pytest.mark.skipif("cascade:highs" not in available_solvers(), reason="highspy missing")
def test_an_answer_of_the_wrong_length_from_a_back_end_is_a_failed_qp():
    """HiGHS answers a level with rows of 1e10 with an empty x; that used to escape as a raw
    ValueError from the certificate's feasibility test instead of a failed QP."""
    levels = [[(np.array([[1e10, 1.0, 0.0]]), [1.0])], [(np.eye(3), [1.0, 2.0, 3.0])]]
    result = solve_hierarchy(levels, -np.ones(3), np.ones(3), solver="cascade:highs")
    assert np.all(np.isfinite(result.x)) and np.all(np.abs(result.x) <= 1.0)
    # (unproven: rows of 1e10 beside rows of 1, which the certificate may not prove at 1e-6)
    assert result.status in (Status.OPTIMAL, Status.BACKEND_ERROR, Status.UNPROVEN)
    if result.status == Status.OPTIMAL:  # then the first level is met: x0 = 1e-10 (1 - x1)
        assert abs(1e10 * result.x[0] + result.x[1] - 1.0) <= 1e-6
