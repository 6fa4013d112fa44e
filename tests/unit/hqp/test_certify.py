"""One QP's KKT certificate and the exact active-set rescue of the cascades (uvms_qp.hqp.kkt).

Hand-checkable QPs: the projection ``min 0.5 |z - c|^2  s.t.  z <= u`` has the optimum
``z* = min(c, u)`` with multipliers ``max(c - u, 0)``; a recorded 1e-8-thin slab (a level QP on
which OSQP gave up and a first version of the rescue cycled) has its optimum at the end of the
slab, computed here from the rows themselves.
"""

import numpy as np
import pytest

from uvms_qp.hqp import HierarchySolver
from uvms_qp.hqp.kkt import active_set_from, certified_point, certify_qp


def projection_qp(rng, n=6):
    c = rng.standard_normal(n)
    u = rng.standard_normal(n)
    return np.eye(n), -c, np.eye(n), u, c, u


def test_certify_accepts_the_optimum_with_its_multipliers():
    rng = np.random.default_rng(1)
    for _ in range(20):
        P, q, G, h, c, u = projection_qp(rng)
        z = np.minimum(c, u)
        cert = certify_qp(P, q, G, h, None, None, z)
        assert cert is not None
        assert cert.lam == pytest.approx(np.maximum(c - u, 0.0), abs=1e-12)
        # the same constraints as bounds: upper multipliers are positive
        cert_b = certify_qp(P, q, None, None, None, u, z)
        assert cert_b is not None
        assert cert_b.lam_box == pytest.approx(np.maximum(c - u, 0.0), abs=1e-12)


def test_certify_rejects_infeasible_and_suboptimal_points():
    rng = np.random.default_rng(2)
    for _ in range(20):
        P, q, G, h, c, u = projection_qp(rng)
        z = np.minimum(c, u)
        assert certify_qp(P, q, G, h, None, None, z + 1e-6) is None  # breaks the active rows
        inner = z.copy()
        inner[np.argmax(u - z)] -= 1e-6  # feasible, 1e-6 away from the optimum
        assert certify_qp(P, q, G, h, None, None, inner) is None


def test_certified_point_sharpens_an_inexact_answer():
    """An ADMM-like answer 1e-7 off becomes the exact optimum (active-set KKT solve)."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        P, q, G, h, c, u = projection_qp(rng)
        z = np.minimum(c, u)
        cert = certified_point(P, q, G, h, None, None, z + 1e-7 * rng.standard_normal(z.size))
        assert cert is not None
        assert cert.z == pytest.approx(z, abs=1e-13)


#: a level QP over z = (y, t) recorded from the lexicographic sweep (problem 521, level 1):
#: min 0.5 t^2 with y confined to a slab of width ~3e-8 by nearly redundant frozen rows
SLAB_G = np.array([
    [-0.3668703266907465, 0.0], [0.03739317227655915, 0.0], [0.9295202601669964, 0.0],
    [0.3668703266907465, 0.0], [-0.01552203229392665, 0.0], [-0.3572529699047476, 0.0],
    [0.25518349641667537, 0.0], [-0.13480089268554596, 0.0], [0.1297561458565511, 0.0],
    [0.05359265691330425, 0.0], [0.10897335490173166, 0.0], [0.3572529699047476, 0.0],
    [0.13480089268554596, 0.0], [-0.1297561458565511, 0.0], [-0.10897335490173166, 0.0],
    [-0.44486363954750835, 1.0], [0.44486363954750835, -1.0]])
SLAB_H = np.array([
    6.6573316034786045e-01, 9.9050699048230528e-01, 1.0178881582387986e+00,
    3.2325690222679959e-01, 9.9999997171806854e-10, 4.2299865832262640e-09,
    8.4614287393393228e-01, 6.8879896504572242e+00, 3.3242619881299018e+00,
    1.4861634114186122e+00, 2.3022280748463686e-09, 3.1235743398523859e+00,
    3.7346400971749460e-09, 1.9209976942491380e-09, 2.8203180246618125e+00,
    -1.4947695025567511e+00, 2.3263409439409934e+00])


def test_active_set_rescue_solves_a_thin_slab_exactly():
    P = np.diag([0.0, 1.0])
    q = np.zeros(2)
    z0 = np.array([0.0, SLAB_H[15]])  # the previous level's answer, feasible
    cert = active_set_from(P, q, SLAB_G, SLAB_H, None, None, z0)
    assert cert is not None
    # t <= h15 + 0.4449 y is negative: |t| is smallest at the largest y the y-only rows allow
    y_rows = SLAB_G[:, 1] == 0.0
    up = y_rows & (SLAB_G[:, 0] > 0.0)
    y_max = np.min(SLAB_H[up] / SLAB_G[up, 0])
    t = SLAB_H[15] - SLAB_G[15, 0] * y_max
    assert cert.z == pytest.approx([y_max, t], abs=1e-15)


def test_active_set_rescue_refuses_an_infeasible_start():
    P, q, G, h, _, u = projection_qp(np.random.default_rng(4))
    assert active_set_from(P, q, G, h, None, None, u + 1.0) is None


def test_active_set_rescue_equals_the_projection():
    rng = np.random.default_rng(5)
    for _ in range(20):
        P, q, G, h, c, u = projection_qp(rng)
        cert = active_set_from(P, q, G, h, None, None, u - 1.0)
        assert cert is not None
        assert cert.z == pytest.approx(np.minimum(c, u), abs=1e-12)


class _FailingQpsolvers:
    """qpsolvers stand-in whose ``solve_problem`` always raises ``exc``."""

    def __init__(self, module, exc):
        self._module, self._exc = module, exc

    def __getattr__(self, name):
        return getattr(self._module, name)

    def solve_problem(self, *args, **kwargs):
        raise self._exc


def _failing_solver(exc):
    from uvms_qp.hqp import HierarchySolver

    solver = HierarchySolver("cascade:quadprog")
    solver.backend._qpsolvers = _FailingQpsolvers(solver.backend._qpsolvers, exc)
    return solver


def test_cascade_rescues_every_failed_qp_exactly():
    """A back-end that fails every QP: the certified active-set rescue gives the exact optimum."""
    from uvms_qp.hqp import HierarchySolver

    rng = np.random.default_rng(6)
    A1, A2 = rng.standard_normal((2, 5)), rng.standard_normal((4, 5))
    # level 1 cannot be met inside the box: bounds active, a compromise to reproduce exactly
    levels = [[(A1, rng.standard_normal(2))], [(A2, np.ones(4), 1.0 + rng.uniform(size=4))]]
    lower, upper = -0.3 * np.ones(5), 0.4 * np.ones(5)
    reference = HierarchySolver("cascade:quadprog").solve(levels, lower, upper)
    result = _failing_solver(RuntimeError("boom")).solve(levels, lower, upper)
    assert result.ok and result.info["rescued_qps"] == 3  # two levels and the final QP
    assert reference.infeasible_level == 1 and reference.active_upper.any()
    assert result.status is reference.status
    assert result.x == pytest.approx(reference.x, abs=1e-9)
    assert result.hard_violation <= 1e-12
    assert result.level_residuals == pytest.approx(reference.level_residuals, abs=1e-9)


def test_cascade_stops_at_its_end_without_a_rescue():
    """A cascade whose solve has ended starts no QP and no rescue: it says where it stopped."""
    rng = np.random.default_rng(7)
    levels = [[(rng.standard_normal((2, 4)), rng.standard_normal(2))]]
    solver = HierarchySolver("cascade:quadprog", deadline=1e-9)
    result = solver.solve(levels, -np.ones(4), np.ones(4))
    assert not result.ok and "level 0" in result.message and "deadline" in result.message
    assert np.all(np.isfinite(result.x))
