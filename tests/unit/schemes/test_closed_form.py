"""Closed-form paper schemes: interface, validation and the invariants of their formulas."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_qp.analytic import end_point_field, self_motion_field
from uvms_qp.controller import StepResult
from uvms_qp.errors import ConfigError, InputError
from uvms_qp.hqp import Status
from uvms_qp.schemes import (
    SCHEME_TYPES,
    NenchevSingularityConsistent,
    SoyluDexterous,
    SoyluTaskPriority,
    WangEuclideanProjection,
    WangFuzzyGradientProjection,
    WangPseudoinverse,
    build_scheme,
)
from uvms_qp.schemes.scheme import _make_result
from uvms_qp.sim.scenario import load_scenario
from uvms_qp.sim.trajectories import LineTrajectory


@pytest.fixture(scope="module")
def soylu(models):
    return models["soylu_planar"]


@pytest.fixture(scope="module")
def wang(models):
    return models["wang_9dof"]


@pytest.fixture(scope="module")
def nenchev(models):
    return models["nenchev_pa10_arm"]


def _moving_target(state, frame="tool"):
    p = state.position(frame)
    return LineTrajectory(p, p + np.array([0.3, 0.2, 0.1]), 1.0)


def test_registry_names_match_classes():
    for name, cls in SCHEME_TYPES.items():
        assert cls.type_name == name


def test_unknown_scheme_lists_the_known_ones():
    scenario = load_scenario("paper000_quintic")
    with pytest.raises(ConfigError, match="known schemes: hqp, nenchev_sc"):
        build_scheme("soylu", scenario)


def test_scheme_for_the_wrong_model_kind_is_a_config_error():
    scenario = load_scenario("paper000_quintic")
    with pytest.raises(ConfigError, match="vehicle kind"):
        build_scheme("nenchev_sc", scenario)


def test_step_before_bind_and_without_trajectory(soylu):
    scheme = SoyluTaskPriority()
    state = soylu.state(soylu.home())
    with pytest.raises(InputError, match="bind"):
        scheme.step(state, 0.0)
    scheme.bind(soylu, 0.01)
    with pytest.raises(InputError, match="trajectory"):
        scheme.step(state, 0.0)


def test_bad_parameters_name_the_culprit(soylu, wang):
    with pytest.raises(InputError, match="weights"):
        SoyluTaskPriority(weights=[10, 10, 10, 1, 1]).bind(soylu, 0.01)
    with pytest.raises(InputError, match="rho_bar"):
        SoyluDexterous(rho_bar=-1.0)
    with pytest.raises(InputError, match="w_max"):
        WangFuzzyGradientProjection(w_max=2.0)
    with pytest.raises(InputError, match="limit_constants"):
        WangFuzzyGradientProjection(limit_constants=[1.0, 2.0]).bind(wang, 0.01)
    with pytest.raises(InputError, match="direction"):
        NenchevSingularityConsistent(direction=[0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="projector"):
        WangFuzzyGradientProjection(projector="oblique")


angles = st.lists(st.floats(-1.2, 1.2), min_size=3, max_size=3)


@settings(max_examples=20)
@given(angles, st.floats(0.0, 2.0))
def test_soylu_schemes_meet_the_primary_task_exactly(soylu, q, t):
    state = soylu.state(soylu.configuration([0.3, -0.2, 0.4], q))
    target = _moving_target(state)
    for cls in (SoyluTaskPriority, SoyluDexterous):
        scheme = cls().bind(soylu, 0.01)
        scheme.track(target)
        zeta = scheme.step(state, t).zeta
        sample = target.sample(t)
        e = sample.position[:2] - state.position("tool")[:2]
        expected = sample.velocity[:2] + 10.0 * e
        np.testing.assert_allclose(state.jacobian("tool", rows="position")[:2] @ zeta, expected,
                                   atol=1e-8)


def test_dexterous_equals_task_priority_above_the_threshold(soylu):
    state = soylu.state(soylu.home())  # rho = 1.5 > rho_bar = 1.3
    target = _moving_target(state)
    a = SoyluTaskPriority().bind(soylu, 0.01)
    b = SoyluDexterous().bind(soylu, 0.01)
    a.track(target)
    b.track(target)
    np.testing.assert_allclose(a.step(state, 0.5).zeta, b.step(state, 0.5).zeta, atol=1e-12)
    assert b.info["k"] == 0.0


@settings(max_examples=15)
@given(st.lists(st.floats(-0.8, 0.8), min_size=5, max_size=5), st.floats(0.0, 50.0))
def test_wang_schemes_meet_the_tool_rate(wang, q, force):
    joints = np.asarray(q) + np.array([0.0, -0.5, 1.2, 0.5, 0.0])
    state = wang.state(wang.configuration(np.zeros(6), joints))
    target = _moving_target(state)
    for scheme in (WangPseudoinverse(), WangFuzzyGradientProjection(force=force),
                   WangEuclideanProjection(force=force)):
        scheme.bind(wang, 0.01)
        scheme.track(target)
        zeta = scheme.step(state, 0.3).zeta
        sample = target.sample(0.3)
        expected = sample.velocity + 50.0 * (sample.position - state.position("tool"))
        np.testing.assert_allclose(state.jacobian("tool", rows="position") @ zeta, expected,
                                   atol=1e-7)


@settings(max_examples=25)
@given(st.lists(st.floats(-3.0, 3.0), min_size=4, max_size=4))
def test_sc_fields_lie_in_the_kernel_of_the_model_jacobian(nenchev, q):
    state = nenchev.state(nenchev.configuration([], q))
    J = state.jacobian("tool", rows="position")
    c = abs(np.sin(q[1]) * (1 + np.cos(q[3])) + np.cos(q[1]) * np.cos(q[2]) * np.sin(q[3]))
    if c < 1e-3:  # the paper scaling divides by the shoulder term
        return
    v = np.array([1.0, 0.0, 0.0])
    f_sm = self_motion_field(q)
    f_ep = end_point_field(q, v)
    np.testing.assert_allclose(J @ f_sm[:4], 0.0, atol=1e-9)
    np.testing.assert_allclose(J @ f_ep[:4], v * f_ep[4], atol=1e-9)
    assert f_sm[3] == 0.0 and f_sm[4] == 0.0 and f_ep[2] == 0.0
    scheme = NenchevSingularityConsistent().bind(nenchev, 0.01)
    zeta = scheme.step(state, 0.0).zeta
    np.testing.assert_allclose(zeta, f_ep[:4], atol=1e-12)


PAPER_SCENARIOS = [
    "paper000_quintic", "paper001_circle", "paper002_line_constant_arm_angle",
    "paper002_line_self_motion", "paper003_case1_no_payload", "paper003_case2_pseudoinverse",
    "paper003_case3_payload",
]


@pytest.mark.parametrize("scenario_name", PAPER_SCENARIOS)
def test_every_scheme_step_result_has_a_summary(scenario_name):
    scenario = load_scenario(scenario_name)
    names = [n for n in scenario.schemes if n != "hqp"]
    assert names
    state = scenario.model.state(scenario.q0)
    for name in names:
        result = build_scheme(name, scenario).step(state, 0.0)
        text = result.summary()
        assert len(result.level_violations) == len(result.level_names)
        for task, (norm, unit) in result.task_residuals.items():
            assert task in text and f"[{unit}]" in text
            assert np.isfinite(norm)


def test_registry_covers_the_paper_scenarios():
    listed = set()
    for scenario_name in PAPER_SCENARIOS:
        listed.update(load_scenario(scenario_name).schemes)
    assert set(SCHEME_TYPES) <= listed


# ----------------------------------------------------------- results of closed-form steps
def test_closed_form_results_use_the_one_constructor():
    zeta = np.array([0.1, -0.2, 0.3])
    residuals = {"tool": (0.01, "m"), "posture": (0.2, "rad")}
    a = _make_result("sr_tp", zeta, residuals, 1e-4, 2.5)
    assert isinstance(a, StepResult) and a.hierarchy is None
    assert (a.status, a.t, a.step_time, a.scheme, a.solver, a.stage) == (
        Status.OPTIMAL, 2.5, 1e-4, "sr_tp", "closed-form", "primary")
    assert a.level_names == (("tool", "posture"),)
    assert a.task_residuals == residuals and a.task_errors == residuals
    assert a.level_violations == pytest.approx([np.hypot(0.01, 0.2)])
    assert a.ok and a.bound_violation == 0.0
    assert "sr_tp" in a.summary() and "level 0" in a.summary()


def test_a_result_without_hierarchy_measures_its_box():
    res = StepResult(np.array([0.5, 2.0]), Status.BACKEND_ERROR, None, 0.0, 0.0, "s", "x",
                     np.array([-1.0, -1.0]), np.array([1.0, 1.0]))
    assert res.bound_violation == pytest.approx(1.0) and not res.ok
    assert res.task_residuals == {} and res.level_violations == []
