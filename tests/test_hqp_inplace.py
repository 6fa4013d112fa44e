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


def _load_into(solver: InPlaceDaqp, problem) -> None:
    ws = solver.ws
    solver.ws.A[ws.n:ws.head] = problem.hard.A
    solver.ws.A[ws.head:] = np.vstack([b.A for b in problem.levels])
    solver.lo[:ws.n], solver.hi[:ws.n] = problem.lower, problem.upper
    solver.lo[ws.n:ws.head], solver.hi[ws.n:ws.head] = problem.hard.lo, problem.hard.hi
    solver.lo[ws.head:] = np.concatenate([b.lo for b in problem.levels])
    solver.hi[ws.head:] = np.concatenate([b.hi for b in problem.levels])
    solver.w[:] = np.concatenate([b.w for b in problem.levels])


def test_rho_soft_ladder_solves_a_recorded_early_stop():
    """A demo-soak tick where DAQP stops early at rho_soft 1e-8 (exit flag 3): the in-place
    solver walks the back-end's ladder and matches the back-end's general path."""
    from pathlib import Path

    from regressions.corpus import load_problem

    from uvms_qp.hqp import HierarchySolver

    problem, _ = load_problem(Path(__file__).parent / "regressions" / "demo_daqp_rho_ladder.npz")
    sizes = [b.A.shape[0] for b in problem.levels]
    bare = InPlaceDaqp(problem.n, problem.hard.A.shape[0], sizes, problem.W, rho_ladder=())
    _load_into(bare, problem)
    assert bare.solve() is None and bare.rejected == "DAQP exit flag 3"
    solver = InPlaceDaqp(problem.n, problem.hard.A.shape[0], sizes, problem.W)
    _load_into(solver, problem)
    result = solver.solve()
    assert result is not None and result.ok
    assert result.info["rho_soft"] != 1e-8
    restored = solver._model.model.settings["rho_soft"]
    assert solver.settings["rho_soft"] == restored == 1e-8
    reference = HierarchySolver("daqp", weights=problem.W).solve_problem(problem)
    assert reference.info["rho_soft"] == result.info["rho_soft"]
    np.testing.assert_allclose(result.x, reference.x, atol=1e-9)
    assert result.status == reference.status
    # the next tick starts from the first rho_soft again and still answers
    assert solver.solve() is not None


def test_daqp_model_fallback_gives_the_same_answers(monkeypatch):
    """Where the direct C calls are unavailable, daqp.Model serves: same answers, same ladder."""
    from pathlib import Path

    import daqp
    from regressions.corpus import load_problem

    problem, _ = load_problem(Path(__file__).parent / "regressions" / "demo_daqp_rho_ladder.npz")
    sizes = [b.A.shape[0] for b in problem.levels]
    native = InPlaceDaqp(problem.n, problem.hard.A.shape[0], sizes, problem.W)
    _load_into(native, problem)
    expected = native.solve()
    monkeypatch.setattr("uvms_qp.hqp.daqp_model.new_daqp_model", daqp.Model)
    fallback = InPlaceDaqp(problem.n, problem.hard.A.shape[0], sizes, problem.W)
    _load_into(fallback, problem)
    got = fallback.solve()
    assert isinstance(fallback._model.model, daqp.Model)
    assert got is not None and expected is not None
    assert got.info["rho_soft"] == expected.info["rho_soft"] != 1e-8  # walked the ladder
    np.testing.assert_allclose(got.x, expected.x, atol=1e-12)
    # a second, warm call takes the update path of daqp.Model
    assert fallback.solve() is not None
