"""Singular-value damping of a level: exact away from singularities, sigma b / epsilon^2 along a
weak direction, the lower levels' freedom untouched, the closed form and the QP agreeing."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp import solve_hierarchy
from uvms_qp.hqp import normalize_problem
from uvms_qp.hqp.damping import level_damping

EPS = 0.1


def _damping(blocks, x, thresholds, metric=None, hard=None, dt=0.0):
    problem = normalize_problem([[b] for b in blocks], weights=metric,
                                hard=None if hard is None else [hard])
    return level_damping(problem, x, thresholds, dt)


def _with_rows(blocks, damping):
    out = []
    for (A, lo, hi), D in zip(blocks, damping.rows, strict=True):
        level = [(A, lo, hi)]
        if D is not None:
            level.append((D, np.zeros(D.shape[0]), np.zeros(D.shape[0])))
        out.append(level)
    return out


def _orthonormal(rng, n):
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return q


def test_levels_without_rows_need_no_damping():
    """Empty levels (every task out of the stack, say) give no rows and no error."""
    empty = (np.zeros((0, 3)), np.zeros(0), np.zeros(0))
    damping = _damping([empty, empty], np.array([0.3, -0.2, 0.1]), [EPS, EPS], dt=0.05)
    assert damping.rows == (None, None)
    assert not damping.acted


def test_no_rows_away_from_singularities():
    rng = np.random.default_rng(0)
    blocks = [(rng.normal(size=(3, 7)), np.zeros(3), np.zeros(3)),
              (rng.normal(size=(2, 7)), -np.ones(2), np.ones(2))]
    x = solve_hierarchy([[b] for b in blocks]).x
    damping = _damping(blocks, x, [EPS, EPS])
    assert not damping.acted and damping.damped_levels == ()
    assert min(damping.sigma_min) >= EPS  # a proven lower bound


@pytest.mark.parametrize("angle", [0.05, 1e-3, 1e-7])
def test_the_weak_direction_gets_sigma_b_over_epsilon_squared(angle):
    """Two unit rows at ``angle``: singular values ``sqrt(2) cos(angle/2)`` and
    ``sqrt(2) sin(angle/2)``; along the weak one the damped answer is ``sigma b / eps^2``."""
    rng = np.random.default_rng(1)
    V = _orthonormal(rng, 4)
    A = np.vstack([V[:, 0], np.cos(angle) * V[:, 0] + np.sin(angle) * V[:, 1]])
    b = np.array([0.4, 0.1])
    U, S, Vt = np.linalg.svd(A)
    sigma, u, v = S[1], U[:, 1], Vt[1]
    assert sigma == pytest.approx(np.sqrt(2.0) * np.sin(angle / 2.0), rel=1e-6)
    blocks = [(A, b, b)]
    undamped = solve_hierarchy([[blocks[0]]]).x
    if angle > 1e-4:  # (below, DAQP's own soft-row regularisation already caps the answer)
        assert v @ undamped == pytest.approx(u @ b / sigma, rel=1e-5)
    damping = _damping(blocks, undamped, [EPS])
    assert damping.damped_levels == (0,) and damping.sigma_min[0] == pytest.approx(sigma)
    x = solve_hierarchy(_with_rows(blocks, damping)).x
    assert v @ x == pytest.approx(sigma * (u @ b) / EPS**2, rel=1e-6, abs=1e-8)
    assert Vt[0] @ x == pytest.approx(U[:, 0] @ b / S[0], rel=1e-7)  # the strong one: exact


def test_the_scale_and_units_of_the_rows_do_not_matter():
    """Rows are compared at unit norm: the units of a level (a common scale of its rows and
    targets) leave the damped answer alone (solved in closed form, itself blind to them)."""
    rng = np.random.default_rng(7)
    A = rng.normal(size=(2, 5))
    A[1] = A[0] + 1e-3 * rng.normal(size=5)
    b = np.array([0.3, -0.2])
    answers = []
    for scale in (np.array([1.0, 1.0]), np.array([1e-6, 1e-6]), np.array([1e4, 1e4])):
        blocks = [(scale[:, None] * A, scale * b, scale * b)]
        undamped = solve_hierarchy([[blocks[0]]], solver="nullspace").x
        damping = _damping(blocks, undamped, [EPS])
        assert damping.acted
        answers.append(solve_hierarchy(_with_rows(blocks, damping), solver="nullspace").x)
    assert np.allclose(answers[1], answers[0], rtol=1e-7, atol=1e-10)
    assert np.allclose(answers[2], answers[0], rtol=1e-7, atol=1e-10)


def test_a_large_demand_over_a_long_period_raises_the_threshold():
    """``epsilon_i = max(epsilon, sqrt(dt |b_i|))``: the damped closed loop settles without
    overshoot only when ``epsilon_i^2 >= dt g |b_i|``."""
    rng = np.random.default_rng(8)
    V = _orthonormal(rng, 3)
    angle = 0.2  # sigma = sqrt(2) sin(0.1) = 0.141: above EPS, below sqrt(dt |b|) for a big b
    A = np.vstack([V[:, 0], np.cos(angle) * V[:, 0] + np.sin(angle) * V[:, 1]])
    for b, dt, damped in ((np.array([0.0, 0.02]), 0.05, False),
                          (np.array([0.0, 2.0]), 0.05, True),
                          (np.array([0.0, 2.0]), 0.0, False)):
        blocks = [(A, b, b)]
        undamped = solve_hierarchy([[blocks[0]]]).x
        damping = _damping(blocks, undamped, [EPS], dt=dt)
        assert damping.acted is damped, (b, dt)


def test_damping_leaves_the_lower_levels_all_the_freedom_the_rows_leave():
    """The damped hierarchy equals the undamped one whose damped level asks exactly what the
    damped answer achieves: damping changes that level's target, nothing else."""
    rng = np.random.default_rng(2)
    n = 7
    A0 = rng.normal(size=(3, n))
    A0[2] = A0[1] + 0.01 * rng.normal(size=n)  # two nearly parallel rows, conflicting targets
    b0 = np.array([0.5, 0.2, -0.3])
    A1 = rng.normal(size=(3, n))
    b1 = rng.normal(size=3)
    blocks = [(A0, b0, b0), (A1, b1, b1)]
    undamped = solve_hierarchy([[b] for b in blocks]).x
    damping = _damping(blocks, undamped, [EPS, 0.0])
    assert damping.damped_levels == (0,)
    x = solve_hierarchy(_with_rows(blocks, damping)).x
    achieved = A0 @ x
    reference = solve_hierarchy([[(A0, achieved, achieved)], [(A1, b1, b1)]]).x
    assert np.allclose(x, reference, atol=1e-7)
    assert np.linalg.norm(x) < np.linalg.norm(undamped) / 10  # the rates stay bounded


def test_a_conflict_with_a_higher_level_is_damped_in_its_freedom():
    """Each level alone is well conditioned; the lower one is nearly a combination of the
    higher one's rows (an algorithmic singularity): its projected singular value is damped."""
    rng = np.random.default_rng(3)
    n = 5
    A0 = rng.normal(size=(2, n))
    A1 = (rng.normal(size=2) @ A0 + 1e-3 * rng.normal(size=n))[None, :]
    blocks = [(A0, np.zeros(2), np.zeros(2)), (A1, np.ones(1), np.ones(1))]
    assert np.linalg.svd(A1, compute_uv=False)[0] > 1.0
    undamped = solve_hierarchy([[b] for b in blocks]).x
    damping = _damping(blocks, undamped, [EPS, EPS])
    assert damping.damped_levels == (1,) and damping.sigma_min[1] < 1e-2
    x = solve_hierarchy(_with_rows(blocks, damping)).x
    assert np.allclose(A0 @ x, 0.0, atol=1e-9)  # the higher level is untouched
    assert np.linalg.norm(x) < 1.0 < np.linalg.norm(undamped)


def test_inactive_inequality_rows_and_a_zero_threshold_are_not_damped():
    rng = np.random.default_rng(4)
    n = 4
    A = np.vstack([rng.normal(size=n), rng.normal(size=n)])
    A[1] = A[0] + 1e-5 * rng.normal(size=n)
    blocks = [(A, np.array([0.1, -np.inf]), np.array([0.1, 10.0]))]  # row 1 far from its side
    x = solve_hierarchy([[blocks[0]]]).x
    assert not _damping(blocks, x, [EPS]).acted
    blocks = [(A, np.array([0.1, 0.3]), np.array([0.1, 0.3]))]
    x = solve_hierarchy([[blocks[0]]]).x
    assert _damping(blocks, x, [EPS]).acted
    assert not _damping(blocks, x, [0.0]).acted


def test_the_metric_and_the_closed_form_agree_with_the_qp():
    rng = np.random.default_rng(5)
    n = 6
    W = rng.uniform(0.5, 4.0, n)
    A0 = rng.normal(size=(2, n))
    A0[1] = A0[0] + 2e-3 * rng.normal(size=n)
    b0 = np.array([0.3, -0.2])
    A1 = rng.normal(size=(2, n))
    b1 = rng.normal(size=2)
    blocks = [(A0, b0, b0), (A1, b1, b1)]
    undamped = solve_hierarchy([[b] for b in blocks], weights=W).x
    damping = _damping(blocks, undamped, [EPS, EPS], W)
    assert damping.acted
    qp = solve_hierarchy(_with_rows(blocks, damping), weights=W).x
    closed = solve_hierarchy(_with_rows(blocks, damping), weights=W, solver="nullspace").x
    assert np.allclose(qp, closed, atol=1e-7)


def test_active_hard_rows_restrict_the_freedom():
    rng = np.random.default_rng(6)
    n = 4
    h = rng.normal(size=n)
    A = (h + 1e-4 * rng.normal(size=n))[None, :]  # almost the hard row itself
    blocks = [(A, np.ones(1), np.ones(1))]
    hard = (h[None, :], np.zeros(1), np.zeros(1))
    x = solve_hierarchy([[blocks[0]]], hard=[hard]).x
    with_hard = _damping(blocks, x, [EPS], hard=hard)
    alone = _damping(blocks, x, [EPS])
    assert with_hard.acted and not alone.acted


def _oracle(blocks, x, thresholds, W, dt, hard=None):
    """The damping rows from their definition, level by level, without shortcuts (Gram matrices
    ``D' D`` per level, which do not depend on the signs or the basis of equal singular values)."""
    n = x.size
    root = np.sqrt(W)
    y = x * root
    Z = np.eye(n)
    if hard is not None:
        H, lo, hi = hard
        z = H @ x
        act = (lo == hi) | (z <= lo + 1e-7 * max(1.0, np.abs(lo).max())) | (z >= hi - 1e-7)
        if act.any():
            _, s, vt = np.linalg.svd(H[act] / root)
            Z = vt[int(np.sum(s > 1e-12 * s[0])):].T
    grams = []
    for (A, lo, hi), eps in zip(blocks, thresholds, strict=True):
        z = A @ x
        tol = 1e-7 * max(1.0, np.abs(z).max())
        act = (lo == hi) | (z <= lo + tol) | (z >= hi - tol)
        dem = act & ((lo == hi) | (lo > 0) | (hi < 0))
        U = A / root
        norms = np.linalg.norm(U, axis=1)
        U = U / norms[:, None]
        gram = None
        if dem.any() and eps > 0 and Z.shape[1]:
            u, s, vt = np.linalg.svd(U[dem] @ Z)
            r = int(np.sum(s > 1e-12 * s[0]))
            target = np.clip(z, lo, hi)[dem] / norms[dem]
            # the level's target less what the higher levels' motion already gives it
            demand = u[:, :r].T @ (target - U[dem] @ (y - Z @ (Z.T @ y)))
            limit = np.maximum(eps**2, dt * np.abs(demand))
            weak = s[:r] ** 2 < limit
            if weak.any():
                lam = np.linalg.norm(u[:, :r][:, weak] * norms[dem][:, None], axis=0)
                lam = lam * np.sqrt(limit[weak] - s[:r][weak] ** 2)
                D = lam[:, None] * (vt[:r][weak] @ Z.T) * root
                gram = D.T @ D
        grams.append(gram)
        if act.any() and Z.shape[1]:
            _, s, vt = np.linalg.svd(U[act] @ Z)
            Z = Z @ vt[int(np.sum(s > 1e-12 * s[0])):].T
    return grams


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize("dt", [0.0, 0.05, 0.5])
def test_the_damping_rows_match_their_definition(seed, dt):
    rng = np.random.default_rng(seed)
    n = 7
    W = rng.uniform(0.5, 3.0, n)
    A0 = rng.normal(size=(2, n))
    A0[1] = A0[0] + 10.0 ** rng.uniform(-4, 0) * rng.normal(size=n)
    b0 = rng.normal(size=2)
    A1 = rng.normal(size=(3, n))
    A1[2] = A1[0] + 10.0 ** rng.uniform(-4, 0) * rng.normal(size=n)
    lo1 = np.array([rng.normal(), 0.5, -1.0])  # a floor that excludes zero; a band around it
    hi1 = np.array([lo1[0], np.inf, 10.0])
    A2 = A0[:1] + 10.0 ** rng.uniform(-4, 0) * rng.normal(size=(1, n))  # conflicts with level 0
    b2 = rng.normal(size=1)
    blocks = [(A0, b0, b0), (A1, lo1, hi1), (A2, b2, b2)]
    x = solve_hierarchy([[b] for b in blocks], weights=W).x
    thresholds = [EPS, 0.2, EPS]
    expected = _oracle(blocks, x, thresholds, W, dt)
    damping = _damping(blocks, x, thresholds, W, dt=dt)
    for got, want in zip(damping.rows, expected, strict=True):
        assert (got is None) == (want is None)
        if got is not None:
            assert np.allclose(got.T @ got, want, rtol=1e-6, atol=1e-9 * np.abs(want).max())


def test_a_level_that_undoes_a_higher_levels_motion_is_damped_by_its_demand():
    n = 4
    A0 = np.eye(n)[:1]  # level 0 moves x0 by 5
    b0 = np.array([5.0])
    A1 = np.array([[1.0, 0.3, 0.0, 0.0]])  # sees that motion, cancels it through x1 (weakly)
    blocks = [(A0, b0, b0), (A1, np.zeros(1), np.zeros(1))]
    x = solve_hierarchy([[b] for b in blocks]).x
    assert A1 @ x == pytest.approx(0.0, abs=1e-9)  # the level itself is met: its A x is zero
    assert not _damping(blocks, x, [0.0, EPS], dt=0.0).acted  # 0.3 is above epsilon
    damping = _damping(blocks, x, [0.0, EPS], dt=0.05)  # 0.3^2 < dt * |demand| ~ 0.05 * 5
    assert damping.damped_levels == (1,)


def test_an_inactive_row_beside_a_weak_pair_changes_nothing():
    rng = np.random.default_rng(8)
    n = 5
    A = rng.normal(size=(2, n))
    A[1] = A[0] + 1e-3 * rng.normal(size=n)
    b = np.array([0.2, 0.1])
    far = rng.normal(size=(1, n))
    pair = [(A, b, b)]
    with_far = [(np.vstack((A, far)), np.append(b, -100.0), np.append(b, 100.0))]
    x = solve_hierarchy([pair]).x
    rows = _damping(pair, x, [EPS]).rows[0]
    rows_far = _damping(with_far, x, [EPS]).rows[0]
    assert rows is not None and rows_far is not None
    assert np.allclose(rows_far.T @ rows_far, rows.T @ rows)


def _random_stack(rng, n, hard_rows):
    """Three levels of random rows, some nearly dependent, some inequalities, some hard rows."""
    blocks = []
    for m in rng.integers(1, 5, size=3):
        A = rng.normal(size=(m, n))
        if m > 1 and rng.random() < 0.5:
            A[-1] = A[0] + 10.0 ** rng.uniform(-3, 0) * rng.normal(size=n)
        b = rng.normal(size=m)
        lo, hi = b.copy(), b.copy()
        loose = rng.random(m) < 0.3
        lo[loose], hi[loose] = -np.inf, b[loose] + rng.uniform(-0.5, 2.0, size=loose.sum())
        blocks.append((A, lo, hi))
    hard = None
    if hard_rows:
        hard = (rng.normal(size=(hard_rows, n)), np.full(hard_rows, -0.2), np.full(hard_rows, 0.2))
    return blocks, hard


@pytest.mark.parametrize("seed", range(40))
def test_the_screen_never_hides_a_weak_direction(seed):
    """Random stacks of 4 to 9 variables whose levels fit, fill or overflow the freedom, near
    and far from their thresholds: the answer with the screen is the definition's."""
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(4, 10))
    blocks, hard = _random_stack(rng, n, int(rng.integers(0, 3)))
    W = rng.uniform(0.5, 3.0, n)
    x = solve_hierarchy([[b] for b in blocks], weights=W,
                        hard=None if hard is None else [hard]).x
    thresholds = list(rng.choice([0.0, 0.05, 0.3], size=3))
    dt = float(rng.choice([0.0, 0.05, 0.2]))
    damping = _damping(blocks, x, thresholds, W, hard=hard, dt=dt)
    expected = _oracle(blocks, x, thresholds, W, dt, hard)
    for got, want in zip(damping.rows, expected, strict=True):
        assert (got is None) == (want is None)
        if got is not None:
            assert np.allclose(got.T @ got, want, rtol=1e-6, atol=1e-9 * np.abs(want).max())


def test_rank_deficient_hard_rows_leave_the_levels_their_freedom():
    """As many active hard rows as variables but of rank n - 1: the level keeps one direction,
    nearly singular, and is damped there."""
    n = 3
    h = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
    hard = (h, np.zeros(3), np.zeros(3))
    A = np.array([[1.0, 0.0, 1e-3]])  # sees the free direction z only weakly
    blocks = [(A, np.ones(1), np.ones(1))]
    x = solve_hierarchy([[blocks[0]]], hard=[hard]).x
    damping = _damping(blocks, x, [EPS], hard=hard)
    assert damping.damped_levels == (0,)
    expected = _oracle(blocks, x, [EPS], np.ones(n), 0.0, hard)[0]
    assert np.allclose(damping.rows[0].T @ damping.rows[0], expected)


def test_what_a_problem_keeps_between_calls_follows_its_rows_sides_and_metric():
    """The views, buffers and per-active-set structure kept for a problem give, call after call
    with new rows, sides (active sets that change), hard rows, thresholds and metric, what a
    fresh copy of the problem gives."""
    rng = np.random.default_rng(7)
    n, sizes = 7, [2, 2, 5]
    blocks = [(rng.normal(size=(m, n)), -np.ones(m), np.ones(m)) for m in sizes]
    hard = (rng.normal(size=(2, n)), -np.ones(2), np.ones(2))
    problem = normalize_problem([[b] for b in blocks], hard=[hard])
    rows, head = problem.A[n:], problem.head
    for step in range(60):
        rows[...] = rng.normal(size=rows.shape)
        if step % 3 == 0:  # a nearly dependent row: the screen cannot settle it
            rows[-1] = rows[-2] + 1e-3 * rng.normal(size=n)
        x = rng.normal(size=n)
        z = problem.A @ x
        gap = rng.choice([0.0, 1e-9, 0.5, 0.5, np.inf], size=(2, problem.M - n))
        problem.lo[n:], problem.hi[n:] = z[n:] - gap[0], z[n:] + gap[1]
        equality = rng.random(problem.M - head) < 0.5
        problem.hi[head:][equality] = problem.lo[head:][equality] = z[head:][equality] + 0.1
        if step == 30:
            problem.W = rng.uniform(0.5, 2.0, size=n)
        thresholds = (0.01, 0.01, 0.01) if step < 45 else (0.01, 0.0, 0.02)
        kept = level_damping(problem, x, thresholds, 0.05)
        fresh = level_damping(problem.copy(), x, thresholds, 0.05)
        assert kept.sigma_min == pytest.approx(fresh.sigma_min, nan_ok=True, rel=0, abs=0)
        for a, b in zip(kept.rows, fresh.rows, strict=True):
            assert (a is None and b is None) or np.array_equal(a, b)


def test_a_kept_reference_gives_what_the_tests_give():
    """Rows drifting slowly through an overflowing set of active rows, the two leading ones onto
    each other and away again: the unit rows a problem keeps from the last passed tests (which stand
    for the tests while the rows stay near them) give, call after call, what a fresh copy of
    the problem gives, damping rows and bounds alike."""
    from uvms_qp.hqp import damping

    rng = np.random.default_rng(11)
    n, sizes = 5, [2, 6]  # two rows that fit, then six that overflow the freedom left
    blocks = [(rng.normal(size=(m, n)), np.zeros(m), np.zeros(m)) for m in sizes]
    problem = normalize_problem([[b] for b in blocks])
    rows, head = problem.A[n:], problem.head
    start = rows.copy()
    stood = 0
    for step in range(90):
        rows[...] = start + 1e-3 * step * rng.normal(size=rows.shape)
        if 30 <= step < 60:  # the second row moves onto the first, and back
            rows[1] = rows[0] + (abs(step - 45) / 15 + 1e-3) * start[1]
        problem.lo[head:] = problem.hi[head:] = rng.normal(size=problem.M - head)
        x = rng.normal(size=n)
        kept = level_damping(problem, x, (EPS, EPS), 0.05)
        fresh = level_damping(problem.copy(), x, (EPS, EPS), 0.05)
        assert kept.sigma_min == pytest.approx(fresh.sigma_min, nan_ok=True, rel=0, abs=0)
        for a, b in zip(kept.rows, fresh.rows, strict=True):
            assert (a is None and b is None) or np.array_equal(a, b)
        shapes = damping._SETUPS[problem].shapes.values()
        stood += any(shape.reference is not None for shape in shapes)
    assert stood > 15  # the kept unit rows stood for the tests on many calls
