"""The per-level optimality certificate and its repair, judged by the independent oracle.

``certify`` must agree with the oracle (Clarabel on each level's frozen set, every witness
verified in NumPy): a level it certifies cannot be improved by more than 1e-6 (relative to the
level's scale), a level the oracle improves by more than 1e-4 is never certified, and every
witness it returns is a verified better point.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.oracle.lexicographic import Oracle
from uvms_qp.bench.problems import family
from uvms_qp.hqp import HierarchySolver, normalize_problem
from uvms_qp.hqp.backends.daqp_binding import open_daqp
from uvms_qp.hqp.certificate import CERTIFIED, IMPROVABLE, MET, Certifier, certify, repair, slacks
from uvms_qp.hqp.measure import measure

#: families where the lexicographic optimum is well posed (a 1e-9 change of a higher level
#: cannot buy a lower one more than 1e-6), so certificate and oracle must agree exactly
WELL_POSED = ("well", "repeated", "no_box_repeat")
SOLVERS = ("daqp", "cascade:quadprog", "cascade:proxqp")


def arrays(problem):
    """The stacked layout ``(A, lo, hi, n, mh, sizes, w)`` the oracle reads."""
    return (problem.A, problem.lo, problem.hi, problem.n, problem.mh, problem.sizes, problem.w)


def judge(problem, x):
    cert = certify(problem, x, exact=True, least_distance=open_daqp)
    better = [c.better for c in cert.levels if c.better is not None]
    return cert, Oracle(*arrays(problem)).judge(x, candidates=better)


def assert_agree(cert, judged, loose=1e-4):
    for c, j in zip(cert.levels, judged, strict=True):
        if c.ok:
            assert j.improvement <= 1e-6 * j.scale, (c, j.improvement)
        if j.improvement > loose * j.scale:
            assert not c.ok, (c, j.improvement)
        if c.verdict == IMPROVABLE:
            # the certificate's witness is a verified point of the frozen set, as good as claimed
            assert j.best <= c.residual - c.improvement + 1e-9 * j.scale


def test_a_lower_level_repeating_a_higher_row_cannot_hide_a_degraded_top_level():
    a = np.array([[1.0, 2.0]])
    problem = normalize_problem([[(a, [10.0])], [(a, [1.0])]])
    x = np.array([0.0, 4.0])  # what five cascades returned: level 0 at residual 2
    cert, judged = judge(problem, x)
    assert cert.levels[0].verdict == IMPROVABLE
    assert cert.levels[0].improvement == pytest.approx(2.0, abs=1e-9)
    assert_agree(cert, judged)
    fixed = repair(problem, x, certifier=Certifier(open_daqp))
    assert fixed.repaired and fixed.certificate.ok
    assert fixed.certificate.levels[0].residual < 1e-9
    assert fixed.certificate.levels[1].residual == pytest.approx(9.0, abs=1e-9)


def test_the_exact_answer_is_certified_and_a_perturbed_one_is_not():
    a = np.array([[1.0, 2.0]])
    problem = normalize_problem([[(a, [10.0])], [(a, [1.0])]])
    cert = certify(problem, np.array([2.0, 4.0]), least_distance=open_daqp)
    assert [c.verdict for c in cert.levels] == [MET, CERTIFIED]
    assert not certify(problem, np.array([2.0, 3.9]), least_distance=open_daqp).ok


@pytest.mark.parametrize("fam", WELL_POSED)
@pytest.mark.parametrize("solver", SOLVERS)
def test_certificate_agrees_with_the_oracle_on_seeded_families(fam, solver):
    plain = HierarchySolver(solver)
    plain.certify, plain.repair = None, False  # the back-end's own answers, unquestioned
    for p in family(fam, 25, seed=100):
        problem = normalize_problem(p.levels_rows(), p.lower, p.upper, None, p.hard_rows())
        res = plain.solve_problem(problem)
        if res.status.value != "optimal":
            continue
        assert_agree(*judge(problem, res.x))


@pytest.mark.parametrize("fam", WELL_POSED)
def test_repair_reaches_a_certified_point_from_a_perturbed_answer(fam):
    rng = np.random.default_rng(7)
    for p in family(fam, 10, seed=300):
        problem = normalize_problem(p.levels_rows(), p.lower, p.upper)
        res = HierarchySolver("cascade:daqp").solve_problem(problem)
        x = np.clip(res.x + rng.normal(scale=0.05, size=p.n), p.lower, p.upper)
        fixed = repair(problem, x, certifier=Certifier(open_daqp))
        if not fixed.repaired:
            assert fixed.certificate.ok or "failed" in fixed.message or (
                fixed.certificate.ill_posed)
            continue
        assert fixed.certificate.ok
        oracle = Oracle(*arrays(problem))
        judged = oracle.judge(fixed.x)
        # nothing above the first failing level got worse, and the result is optimal
        first = certify(problem, x, least_distance=open_daqp).first_failure
        for j, k in zip(judged, range(len(judged)), strict=True):
            assert j.improvement <= 1e-6 * j.scale
            if k < first:
                assert j.residual <= oracle.residual(k, x) + 1e-9


@settings(max_examples=60)
@given(seed=st.integers(0, 10_000), shift=st.floats(0.0, 0.5))
def test_certificate_agrees_with_the_oracle_on_shifted_answers(seed, shift):
    rng = np.random.default_rng(seed)
    p = family("well", 1, seed)[0]
    problem = normalize_problem(p.levels_rows(), p.lower, p.upper)
    res = HierarchySolver("cascade:daqp").solve_problem(problem)
    x = np.clip(res.x + shift * rng.normal(size=p.n), p.lower, p.upper)
    assert_agree(*judge(problem, x))


def test_a_point_outside_the_box_is_not_certified():
    a = np.array([[1.0, 0.0]])
    problem = normalize_problem([[(a, [0.5])]], lower=[-1, -1], upper=[1, 1])
    cert = certify(problem, np.array([1.5, 0.0]), least_distance=open_daqp)
    assert not cert.inside and not cert.ok


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_non_finite_point_is_not_certified_with_or_without_the_measurement(bad):
    """The certificate reads x's finiteness from a finite hard violation of its slacks; the
    slacks of a non-finite x carry it (inf or NaN on the box rows), so no path certifies it."""
    a = np.array([[1.0, 1.0]])
    for box in (1.0, np.inf):
        problem = normalize_problem([[(a, [5.0])]], lower=[-box, -box], upper=[box, box])
        x = np.array([bad, 0.0])
        with np.errstate(all="ignore"):
            s = slacks(problem, x)
            measured = measure(problem, x)[0]
            hv = float(np.abs(s[:problem.n]).max())
            assert not hv < np.inf
            certifier = Certifier(open_daqp)
            for cert in (certifier(problem, x), certifier(problem, x, s),
                         certifier(problem, x, measured, None, hv)):
                assert not cert.ok and not cert.inside
