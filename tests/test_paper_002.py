"""Paper 002 (Nenchev, Tsumaki): SC natural motion through the extended-arm singularity.

Claims of ``002_1230892968c9c95c.txt``, Sections 3 and 4, on the bundled scenarios
``paper002_line_constant_arm_angle`` (b_sm = 0) and ``paper002_line_self_motion`` (b_sm = 1).
See docs/papers/002_nenchev.md.
"""

import numpy as np
import pytest

from uvms_qp.sim.comparison import compare

REACH = 2.0  # d3 + d5 [m]


@pytest.fixture(scope="module")
def run1():
    return compare("paper002_line_constant_arm_angle")


@pytest.fixture(scope="module")
def run2():
    return compare("paper002_line_self_motion")


def _sc(comparison):
    return next(r for r in comparison.runs if r.name != "hqp")


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


@pytest.mark.parametrize("which", ["run1", "run2"])
def test_sc_passes_the_extended_arm_singularity_with_bounded_rates(which, request):
    sc = _sc(request.getfixturevalue(which))
    t_cross = _check_crossing(sc)
    assert 0.5 < t_cross < 4.0
    assert sc.metrics["joint_rate_max"] < 3.0
    assert sc.metrics["nan_steps"] == 0


@pytest.mark.parametrize("which", ["run1", "run2"])
def test_fields_have_their_structural_zeros_everywhere(which, request):
    sc = _sc(request.getfixturevalue(which))
    assert np.abs(sc.info["f_sm4"]).max() < 1e-12
    assert np.abs(sc.info["f_sm5"]).max() < 1e-12
    assert np.abs(sc.info["f_ep3"]).max() < 1e-12
    assert np.abs(sc.info["f_ep5"] - sc.info["sin_q4"]).max() < 1e-9


@pytest.mark.parametrize("which", ["run1", "run2"])
def test_end_point_stays_on_the_line(which, request):
    r = _sc(request.getfixturevalue(which)).result
    deviation = np.abs(r.ee_position[:, 1:] - r.ee_position[0, 1:])
    assert deviation.max() < 1e-2  # explicit Euler drift only (no feedback in natural motion)


def test_run1_keeps_the_arm_angle_and_crosses_the_shoulder_singularity(run1):
    r = _sc(run1).result
    assert np.abs(r.joints[:, 2]).max() < 1e-12
    x = r.ee_position[:, 0]
    assert x.min() < 0.0 < x.max()


def test_run2_moves_the_arm_plane(run2):
    q3 = _sc(run2).result.joints[:, 2]
    assert q3.max() - q3.min() > 0.5


@pytest.mark.parametrize("which", ["run1", "run2"])
def test_hqp_keeps_its_rate_bounds_and_stops_at_the_boundary(which, request):
    hqp = request.getfixturevalue(which).run("hqp")
    assert hqp.metrics["bound_violation_max"] <= 1e-7
    assert hqp.metrics["joint_rate_max"] <= 2.0 + 1e-9
    # the line leaves the workspace: a tracking controller cannot reverse like the SC motion
    assert hqp.metrics["ee_error_max"] > 0.1
