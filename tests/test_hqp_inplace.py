"""InPlaceDaqp (uvms_qp.hqp.inplace): a fixed structure filled in place, against solve_hierarchy."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

import uvms_qp.hqp.inplace as inplace_module
from uvms_qp.errors import InputError
from uvms_qp.hqp import Rows, Status, solve_hierarchy
from uvms_qp.hqp.inplace import InPlaceDaqp


def test_docstring_example_runs():
    assert doctest.testmod(inplace_module, raise_on_error=False).failed == 0


@pytest.mark.parametrize("bad", [
    {"n": 0}, {"n": 2.5}, {"hard_rows": -1}, {"sizes": []}, {"sizes": [2, 0]},
    {"W": [1.0, -1.0, 1.0]}, {"W": [1.0, 1.0]}, {"W": [1.0, np.nan, 1.0]},
])
def test_bad_construction_raises_input_error(bad):
    args = {"n": 3, "hard_rows": 0, "sizes": [2, 1], "W": None, **bad}
    with pytest.raises(InputError):
        InPlaceDaqp(args["n"], args["hard_rows"], args["sizes"], args["W"])


def test_matches_solve_hierarchy_over_a_drifting_sequence():
    """Same x, status and level residuals as the public entry, call after call.

    To 1e-7: DAQP's accuracy at rho_soft 1e-8 (the two warm-start from different histories).
    """
    rng = np.random.default_rng(21)
    accepted = 0
    for case in range(30):
        n = int(rng.integers(3, 16))
        sizes = [int(v) for v in rng.integers(1, 5, size=int(rng.integers(1, 5)))]
        mh = int(rng.integers(0, 3))
        W = rng.uniform(0.5, 3.0, n)
        box = float(rng.choice([0.05, 0.5, 10.0]))
        solver = InPlaceDaqp(n, mh, sizes, W)
        ws = solver.ws
        A = rng.standard_normal((sum(sizes), n))
        H = rng.standard_normal((mh, n))
        b = rng.standard_normal(sum(sizes))
        ineq = rng.uniform(size=sum(sizes)) < 0.3
        for _ in range(5):
            A += 0.05 * rng.standard_normal(A.shape)
            b += 0.05 * rng.standard_normal(b.shape)
            hi_levels = np.where(ineq, np.inf, b)
            hard_hi = np.full(mh, box * n)  # a hard slab that may be active
            ws.A[ws.head:] = A
            ws.A[n:ws.head] = H
            solver.lo[:n], solver.hi[:n] = -box, box
            solver.lo[n:ws.head], solver.hi[n:ws.head] = -hard_hi, hard_hi
            solver.lo[ws.head:], solver.hi[ws.head:] = b, hi_levels
            got = solver.solve()
            levels, r = [], 0
            for m in sizes:
                levels.append([Rows(A[r:r + m].copy(), b[r:r + m].copy(),
                                    hi_levels[r:r + m].copy())])
                r += m
            hard = [Rows(H.copy(), -hard_hi, hard_hi)] if mh else None
            ref = solve_hierarchy(levels, -box * np.ones(n), box * np.ones(n), weights=W,
                                  hard=hard)
            if got is None:  # declined: the caller's general path answers instead
                assert solver.rejected
                continue
            accepted += 1
            assert got.status == ref.status, case
            np.testing.assert_allclose(got.x, ref.x, atol=1e-7, err_msg=str(case))  # rho_soft 1e-8
            np.testing.assert_allclose(got.level_residuals, ref.level_residuals, atol=1e-7)
            assert got.infeasible_level == ref.infeasible_level
            assert np.all(got.x >= -box) and np.all(got.x <= box)
            assert got.hard_violation <= 1e-9
            assert got.status in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE)
    assert accepted >= 140  # of 150 calls
