"""Paper 003 (Wang et al.): fuzzy weighted gradient projection vs pseudoinverse, with a payload.

Claims of ``003_229789978cc4b235.txt``, Simulation results, on the bundled scenarios
``paper003_case1_no_payload``, ``paper003_case2_pseudoinverse`` and ``paper003_case3_payload``.
See docs/papers/003_wang.md (the fuzzy rule base is a reconstruction).
"""

import numpy as np
import pytest

from uvms_qp.sim.comparison import compare

Q3_LIMIT = np.radians(110.0)


@pytest.fixture(scope="module")
def case1():
    return compare("paper003_case1_no_payload")


@pytest.fixture(scope="module")
def case2():
    return compare("paper003_case2_pseudoinverse", ["wang_pseudoinverse"])


@pytest.fixture(scope="module")
def case3():
    return compare("paper003_case3_payload")


def _displacement(run):
    p = run.result.vehicle_position
    return np.linalg.norm(p - p[0], axis=1)


def _at(run, t):
    return float(_displacement(run)[round(t / run.result.dt)])


def _first_move(run, distance=0.01):
    moved = np.flatnonzero(_displacement(run) > distance)
    return float(run.result.time_states[moved[0]]) if moved.size else float("inf")


def test_every_case_tracks_the_tool(case1, case2, case3):
    for comparison in (case1, case2, case3):
        for run in comparison.runs:
            assert run.metrics["ee_error_max"] < 1e-3, (comparison.scenario, run.name)


def test_case1_vehicle_nearly_still_until_the_arm_nears_singularity(case1):
    run = case1.run("wang_fuzzy_gradient_projection")
    assert _at(run, 8.0) < 0.01
    assert _first_move(run) > 8.0
    # it does move later, when the manipulability has dropped
    assert run.metrics["vehicle_displacement_max"] > 0.1
    ratio = run.info["manipulability_ratio"]
    k_move = round(_first_move(run) / run.result.dt)
    assert ratio[k_move] < ratio[0]


def test_case2_moves_the_vehicle_from_the_start_and_breaks_joint_3_limit(case1, case2):
    pinv = case2.run("wang_pseudoinverse")
    fuzzy = case1.run("wang_fuzzy_gradient_projection")
    assert _at(pinv, 1.0) > 10.0 * _at(fuzzy, 1.0)
    assert _first_move(pinv) < 3.0
    assert pinv.result.joints[:, 2].max() > Q3_LIMIT
    assert pinv.metrics["joint_limit_violation_max"] > 0.01


def test_case3_lowers_the_payload_lever_against_case1(case1, case3):
    loaded = case3.run("wang_fuzzy_gradient_projection").metrics
    empty = case1.run("wang_fuzzy_gradient_projection").metrics
    # the payload moment is F times this lever arm; measured 0.7205 m vs 0.7343 m (-1.9 %)
    assert loaded["tool_base_radius_mean"] < empty["tool_base_radius_mean"]
    assert loaded["tool_base_radius_max"] < empty["tool_base_radius_max"]


@pytest.mark.parametrize("which", ["case1", "case3"])
def test_hqp_never_leaves_the_joint_limits(which, request):
    hqp = request.getfixturevalue(which).run("hqp")
    assert hqp.metrics["joint_limit_violation_max"] == 0.0
    assert hqp.metrics["bound_violation_max"] <= 1e-7


def test_hqp_payload_moment_no_higher_than_case3(case3):
    hqp = case3.run("hqp").metrics
    scheme = case3.run("wang_fuzzy_gradient_projection").metrics
    assert hqp["payload_moment_max"] <= scheme["payload_moment_max"]
