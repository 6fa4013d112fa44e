"""Singular-value damping of a level: exact away from singularities, sigma b / epsilon^2 along a
weak direction, the lower levels' freedom untouched, the closed form and the QP agreeing."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp import solve_hierarchy
from uvms_qp.hqp.damping import level_damping

EPS = 0.1


def _levels(blocks):
    return [(A, lo, hi, np.ones(A.shape[0])) for A, lo, hi in blocks]


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


def test_no_rows_away_from_singularities():
    rng = np.random.default_rng(0)
    blocks = [(rng.normal(size=(3, 7)), np.zeros(3), np.zeros(3)),
              (rng.normal(size=(2, 7)), -np.ones(2), np.ones(2))]
    x = solve_hierarchy([[b] for b in blocks]).x
    damping = level_damping(_levels(blocks), x, np.ones(7), [EPS, EPS])
    assert not damping.acted and damping.damped_levels == ()
    assert min(damping.sigma_min) > EPS


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
    damping = level_damping(_levels(blocks), undamped, np.ones(4), [EPS])
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
        damping = level_damping(_levels(blocks), undamped, np.ones(5), [EPS])
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
        damping = level_damping(_levels(blocks), undamped, np.ones(3), [EPS], dt=dt)
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
    damping = level_damping(_levels(blocks), undamped, np.ones(n), [EPS, 0.0])
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
    damping = level_damping(_levels(blocks), undamped, np.ones(n), [EPS, EPS])
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
    assert not level_damping(_levels(blocks), x, np.ones(n), [EPS]).acted
    blocks = [(A, np.array([0.1, 0.3]), np.array([0.1, 0.3]))]
    x = solve_hierarchy([[blocks[0]]]).x
    assert level_damping(_levels(blocks), x, np.ones(n), [EPS]).acted
    assert not level_damping(_levels(blocks), x, np.ones(n), [0.0]).acted


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
    damping = level_damping(_levels(blocks), undamped, W, [EPS, EPS])
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
    with_hard = level_damping(_levels(blocks), x, np.ones(n), [EPS], hard=hard)
    alone = level_damping(_levels(blocks), x, np.ones(n), [EPS])
    assert with_hard.acted and not alone.acted
