"""The fallback ladder on plain problems: every fault gives a safe command and a named stage.

Faults are injected into the back-end, or below the DAQP back-end at its C binding
(uvms_qp.testing.faults), so the whole path is exercised: back-end -> measurement -> ladder ->
final clip. Deadlines are tested with a fake clock, never with the machine's speed.
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.errors import InputError, NoSolutionFound, UnknownSolverError
from uvms_qp.hqp import HierarchySolver, Status, hard_violation, normalize_problem
from uvms_qp.hqp.measure import clip_to_box
from uvms_qp.safety import (
    DEGRADED_STAGES,
    STAGES,
    SafeSolver,
    backend_limits,
    default_alternate,
    fallback_summary,
)
from uvms_qp.testing.faults import Fault, inject

BOX = 0.3
#: faults a measurement tells from an answer (the feasible wrong x, which only the certificate
#: tells, has its own test)
DETECTABLE = [f for f in Fault if f not in (Fault.SLEEP, Fault.FEASIBLE_WRONG)]


class FakeClock:
    """A clock that advances ``step`` seconds every time it is read, and on :meth:`advance`."""

    def __init__(self, step: float = 0.0) -> None:
        self.now, self.step = 0.0, step

    def __call__(self) -> float:
        self.now += self.step
        return self.now

    def advance(self, seconds: float) -> None:
        self.now += seconds


def _problem(seed: int = 0, n: int = 6, hard_rows: bool = True, box: float = BOX):
    rng = np.random.default_rng(seed)
    A1 = rng.normal(size=(3, n))
    A2 = rng.normal(size=(2, n))
    hard = [(rng.normal(size=(1, n)), [-0.2], [0.2])] if hard_rows else None
    return normalize_problem([[(A1, rng.normal(size=3))], [(A2, rng.normal(size=2))]],
                             np.full(n, -box), np.full(n, box), hard=hard)


def _safe(problem, x, tol=1e-9):
    """Finite, inside the box exactly, hard rows within ``tol``."""
    hard = problem.hard
    return bool(np.all(np.isfinite(x)) and np.all(x >= problem.lower)
                and np.all(x <= problem.upper)
                and hard_violation(x, problem.lower, problem.upper, hard.A, hard.lower,
                                   hard.upper) <= tol)


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
@pytest.mark.parametrize("fault", [*DETECTABLE, Fault.SLEEP])
def test_every_fault_gives_a_verified_command_and_names_the_stage(solver, fault):
    problem = _problem(1)
    reference = SafeSolver(solver).solve(problem)
    assert reference.stage == "primary"
    clock = FakeClock()
    safe = SafeSolver(solver, deadline=0.1, clock=clock)
    injector = inject(safe, fault, count=1, sleep=0.15)
    injector.sleeper = clock.advance  # a SLEEP fault takes 0.15 s of the fake clock
    out = safe.solve(problem)
    assert injector.n_faults == 1
    assert _safe(problem, out.x)
    if fault is Fault.SLEEP:  # late: used as it is, and the miss is reported; no time was
        # left to prove its unmet level optimal, and the status says so
        assert out.stage == "primary" and out.deadline_missed
        assert out.result.status is Status.UNPROVEN and "deadline" in out.result.message
        assert np.allclose(out.x, reference.x, atol=1e-7)
        return
    else:
        assert out.stage == "cold_retry"
        assert out.attempts and out.attempts[0].startswith("primary:")
        assert np.allclose(out.x, reference.x, atol=1e-7)
    assert out.result.ok and out.result.status == reference.result.status


@pytest.mark.parametrize("fault", [*DETECTABLE, Fault.SLEEP])
def test_faults_below_the_daqp_back_end_give_a_verified_command(fault):
    """Faults of DAQP's C binding: the back-end's own rho_soft ladder or the safe ladder
    answers, truthfully; the next solve is the clean one."""
    problem = _problem(1)
    reference = SafeSolver("daqp").solve(problem)
    clock = FakeClock()
    safe = SafeSolver("daqp", clock=clock)
    injector = inject(safe, fault, at="binding", count=1, sleep=0.15)
    injector.sleeper = clock.advance
    out = safe.solve(problem)
    assert injector.n_faults == 1
    assert _safe(problem, out.x) and out.result.ok
    if fault in (Fault.RAISE_OWN, Fault.RAISE_FOREIGN, Fault.MEMORY):
        assert out.stage == "cold_retry" and "raised" in out.attempts[0]
    else:  # a claimed answer that fails the back-end's acceptance: its next rho_soft solves
        assert out.stage == "primary"
    assert np.allclose(out.x, reference.x, atol=1e-6)
    again = safe.solve(problem)
    assert again.stage == "primary" and np.allclose(again.x, reference.x, atol=1e-9)


def test_a_feasible_but_wrong_answer_is_caught_by_the_default_certificate():
    """A feasible but wrong x (DAQP faulted to return zero clipped into the box) is not believed:
    the certificate, asked by default, does not prove it, and the answer is the true optimum
    (repaired from the wrong one, and said so); believed only with the certificate off."""
    problem = _problem(2)
    truth = SafeSolver("cascade:quadprog").solve(problem).result.level_residuals
    safe = SafeSolver("daqp")
    injector = inject(safe, Fault.FEASIBLE_WRONG, count=1)
    out = safe.solve(problem)
    assert injector.n_faults == 1
    assert out.result.ok and out.result.level_residuals == pytest.approx(truth, abs=1e-6)
    assert "not proven optimal" in out.result.message and (
        out.result.info.get("repaired_from_level") is not None or out.stage != "primary")

    safe = SafeSolver("daqp")
    safe.primary.certify = None  # nothing else can tell a feasible wrong x from an optimum
    inject(safe, Fault.FEASIBLE_WRONG, count=1)
    believed = safe.solve(problem)
    assert believed.stage == "primary" and believed.result.ok
    assert believed.result.level_residuals != pytest.approx(truth, abs=1e-6)


@pytest.mark.parametrize("fault, needle", [
    (Fault.RAISE_OWN, "SolverError"), (Fault.RAISE_FOREIGN, "RuntimeError"),
    (Fault.MEMORY, "MemoryError"), (Fault.NONE, "returned no x"),
    (Fault.WRONG_LENGTH, "x of shape (7,), expected (6,)"),
    (Fault.NAN_SUCCESS, "non-finite x"), (Fault.BOUND_VIOLATION, ") violated by"),
    (Fault.WILD_FAILURE, "backend_error (injected failure"),
])
def test_attempt_log_says_what_went_wrong(fault, needle):
    safe = SafeSolver("daqp")
    inject(safe, fault, count=1)
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
    inject(safe, Fault.NAN_SUCCESS, count=times)
    got = []
    for _ in range(3):
        out = safe.solve(problem)
        assert _safe(problem, out.x)
        assert np.allclose(out.x, reference, atol=1e-6)
        got.append(out.stage)
    assert got == stages


def test_all_back_ends_down_decays_then_holds_zero_then_recovers():
    problem = _problem(4)
    safe = SafeSolver("daqp", max_fallbacks=3, decay=0.5)
    first = safe.solve(problem)
    primary = inject(safe, Fault.RAISE_FOREIGN)
    alternate = inject(safe.alternate, Fault.WILD_FAILURE)
    primary.armed = alternate.armed = True
    stages, xs = [], []
    for _ in range(6):
        out = safe.solve(problem)
        assert _safe(problem, out.x)
        assert out.result.status == Status.BACKEND_ERROR  # truthful: not a solve
        assert out.stage in DEGRADED_STAGES and out.stage in out.result.message
        stages.append(out.stage)
        xs.append(out.x)
    assert stages == ["decayed_previous"] * 3 + ["hold_zero"] * 3
    for k in range(3):
        assert np.allclose(xs[k], first.x * 0.5 ** (k + 1))
    assert not np.any(xs[3]) and not np.any(xs[5])
    # while holding zero the whole ladder is still tried: primary, cold retry, alternate
    calls = (primary.n_calls, alternate.n_calls)
    safe.solve(problem)
    assert primary.n_calls >= calls[0] + 2 and alternate.n_calls == calls[1] + 1
    primary.armed = False
    out = safe.solve(problem)
    assert out.stage == "primary" and safe.consecutive == 0
    assert safe.stage_counts["hold_zero"] == 4
    assert safe.status_counts["backend_error"] == 7
    assert "hold_zero: 4" in fallback_summary(safe.stage_counts)


def test_hold_zero_ends_through_the_alternate_when_the_primary_stays_down():
    """A primary that never solves (structurally unable) and an alternate down for a while:
    the run holds zero, then recovers through the alternate, not only through the primary."""
    problem = _problem(5)
    safe = SafeSolver("daqp", max_fallbacks=2, relax=False)
    safe.solve(problem)
    inject(safe, Fault.RAISE_FOREIGN).armed = True
    alternate = inject(safe.alternate, Fault.NAN_SUCCESS)
    alternate.armed = True
    stages = [safe.solve(problem).stage for _ in range(4)]
    assert stages == ["decayed_previous"] * 2 + ["hold_zero"] * 2
    alternate.armed = False
    stages = [safe.solve(problem).stage for _ in range(3)]
    assert stages == ["alternate"] * 3 and safe.consecutive == 0


def test_relaxed_stage_drops_the_lowest_level_and_reports_the_full_problem():
    problem = _problem(5)
    safe = SafeSolver("daqp", alternate=None)
    injector = inject(safe, Fault.NAN_SUCCESS, calls=[0, 1])  # primary + cold retry
    out = safe.solve(problem)
    assert injector.n_faults == 2
    assert out.stage == "relaxed" and out.relaxed_levels == 1
    assert len(out.result.level_residuals) == 2  # evaluated against the full problem
    assert "dropped" in out.result.message
    assert _safe(problem, out.x)


def test_strict_mode_raises_with_the_failed_result():
    safe = SafeSolver("daqp", strict=True)
    inject(safe, Fault.BOUND_VIOLATION).armed = True
    inject(safe.alternate, Fault.NAN_SUCCESS).armed = True
    with pytest.raises(NoSolutionFound, match="no verified solution") as info:
        safe.solve(_problem(6))
    assert info.value.result is not None
    assert info.value.result.status == Status.BACKEND_ERROR


def test_strict_mode_still_takes_the_non_degrading_stages():
    safe = SafeSolver("daqp", strict=True)
    inject(safe, Fault.RAISE_OWN, count=1)
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
    clock = FakeClock()
    safe = SafeSolver("daqp", deadline=0.01, clock=clock)
    safe.solve(problem)
    inject(safe, Fault.SLEEP, count=1, sleep=0.03).sleeper = clock.advance
    out = safe.solve(problem)
    assert out.stage == "primary" and out.deadline_missed  # late, verified: used
    # late *and* wrong: no more solver stages; the cheap stages answer
    clock.step = 0.02  # every clock read is 20 ms later: the answer comes past the deadline
    injector = inject(safe, Fault.NAN_SUCCESS, count=1)
    out = safe.solve(problem)
    assert injector.n_faults == 1 and injector.n_calls == 1  # one back-end call, nothing more
    assert out.stage == "decayed_previous" and out.deadline_missed
    assert any("deadline passed" in a for a in out.attempts)


def test_deadline_bounds_a_slow_cascade():
    """A cascade whose QPs each take 20 ms (fake clock) under a 50 ms deadline: the cascade
    starts no QP after it, the step ends flagged, degraded, inside the box."""
    problem = _problem(8)
    clock = FakeClock()
    safe = SafeSolver("cascade:quadprog", deadline=0.05, clock=clock)
    assert safe.solve(problem).stage == "primary"
    clock.step = 0.02
    out = safe.solve(problem)
    assert out.deadline_missed
    assert any("deadline passed" in a for a in out.attempts)
    assert out.stage in DEGRADED_STAGES
    assert _safe(problem, out.x, 1e-9 * problem.hard_scale)


def test_a_solver_stops_at_its_deadline_on_its_clock():
    """On a fake clock every read takes 20 ms. A cascade solve (several QPs) under a 50 ms
    deadline passes it, starts no further QP and says so; a plain solver has no deadline
    unless given one, and ``solve_hierarchy`` takes the same."""
    problem = _problem(8)
    solver = HierarchySolver("cascade:quadprog")
    assert solver.deadline == float("inf")
    solver.clock = FakeClock(0.02)
    assert solver.solve_problem(problem).ok
    solver.deadline = 0.05
    capped = solver.solve_problem(problem)
    assert capped.status is Status.BACKEND_ERROR and "deadline" in capped.message
    assert capped.info["deadline_passed"] and np.all(np.isfinite(capped.x))
    assert HierarchySolver("daqp", deadline=0.01).deadline == 0.01
    with pytest.raises(InputError, match="deadline"):
        HierarchySolver("daqp", deadline=-1.0)


def test_backend_limits():
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


def test_clip_reports_the_amount():
    lo, hi = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    x, amount = clip_to_box(np.array([0.5, 1.5]), lo, hi)
    assert x.tolist() == [0.5, 1.0] and amount == 0.5
    x, amount = clip_to_box(np.array([0.5, 1.0 + 1e-12]), lo, hi)
    assert x[1] == 1.0 and amount < 1e-11


def test_alternates_and_construction_errors():
    assert default_alternate("daqp") == "cascade:quadprog"
    assert default_alternate("cascade:proxqp") == "daqp"
    assert default_alternate("nullspace") == "daqp"
    assert default_alternate("cascade:daqp", cascade_only=True) == "cascade:quadprog"
    assert default_alternate("cascade:quadprog", cascade_only=True) == "cascade:proxqp"
    with pytest.raises(UnknownSolverError):
        SafeSolver("daqp", alternate="gurobi")
    with pytest.raises(InputError, match="decay"):
        SafeSolver("daqp", decay=1.0)
    with pytest.raises(InputError, match="max_fallbacks"):
        SafeSolver("daqp", max_fallbacks=0)
    assert set(STAGES) >= DEGRADED_STAGES


def test_a_perturbed_start_of_the_demo_is_answered_by_the_primary(tmp_path):
    # a sweep's run whose perturbed start and noisy pose make the certificate drop dependent
    # level rows (the reduced problem DAQP then solves tick after tick) while the
    # command-rate window moves: every step is the warm-started primary's, none a cold retry
    from tests.support.sweeps import TINY, write_sweep
    from uvms_qp.sweep.records import simulate_run
    from uvms_qp.sweep.sampling import run_seed
    from uvms_qp.sweep.spec import load_sweep

    spec = load_sweep(write_sweep(tmp_path, text=TINY.replace("duration = 0.25",
                                                              "duration = 1.0")))
    _, result = simulate_run(spec, run_seed(spec.seed, 3))
    counts = result.fallback_metrics()["stage_counts"]
    assert counts.get("cold_retry", 0) == 0 and counts.get("primary", 0) == 20, counts


def test_an_unproven_answer_is_kept_when_the_deadline_passes_in_the_last_solver_stage():
    """The primary's answer is safe but unproven (a near-singular level the repair cannot
    prove); the alternate then runs past the deadline. The step keeps the unproven answer (a
    solve of this problem, inside the hard set) instead of dropping to the zero command."""
    from uvms_qp.bench.problems import family

    p = family("near_singular", 1, seed=5)[0]
    problem = normalize_problem(p.levels_rows(), p.lower, p.upper, hard=p.hard_rows())
    clock = FakeClock()
    safe = SafeSolver("daqp", deadline=1.0, clock=clock)
    inject(safe.alternate, Fault.SLEEP, count=1, sleep=2.0).sleeper = clock.advance
    out = safe.solve(problem)
    stages = [(r.stage, r.verdict) for r in out.record]
    assert stages[0] == ("primary", "unproven")
    assert any(stage.startswith("alternate") for stage, _ in stages)
    assert out.deadline_missed
    assert out.stage == "primary" and out.result.status is Status.UNPROVEN, stages
    assert stages[-1] == ("primary", "kept")
    assert np.any(out.x != 0.0) and _safe(problem, out.x)
