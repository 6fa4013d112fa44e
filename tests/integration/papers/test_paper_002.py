"""Nenchev and Tsumaki: SC natural motion through the extended-arm singularity.

Claims of Nenchev and Tsumaki, "Redundancy resolution based on the singularity-consistent
method", Sections 3 and 4, on the bundled scenarios ``paper002_line_constant_arm_angle`` (run 1
as printed, b_ep = 1), ``paper002_line_paper_order`` (run 1 with b_ep = -1, the order of events
the text describes) and ``paper002_line_self_motion`` (run 2, b_sm = 1).
See docs/papers/002_nenchev.md.
"""

import numpy as np
import pytest

from tests.support.paper_scenarios import scheme_options, variant
from uvms_qp.analytic import singularity_crossings
from uvms_qp.schemes import NenchevSelfMotion
from uvms_qp.sim.comparison import compare
from uvms_qp.sim.runner import simulate

REACH = 2.0  # d3 + d5 [m]
#: First crossing of run 1 [s] ("after approx. 1 s"); natural motion repeats it every 2.16 s.
FIRST = 1.079
#: Tolerance on crossing times [s].
TOL = 0.1


@pytest.fixture(scope="module")
def run1():
    return compare("paper002_line_constant_arm_angle")


@pytest.fixture(scope="module")
def paper_order():
    return compare("paper002_line_paper_order")


@pytest.fixture(scope="module")
def run2():
    return compare("paper002_line_self_motion")


def _sc(comparison):
    return next(r for r in comparison.runs if r.name != "hqp")


def _crossings(run):
    return singularity_crossings(run.result.joints, run.result.time_states)


def _check_crossing(run):
    r = run.result
    q4 = r.joints[:, 3]
    crossings = np.flatnonzero(np.diff(np.sign(q4)) != 0)
    assert crossings.size >= 1, "q4 never changes sign: no pass through the singularity"
    k = int(crossings[0])
    # at the crossing the arm is fully extended and the end point reverses along the line
    assert abs(np.linalg.norm(r.ee_position[k]) - REACH) < 1e-2
    rate = run.info["path_rate"]
    assert rate[max(k - 20, 0)] * rate[min(k + 20, rate.size - 1)] < 0.0
    return float(r.time_states[k])


def test_paper_order_crosses_extended_shoulder_extended_at_1_3_5_s(paper_order):
    """The text: extended arm "after approx. 1 s", then the shoulder (x = 0), then the extended
    arm on the opposite side: measured at 1.079, 3.237 and 5.397 s."""
    sc = _sc(paper_order)
    events = _crossings(sc)
    assert [kind for _, kind in events] == ["extended", "shoulder", "extended"]
    for (t, _), expected in zip(events, (FIRST, 3 * FIRST, 5 * FIRST), strict=True):
        assert abs(t - expected) < TOL
    x = sc.result.ee_position[:, 0]
    # first at the +x boundary, then at the -x boundary (|x| = sqrt(3) m at z = 1 m)
    k1, k3 = (round(t / sc.result.dt) for t in (events[0][0], events[2][0]))
    assert x[k1] == pytest.approx(np.sqrt(3.0), abs=0.01)
    assert x[k3] == pytest.approx(-np.sqrt(3.0), abs=0.01)


def test_printed_sign_crosses_in_the_reverse_order(run1):
    """b_ep = +1 with the printed fields (f_ep5 = S4 = -1 at the start): shoulder first."""
    events = _crossings(_sc(run1))
    assert [kind for _, kind in events] == ["shoulder", "extended", "shoulder"]
    for (t, _), expected in zip(events, (FIRST, 3 * FIRST, 5 * FIRST), strict=True):
        assert abs(t - expected) < TOL


def test_paper_order_file_sets_only_the_end_point_sign():
    assert scheme_options("paper002_line_paper_order") == {"nenchev_sc": {"b_ep": -1.0}}


def test_sc_runs_report_no_tool_error(run1, paper_order, run2):
    """Natural motion follows no time trajectory: the table has no tool error for it, but the
    scheme records the wrist's distance from its line."""
    for comparison in (run1, paper_order, run2):
        sc = _sc(comparison)
        assert "ee_error_max" not in sc.metrics
        assert "ee_error_max" in comparison.run("hqp").metrics
        assert sc.info["line_deviation"].max() < 1e-2
        cells = dict((key, texts) for key, _, texts in comparison.cells())
        assert cells["ee_error_max"][comparison.runs.index(sc)] == "-"


@pytest.mark.parametrize("which", ["run1", "paper_order", "run2"])
def test_sc_passes_the_extended_arm_singularity_with_bounded_rates(which, request):
    sc = _sc(request.getfixturevalue(which))
    t_cross = _check_crossing(sc)
    assert 0.5 < t_cross < 4.0
    assert sc.metrics["joint_rate_max"] < 3.0
    assert sc.metrics["nan_steps"] == 0


@pytest.mark.parametrize("which", ["run1", "paper_order", "run2"])
def test_fields_have_their_structural_zeros_everywhere(which, request):
    sc = _sc(request.getfixturevalue(which))
    assert np.abs(sc.info["f_sm4"]).max() < 1e-12
    assert np.abs(sc.info["f_sm5"]).max() < 1e-12
    assert np.abs(sc.info["f_ep3"]).max() < 1e-12
    assert np.abs(sc.info["f_ep5"] - sc.info["sin_q4"]).max() < 1e-9


@pytest.mark.parametrize("which", ["run1", "paper_order", "run2"])
def test_end_point_stays_on_the_line(which, request):
    r = _sc(request.getfixturevalue(which)).result
    deviation = np.abs(r.ee_position[:, 1:] - r.ee_position[0, 1:])
    assert deviation.max() < 1e-2  # explicit Euler drift only (no feedback in natural motion)


@pytest.mark.parametrize("which", ["run1", "paper_order"])
def test_run1_keeps_the_arm_angle_and_crosses_the_shoulder_singularity(which, request):
    r = _sc(request.getfixturevalue(which)).result
    assert np.abs(r.joints[:, 2]).max() < 1e-12
    x = r.ee_position[:, 0]
    assert x.min() < 0.0 < x.max()


def test_run2_moves_the_arm_plane(run2):
    q3 = _sc(run2).result.joints[:, 2]
    assert q3.max() - q3.min() > 0.5


def test_run2_with_the_paper_order_sign_crosses_the_extended_arm_smoothly():
    """The convention of ``paper002_line_paper_order`` (both fields negated: b_ep = b_sm = -1)
    applied to run 2 still crosses the extended-arm singularity with bounded rates (at 1.41 s);
    negating b_ep alone would drive the self-motion field into its 1/c pole."""
    scenario = variant("paper002_line_self_motion", duration=3.0)
    scheme = NenchevSelfMotion(b_ep=-1.0, b_sm=-1.0).bind(scenario.model, scenario.dt)
    r = simulate(scenario, scheme, scheme_name=scheme.name)
    events = singularity_crossings(r.joints, r.time_states)
    assert [kind for _, kind in events] == ["extended"]
    assert abs(events[0][0] - 1.41) < TOL
    assert np.abs(r.zeta).max() < 2.0


@pytest.mark.parametrize("which", ["run1", "paper_order", "run2"])
def test_hqp_keeps_its_rate_bounds_and_stops_at_the_boundary(which, request):
    hqp = request.getfixturevalue(which).run("hqp")
    assert hqp.metrics["bound_violation_max"] <= 1e-7
    assert hqp.metrics["joint_rate_max"] <= 2.0 + 1e-9
    # the line leaves the workspace: a tracking controller cannot reverse like the SC motion
    assert hqp.metrics["ee_error_max"] > 0.1
