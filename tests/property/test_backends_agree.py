"""Every back-end equals the closed-form null-space recursion on well-posed equality hierarchies.

On seeded random problems (n from 3 to 30, 1 to 6 levels of full row rank together, equality
rows, a metric W, box bounds far from the solution) the lexicographic optimum is the recursive
null-space solution of Soylu et al. (2007), Eq. (10), in the metric W; each back-end must match
it to the tolerance the registry states for it (``SolverSpec.agreement_tol``).
"""

import numpy as np
import pytest

from uvms_qp.hqp import HierarchySolver, Status, available_solvers, normalize_problem
from uvms_qp.hqp.backends.nullspace import nullspace_solve
from uvms_qp.hqp.registry import get_spec

N_PROBLEMS = 500
#: interior-point / ADMM back-ends are slower: a seeded subset keeps the suite fast
N_SLOW = 150
SLOW = {"cascade:clarabel", "cascade:highs", "cascade:osqp"}


def random_equality_problem(rng):
    n = int(rng.integers(3, 31))
    p = min(int(rng.integers(1, 7)), n)
    total = int(rng.integers(p, n + 1))
    sizes = np.ones(p, dtype=int)
    for _ in range(total - p):
        sizes[rng.integers(p)] += 1
    levels = [[(rng.standard_normal((m, n)), rng.standard_normal(m))] for m in sizes]
    W = rng.uniform(0.5, 10.0, n) if rng.uniform() < 0.5 else None
    return levels, W


@pytest.fixture(scope="module")
def problems():
    rng = np.random.default_rng(20240501)
    out = []
    for _ in range(N_PROBLEMS):
        levels, W = random_equality_problem(rng)
        ref = HierarchySolver("nullspace", W).solve(levels)
        assert ref.status is Status.OPTIMAL, ref.summary()
        bound = np.abs(ref.x) + 1.0  # inactive box: the null-space solution stays optimal
        out.append((normalize_problem(levels, -bound, bound, W), ref.x))
    return out


@pytest.mark.parametrize("name", [s for s in available_solvers() if s != "nullspace"])
def test_backend_equals_nullspace(name, problems):
    tol = get_spec(name).agreement_tol
    count = N_SLOW if name in SLOW else N_PROBLEMS
    failures = []
    for i, (problem, x_ref) in enumerate(problems[:count]):
        solver = HierarchySolver(name, problem.W)
        result = solver.solve_problem(problem)
        err = np.abs(result.x - x_ref).max() / max(1.0, np.abs(x_ref).max())
        if result.status is not Status.OPTIMAL or err > tol:
            failures.append((i, str(result.status), err))
    assert not failures, f"{name}: {len(failures)}/{count} disagree with nullspace: {failures[:5]}"


def test_weighted_metric_equals_weighted_pseudoinverse():
    """One level: x = W^-1 A' (A W^-1 A')^-1 b (Soylu et al. (2007), Eq. (17))."""
    rng = np.random.default_rng(3)
    W = np.array([10.0, 10.0, 10.0, 1.0, 1.0, 1.0])
    for _ in range(20):
        A = rng.standard_normal((3, 6))
        b = rng.standard_normal(3)
        Wi = np.diag(1.0 / W)
        expected = Wi @ A.T @ np.linalg.solve(A @ Wi @ A.T, b)
        for name in ("nullspace", "daqp", "cascade:quadprog"):
            x = HierarchySolver(name, W).solve([[(A, b)]]).x
            assert np.allclose(x, expected, atol=get_spec(name).agreement_tol * 10), name


@pytest.mark.parametrize("weighted", [False, True])
def test_nullspace_ignores_level_without_remaining_freedom(weighted):
    """n = 10, levels [6, 3, 1, 4]: levels 1-3 fix x, so level 4 must contribute nothing.

    The first three levels form a square regular system, so ``x = A_123^-1 b_123`` exactly
    (independent of W); level 4 only gets a residual. A cut-off relative to the projected
    block would invert the round-off left in it and return ``|x| ~ 1e15``.
    """
    rng = np.random.default_rng(11)
    for _ in range(20):
        levels = [[(rng.standard_normal((m, 10)), rng.standard_normal(m))] for m in (6, 3, 1, 4)]
        W = rng.uniform(0.5, 10.0, 10) if weighted else None
        A = np.vstack([lv[0][0] for lv in levels[:3]])
        b = np.concatenate([lv[0][1] for lv in levels[:3]])
        expected = np.linalg.solve(A, b)
        result = HierarchySolver("nullspace", W).solve(levels)
        tol = 1e-8 * max(1.0, np.abs(expected).max())
        assert np.abs(result.x - expected).max() < tol
        # level 3 is proven optimal, or (a 10 x 10 system of condition up to 1e5 pins x) said
        # to be sensitive to round-off of the levels above: never called optimal unproven
        assert result.infeasible_level == 3
        assert result.status in (Status.OPTIMAL, Status.UNPROVEN)
        assert result.unmet_levels or result.status is Status.UNPROVEN
        # the trusted entry (for the controller's hot path) gives the same numbers
        x, _ = nullspace_solve(normalize_problem(levels, weights=W))
        assert np.abs(x - expected).max() < tol


def test_nullspace_damps_a_near_singular_level_and_does_not_call_it_optimal():
    """A level of condition 1e8: the plain pseudoinverse returns |x| ~ 1e8 (the exact
    solution); the default damping keeps |x| within |b| / (damping |A|_F) and the status says
    that the damped answer is not proven optimal."""
    rng = np.random.default_rng(5)
    U, _ = np.linalg.qr(rng.standard_normal((2, 2)))
    V, _ = np.linalg.qr(rng.standard_normal((4, 2)))
    A = (U * np.array([1.0, 1e-8])) @ V.T
    b = np.array([1.0, -1.0])
    plain = HierarchySolver("nullspace", options={"damping": 0.0}).solve([[(A, b)]])
    assert np.abs(plain.x).max() > 1e7 and plain.status is Status.OPTIMAL  # exact, proven
    damped = HierarchySolver("nullspace").solve([[(A, b)]])
    bound = np.linalg.norm(b) / (1e-6 * np.linalg.norm(A))
    assert np.abs(damped.x).max() <= bound and damped.info["damped"] == (0,)
    assert damped.status is Status.UNPROVEN and not damped.ok
    assert "not proven optimal" in damped.message


def closed_form_cases(count):
    """Equality hierarchies of the fuzz draws (zero, tiny, repeated, scaled rows), no box."""
    from uvms_qp.testing.fuzz import _problem, draw

    out = []
    seed = 0
    while len(out) < count:
        case = draw(seed, ("nullspace",))
        seed += 1
        problem = _problem(case)
        head, n = problem.head, problem.n
        if case.mh or (problem.lo[head:] != problem.hi[head:]).any():
            continue
        problem.lo[:n], problem.hi[:n] = -np.inf, np.inf
        out.append((case.seed, problem))
    return out


def test_closed_form_asks_no_more_than_a_proven_optimum_and_labels_damping_truthfully():
    """Without a box, the closed form's answer is never larger than a proven optimum's (its
    damping only shrinks weak directions), and a damped answer is ``optimal`` only with every
    level met or certified (its message then claims nothing else)."""
    closed, exact = HierarchySolver("nullspace"), HierarchySolver("daqp")
    reference = HierarchySolver("cascade:quadprog")
    damped = 0
    for seed, problem in closed_form_cases(300):
        result = closed.solve_problem(problem)
        if "damped" in result.info:
            damped += 1
            cert = result.certificate
            if result.status is Status.OPTIMAL:
                assert cert is None or cert.ok, seed
                assert "not the undamped optimum" not in result.message, seed
            else:
                assert result.status is Status.UNPROVEN and not cert.ok, seed
        proven = exact.solve_problem(problem)
        if proven.status is not Status.OPTIMAL:
            proven = reference.solve_problem(problem)
        if proven.status is Status.OPTIMAL:
            size = float(np.linalg.norm(proven.x))
            assert np.linalg.norm(result.x) <= 2.0 * size + 1e-9, (seed, size)
    assert damped  # the draws do reach the damping
