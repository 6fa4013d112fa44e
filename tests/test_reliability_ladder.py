"""The fallback ladder on plain problems: every fault gives a safe command and a named stage.

Faults are injected into the back-end (uvms_qp.testing.faults) so the whole path is exercised:
back-end -> evaluation -> verification -> ladder -> saturation.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from uvms_qp.errors import InputError, NoSolutionFound, UnknownSolverError
from uvms_qp.hqp import Status, normalize_problem
from uvms_qp.safety import (
    DEGRADED_STAGES,
    STAGES,
    Deadline,
    SafeSolver,
    backend_limits,
    default_alternate,
    fallback_summary,
    saturate,
    verify_point,
    verify_solution,
)
from uvms_qp.testing.faults import Fault, inject

BOX = 0.3


def _problem(seed: int = 0, n: int = 6, hard_rows: bool = True, box: float = BOX):
    rng = np.random.default_rng(seed)
    A1 = rng.normal(size=(3, n))
    A2 = rng.normal(size=(2, n))
    hard = [(rng.normal(size=(1, n)), [-0.2], [0.2])] if hard_rows else None
    return normalize_problem([[(A1, rng.normal(size=3))], [(A2, rng.normal(size=2))]],
                             np.full(n, -box), np.full(n, box), hard=hard)


def _safe(problem, x, tol=1e-9):
    assert np.all(np.isfinite(x))
    assert np.all(x >= problem.lower) and np.all(x <= problem.upper)  # exactly, after saturation
    return verify_point(problem, x, tol)


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
@pytest.mark.parametrize("fault", list(Fault))
def test_every_fault_gives_a_verified_command_and_names_the_stage(solver, fault):
    problem = _problem(1)
    reference = SafeSolver(solver).solve(problem)
    assert reference.stage == "primary"
    safe = SafeSolver(solver, deadline=0.1)  # generous: the machine may be loaded
    wrapper = inject(safe.primary, fault, count=1, sleep=0.15)
    out = safe.solve(problem)
    assert wrapper.n_faults == 1
    assert _safe(problem, out.x).ok
    if fault is Fault.SLEEP:  # late but correct: used, and the miss is reported
        assert out.stage == "primary" and out.deadline_missed
    else:
        assert out.stage == "cold_retry"
        assert out.attempts and out.attempts[0].startswith("primary:")
        assert np.allclose(out.x, reference.x, atol=1e-7)
    assert out.result.ok and out.result.status == reference.result.status


@pytest.mark.parametrize("fault, needle", [
    (Fault.RAISE_OWN, "SolverError"), (Fault.RAISE_FOREIGN, "RuntimeError"),
    (Fault.NAN_SUCCESS, "no finite x"), (Fault.BOUND_VIOLATION, "box_violated (1.00e-01)"),
    (Fault.WILD_FAILURE, "box_violated (1.00e+12)"),
])
def test_attempt_log_says_what_went_wrong(fault, needle):
    safe = SafeSolver("daqp")
    inject(safe.primary, fault, count=1)
    out = safe.solve(_problem(2))
    assert needle in out.attempts[0]


@pytest.mark.parametrize("times, stages", [
    (1, ["cold_retry", "primary", "primary"]),
    (3, ["alternate", "cold_retry", "primary"]),  # 2 calls on step 0, the 3rd on step 1
    (100, ["alternate", "alternate", "alternate"]),
])
def test_consecutive_failures_climb_down_the_ladder(times, stages):
    # feasible levels, so that both back-end families have the same unique answer
    problem = _problem(3, box=10.0)
    reference = SafeSolver("daqp").solve(problem).x
    safe = SafeSolver("daqp")
    inject(safe.primary, Fault.NAN_SUCCESS, count=times)
    got = []
    for _ in range(3):
        out = safe.solve(problem)
        assert _safe(problem, out.x).ok
        assert np.allclose(out.x, reference, atol=1e-6)
        got.append(out.stage)
    assert got == stages


def test_all_back_ends_down_decays_then_holds_zero_then_recovers():
    problem = _problem(4)
    safe = SafeSolver("daqp", max_fallbacks=3, decay=0.5)
    first = safe.solve(problem)
    primary = inject(safe.primary, Fault.RAISE_FOREIGN)
    assert safe.alternate is not None
    alternate = inject(safe.alternate, Fault.WILD_FAILURE)
    primary.armed = alternate.armed = True
    stages, xs = [], []
    for _ in range(6):
        out = safe.solve(problem)
        assert _safe(problem, out.x).ok
        assert out.result.status == Status.BACKEND_ERROR  # truthful: not a solve
        assert out.stage in DEGRADED_STAGES and out.stage in out.result.message
        stages.append(out.stage)
        xs.append(out.x)
    assert stages == ["decayed_previous"] * 3 + ["hold_zero"] * 3
    for k in range(3):
        assert np.allclose(xs[k], first.x * 0.5 ** (k + 1))
    assert not np.any(xs[3]) and not np.any(xs[5])
    # while holding zero only the primary is tried: one call per step
    calls = primary.n_calls
    safe.solve(problem)
    assert primary.n_calls == calls + 1 and alternate.n_calls == 3
    primary.armed = False
    out = safe.solve(problem)
    assert out.stage == "primary" and safe.consecutive == 0
    assert safe.stage_counts["hold_zero"] == 4
    assert "hold_zero: 4" in fallback_summary(safe.stage_counts)


def test_relaxed_stage_drops_the_lowest_level_and_reports_the_full_problem():
    problem = _problem(5)
    safe = SafeSolver("daqp", alternate=None)
    wrapper = inject(safe.primary, Fault.NAN_SUCCESS, calls=[0, 1])  # primary + cold retry
    out = safe.solve(problem)
    assert wrapper.n_faults == 2
    assert out.stage == "relaxed" and out.relaxed_levels == 1
    assert len(out.result.level_residuals) == 2  # evaluated against the full problem
    assert "dropped" in out.result.message
    assert _safe(problem, out.x).ok


def test_strict_mode_raises_with_the_failed_result():
    safe = SafeSolver("daqp", strict=True)
    primary = inject(safe.primary, Fault.BOUND_VIOLATION)
    alternate = inject(safe.alternate, Fault.NAN_SUCCESS)
    primary.armed = alternate.armed = True
    with pytest.raises(NoSolutionFound, match="no verified solution") as info:
        safe.solve(_problem(6))
    assert info.value.result is not None
    assert info.value.result.status == Status.BACKEND_ERROR


def test_strict_mode_still_takes_the_non_degrading_stages():
    safe = SafeSolver("daqp", strict=True)
    inject(safe.primary, Fault.RAISE_OWN, count=1)
    assert safe.solve(_problem(6)).stage == "cold_retry"


def test_empty_hard_set_goes_straight_to_zero_with_hard_infeasible():
    n = 3
    problem = normalize_problem([[(np.eye(n), np.ones(n))]], np.full(n, -1.0), np.full(n, 1.0),
                                hard=[(np.ones((1, n)), [5.0], [np.inf])])
    for solver in ("daqp", "cascade:quadprog"):
        safe = SafeSolver(solver)
        out = safe.solve(problem)
        assert out.stage == "zero" and out.result.status == Status.HARD_INFEASIBLE
        assert np.all(out.x == 0.0)
        assert any("admit no point" in a for a in out.attempts)


def test_deadline_skips_the_solver_stages_after_a_late_failure():
    problem = _problem(7)
    safe = SafeSolver("daqp", deadline=0.01)
    safe.solve(problem)
    wrapper = inject(safe.primary, Fault.SLEEP, sleep=0.03)
    wrapper.armed = True
    out = safe.solve(problem)
    assert out.stage == "primary" and out.deadline_missed  # late, verified: used
    # late *and* wrong: no more solver stages; the cheap stages answer
    safe2 = SafeSolver("daqp", deadline=0.01)
    safe2.solve(problem)
    late_nan = inject(safe2.primary, Fault.SLEEP)  # not armed: only the inner stand-in acts
    real = late_nan.inner

    class LateNaN:
        def solve(self, p):
            out = real.solve(p)
            time.sleep(0.03)
            out.x = np.full(p.n, np.nan)
            return out

    late_nan.inner = LateNaN()
    start = time.perf_counter()
    out = safe2.solve(problem)
    assert out.stage == "decayed_previous" and out.deadline_missed
    assert any("deadline passed" in a for a in out.attempts)
    assert time.perf_counter() - start < 0.03 + 0.05  # one late call, nothing more


def test_deadline_and_limits():
    d = Deadline(0.5)
    assert 0.0 < d.remaining() <= 0.5 and not d.expired()
    assert Deadline(None).budget == np.inf
    with pytest.raises(InputError, match="deadline"):
        Deadline(-1.0)
    assert backend_limits("daqp", 0.01) == {"time_limit": 0.01}
    assert backend_limits("cascade:highs", 0.02) == {"time_limit": 0.02}
    assert backend_limits("cascade:quadprog", 0.02) == {}
    assert backend_limits("daqp", None) == {}


def test_time_limits_reach_the_back_ends():
    """DAQP and HiGHS accept the limits (a too-small budget is a failure, not a hang)."""
    problem = _problem(8)
    for solver in ("daqp", "cascade:highs", "cascade:osqp", "cascade:clarabel"):
        out = SafeSolver(solver, deadline=0.05, alternate=None).solve(problem)
        assert out.stage == "primary", (solver, out.attempts)


def test_saturation_reports_the_clip():
    lo, hi = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    s = saturate(np.array([0.5, 1.5]), lo, hi)
    assert s.x.tolist() == [0.5, 1.0] and s.clipped == 0.5 and s.flagged
    s = saturate(np.array([0.5, 1.0 + 1e-12]), lo, hi)
    assert s.x[1] == 1.0 and not s.flagged


def test_verify_rejects_untruthful_statuses():
    problem = _problem(9)
    result = SafeSolver("daqp").primary.solve_problem(problem)
    tol = 1e-9 * problem.hard_scale
    assert verify_solution(problem, result, tol).ok
    result.status = Status.BACKEND_ERROR
    assert verify_solution(problem, result, tol).reason == "not_a_solution"
    result.status = Status.OPTIMAL
    result.x = result.x + 1.0
    assert verify_solution(problem, result, tol).reason in ("box_violated", "hard_rows_violated")
    result.x = np.zeros(problem.n + 1)
    assert verify_solution(problem, result, tol).reason == "wrong_shape"


def test_alternates_and_construction_errors():
    assert default_alternate("daqp") == "cascade:quadprog"
    assert default_alternate("cascade:proxqp") == "daqp"
    assert default_alternate("cascade:daqp", cascade_only=True) == "cascade:quadprog"
    assert default_alternate("cascade:quadprog", cascade_only=True) == "cascade:proxqp"
    with pytest.raises(UnknownSolverError):
        SafeSolver("daqp", alternate="gurobi")
    with pytest.raises(InputError, match="decay"):
        SafeSolver("daqp", decay=1.0)
    with pytest.raises(InputError, match="max_fallbacks"):
        SafeSolver("daqp", max_fallbacks=0)
    assert set(STAGES) >= DEGRADED_STAGES


def test_deadline_bounds_a_slow_cascade():
    """ProxQP's cascade needed ~18 s on this badly scaled regression problem (gain 1e9) without
    limits; with a 50 ms deadline the step ends within one QP of the deadline, flagged: either
    late but verified (used), or degraded with the solver stages skipped."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from regressions.corpus import HERE, load_problem

    problem, _ = load_problem(HERE / "ee_gain_1e9_no_vehicle_bound.npz")
    safe = SafeSolver("cascade:proxqp", deadline=0.05)
    start = time.perf_counter()
    out = safe.solve(problem)
    assert time.perf_counter() - start < 3.0
    assert out.deadline_missed
    assert out.stage == "primary" or any("deadline passed" in a for a in out.attempts)
    assert _safe(problem, out.x, 1e-9 * problem.hard_scale).ok
