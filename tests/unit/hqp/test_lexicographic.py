"""Lexicographic optimality with active bounds, inequality levels and hard rows.

On seeded random problems, each level's weighted residual must match an independent reference
(a different algorithm: the cascade for DAQP's native hierarchy, DAQP's native hierarchy for every
cascade) to 1e-6 relative to ``max(1, residual)``, and the hard box and rows must hold to 1e-9.
A back-end "fails" on a problem when it reports a non-ok status, breaks a hard row, or disagrees.
Rows have unit norm and unit weight so that DAQP's row normalisation does not change the
semantics (see docs/solver.md and tests/unit/hqp/test_api.py for weighted rows).
"""

import numpy as np
import pytest

from uvms_qp.hqp import HierarchySolver, available_solvers, normalize_problem

N_PROBLEMS = 1000
N_SLOW = 200
#: back-ends that must never fail on these problems (the issue's promise)
MUST_PASS = ("daqp", "cascade:quadprog", "cascade:proxqp", "cascade:piqp")
SLOW = {"cascade:clarabel", "cascade:highs", "cascade:osqp"}
#: promises not kept yet, with the measured counts on these 1000 problems (see docs/solver.md)
KNOWN_SHORTFALLS: dict[str, str] = {}
#: sweep problems that once broke a back-end (index: what happened), replayed on every cascade
REGRESSIONS = {
    425: "cascade:highs: level 1 residual off by 8.8e-6 with an ok status (margin 1e-8)",
    706: "cascade:proxqp: 1e-9-thin feasible set reported primal infeasible (backend_error)",
    521: "cascade:osqp: thin slab of nearly parallel frozen rows; the rescue cycled",
    543: "cascade:osqp: thin slab, working constraints 1e-9 away from tight",
    98: "cascade:osqp: level 0 failed, y = 0 outside the box (rescue from a hard vertex)",
}


def with_shortfalls(names):
    return [pytest.param(n, marks=pytest.mark.xfail(reason=KNOWN_SHORTFALLS[n], strict=False))
            if n in KNOWN_SHORTFALLS else n for n in names]


def unit_rows(rng, m, n):
    A = rng.standard_normal((m, n))
    return A / np.linalg.norm(A, axis=1, keepdims=True)


def random_mixed_problem(rng):
    """Box (often tight, some free variables), optional hard rows, 1-5 mixed levels."""
    levels, lower, upper, hard = random_mixed_inputs(rng)
    return normalize_problem(levels, lower, upper, None, hard)


def random_mixed_inputs(rng):
    """The user-facing inputs ``(levels, lower, upper, hard)`` of :func:`random_mixed_problem`."""
    n = int(rng.integers(3, 13))
    x0 = rng.uniform(-1.0, 1.0, n)  # a point that satisfies every hard constraint
    width = rng.uniform(0.05, 1.0, n)
    lower = x0 - width * rng.uniform(0.0, 1.0, n)
    upper = x0 + width * rng.uniform(0.0, 1.0, n)
    free = rng.uniform(size=n) < 0.15
    lower[free] = -np.inf
    upper[free & (rng.uniform(size=n) < 0.5)] = np.inf
    hard = []
    if rng.uniform() < 0.4:
        mh = int(rng.integers(1, max(2, n // 2)))
        Ah = unit_rows(rng, mh, n)
        y0 = Ah @ x0
        lo, hi = y0 - rng.uniform(0.0, 0.5, mh), y0 + rng.uniform(0.0, 0.5, mh)
        lo[rng.uniform(size=mh) < 0.3] = -np.inf
        hard.append((Ah, lo, hi))
    levels = []
    for _ in range(int(rng.integers(1, 6))):
        m = int(rng.integers(1, n + 1))
        A = unit_rows(rng, m, n)
        kind = rng.uniform()
        if kind < 0.4:
            levels.append([(A, 2.0 * rng.standard_normal(m))])
        elif kind < 0.8:
            c = 2.0 * rng.standard_normal(m)
            lo, hi = c - rng.uniform(0.0, 1.0, m), c + rng.uniform(0.0, 1.0, m)
            lo[rng.uniform(size=m) < 0.3] = -np.inf
            levels.append([(A, lo, hi)])
        else:
            k = max(1, m // 2)
            level = [(A[:k], 2.0 * rng.standard_normal(k))]
            if m > k:
                c = 2.0 * rng.standard_normal(m - k)
                level.append((A[k:], c - 0.3, c + 0.3))
            levels.append(level)
    return levels, lower, upper, hard


@pytest.fixture(scope="module")
def sweep():
    rng = np.random.default_rng(7)
    problems = [random_mixed_problem(rng) for _ in range(N_PROBLEMS)]
    daqp = HierarchySolver("daqp")
    cascade = HierarchySolver("cascade:quadprog")
    return problems, [daqp.solve_problem(p) for p in problems], [
        cascade.solve_problem(p) for p in problems]


def count_failures(name, sweep, count, indices=None):
    problems, daqp_results, cascade_results = sweep
    solver = HierarchySolver(name)
    failures = []
    for i in range(count) if indices is None else indices:
        result = solver.solve_problem(problems[i])
        ref = cascade_results[i] if name == "daqp" else daqp_results[i]
        gap = max(abs(r - q) / max(1.0, q)
                  for r, q in zip(result.level_residuals, ref.level_residuals, strict=True))
        assert np.all(np.isfinite(result.x))
        if ill_posed(result) and gap <= 1e-6 and result.hard_violation <= 1e-9:
            continue  # the right answer, honestly not called optimal: a property of the problem
        if not result.ok:
            # a failure must be truthful: never a success status with a broken hard row
            failures.append((i, str(result.status), result.message))
        elif result.hard_violation > 1e-9 or gap > 1e-6:
            failures.append((i, "wrong", gap, result.hard_violation))
    return failures


def ill_posed(result):
    """An ``unproven`` answer whose first unproven level the certificate found ill-posed."""
    cert = result.certificate
    return result.status.value == "unproven" and cert is not None and cert.ill_posed


def test_ill_posed_answers_are_a_property_of_the_problem(sweep):
    """The few levels whose optimum a 1e-9 change of the levels above moves by more than the
    tolerance are the same for the two references (a different algorithm each), rare, and the
    answers still agree: only the claim of optimality is withheld."""
    _, daqp_results, cascade_results = sweep
    on_daqp = {i for i, r in enumerate(daqp_results) if ill_posed(r)}
    on_cascade = {i for i, r in enumerate(cascade_results) if ill_posed(r)}
    assert len(on_daqp | on_cascade) <= 0.005 * N_PROBLEMS
    assert on_daqp & on_cascade  # the same problems (one is ill-posed on one side only)
    for i in on_daqp | on_cascade:
        got, ref = daqp_results[i], cascade_results[i]
        assert max(abs(r - q) / max(1.0, q) for r, q in zip(
            got.level_residuals, ref.level_residuals, strict=True)) <= 1e-6


def test_problems_exercise_bounds_and_infeasible_levels(sweep):
    _, daqp_results, _ = sweep
    active = sum(bool(r.active_lower.any() or r.active_upper.any()) for r in daqp_results)
    unmet = sum(r.infeasible_level is not None for r in daqp_results)
    assert active > 0.9 * N_PROBLEMS
    assert unmet > 0.5 * N_PROBLEMS


@pytest.mark.parametrize(
    "name", with_shortfalls([n for n in MUST_PASS if n in available_solvers()]))
def test_no_failure(name, sweep):
    failures = count_failures(name, sweep, N_PROBLEMS)
    assert not failures, f"{name}: {len(failures)} failures: {failures[:5]}"


@pytest.mark.parametrize("name", with_shortfalls(
    [n for n in available_solvers() if n.startswith("cascade:") and n not in MUST_PASS]))
def test_other_cascades_never_wrong(name, sweep):
    """Other back-ends may fail, but only with a truthful status, never with a wrong x.

    Since the inexact back-ends are certified (KKT) and failed QPs rescued, they measure 0
    failures on the whole sweep too (docs/solver.md); the last assertion guards that.
    """
    count = N_SLOW if name in SLOW else N_PROBLEMS
    failures = count_failures(name, sweep, count)
    wrong = [f for f in failures if f[1] == "wrong"]
    assert not wrong, f"{name}: {len(wrong)} wrong answers with an ok status: {wrong[:5]}"
    assert not failures, f"{name}: {len(failures)} failures: {failures[:5]}"


@pytest.mark.parametrize("name", [n for n in available_solvers() if n.startswith("cascade:")])
def test_regression_problems(name, sweep):
    """Problems that once failed (or, worse, were wrong with an ok status) now solve exactly."""
    failures = count_failures(name, sweep, 0, indices=sorted(REGRESSIONS))
    assert not failures, f"{name}: {failures} ({[REGRESSIONS[f[0]] for f in failures]})"


@pytest.mark.skipif("cascade:highs" not in available_solvers(), reason="highspy not installed")
def test_highs_time_limit_is_set_and_an_exhausted_limit_stays_truthful(sweep):
    """HiGHS runs under a time limit; when it stops early, the answer is rescued or refused."""
    from uvms_qp.hqp.registry import get_spec

    limit = get_spec("cascade:highs").settings["time_limit"]
    assert 0.0 < limit <= 1.0  # [s] per QP
    problems, daqp_results, _ = sweep
    solver = HierarchySolver("cascade:highs", options={"time_limit": 0.0})
    rescued = 0
    for i in range(30):
        result = solver.solve_problem(problems[i])
        rescued += result.info["rescued_qps"] if result.ok else 0
        if result.ok:
            gap = max(abs(r - q) / max(1.0, q) for r, q in zip(
                result.level_residuals, daqp_results[i].level_residuals, strict=True))
            assert gap <= 1e-6 and result.hard_violation <= 1e-9, (i, gap)
    assert rescued > 0  # the limit did stop HiGHS, and the certified rescue answered
