"""Hard constraints: box semantics, merging, defaults from the model, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.culprit import assert_names_culprit, bad_cases
from uvms_qp.constraints import (
    CONSTRAINT_TYPES,
    Constraint,
    JointPositionBounds,
    JointVelocityBounds,
    LinearInequality,
    VehicleRateBounds,
)
from uvms_qp.controller import Controller
from uvms_qp.errors import BoundsError, InputError, NonFiniteError, UnknownNameError
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import PostureTask


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


def _with_joints(model, joints):
    eta = model.split(model.home())[0]
    return model.state(model.configuration(eta, joints))


def test_registry():
    assert set(CONSTRAINT_TYPES) == {"joint_position_bounds", "joint_velocity_bounds",
                                     "vehicle_rate_bounds", "command_rate_bounds",
                                     "linear_inequality"}


def test_joint_position_bounds_one_euler_step_stays_inside(rov):
    dt = 0.1
    c = JointPositionBounds(gain=1.0).bind(rov)
    rng = np.random.default_rng(0)
    for _ in range(20):
        joints = rng.uniform(rov.joint_lower, rov.joint_upper)
        lo, hi = c.box(_with_joints(rov, joints), dt)
        assert np.all(np.isinf(lo[:6])) and np.all(np.isinf(hi[:6]))  # vehicle untouched
        np.testing.assert_allclose(joints + dt * hi[6:], rov.joint_upper, atol=1e-12)
        np.testing.assert_allclose(joints + dt * lo[6:], rov.joint_lower, atol=1e-12)


def test_joint_outside_its_limit_may_only_return(rov):
    joints = np.array([-0.2, 1.0, 3.7, 3.0])  # axis_e below 0, axis_c above 3.5
    lo, hi = JointPositionBounds(gain=0.5, margin=0.05).bind(rov).box(_with_joints(rov, joints),
                                                                       0.05)
    assert lo[6] == 0.0 and hi[6] > 0.0      # below: may stay or move up, never down
    assert hi[8] == 0.0 and lo[8] < 0.0      # above: may stay or move down, never up
    assert lo[7] < 0.0 < hi[7]


def test_velocity_and_vehicle_defaults_from_model(rov):
    state = rov.state(rov.home())
    lo, hi = JointVelocityBounds().bind(rov).box(state, 0.1)
    np.testing.assert_allclose(hi[6:], rov.joint_rate_limit)
    np.testing.assert_allclose(lo[6:], -rov.joint_rate_limit)
    lo, hi = VehicleRateBounds().bind(rov).box(state, 0.1)
    np.testing.assert_allclose(hi[:6], rov.vehicle_rate_limit)
    lo, hi = VehicleRateBounds(linear=0.4, angular=0.2).bind(rov).box(state, 0.1)
    np.testing.assert_allclose(hi[:6], [0.4, 0.4, 0.4, 0.2, 0.2, 0.2])
    assert np.all(np.isinf(hi[6:]))
    with pytest.raises(InputError, match="expected 6 values"):
        VehicleRateBounds(limits=[1.0, 1.0]).bind(rov)


def test_boxes_merge_by_intersection(rov):
    stack = Stack(levels=[Level(PostureTask())],
                  constraints=[JointPositionBounds(), JointVelocityBounds(scale=0.5),
                               VehicleRateBounds(linear=0.3, angular=0.1)])
    ctrl = Controller(rov, stack, dt=0.05)
    joints = np.array([0.01, 1.0, 1.0, 6.19])
    state = _with_joints(rov, joints)
    lower, upper = ctrl.bounds(state)
    expected_hi = np.minimum((rov.joint_upper - joints) / 0.05, 0.25)
    expected_lo = np.maximum((rov.joint_lower - joints) / 0.05, -0.25)
    np.testing.assert_allclose(upper[6:], expected_hi)
    np.testing.assert_allclose(lower[6:], expected_lo)
    np.testing.assert_allclose(upper[:6], [0.3, 0.3, 0.3, 0.1, 0.1, 0.1])


class _Forced(Constraint):
    """Test constraint demanding the first joint move at >= 1 rad/s."""

    type_name = "forced"
    has_box = True

    def fill_box(self, state, dt, lower, upper):
        lower[6] = max(lower[6], 1.0)


def test_empty_box_raises_with_culprits(rov):
    stack = Stack(levels=[Level(PostureTask())], constraints=[JointVelocityBounds(), _Forced()])
    ctrl = Controller(rov, stack, dt=0.05)
    with pytest.raises(BoundsError, match=r"zeta\[6\] \(axis_e\).*joint_velocity_bounds.*forced"):
        ctrl.step(rov.state(rov.home()), 0.0)


def test_linear_inequality_named_columns(rov):
    c = LinearInequality(A=[[1.0, 1.0]], upper=[0.2], columns=["u", "axis_b"]).bind(rov)
    rows = c.rows(rov.state(rov.home()), 0.1)
    assert rows.A[0, 0] == 1.0 and rows.A[0, 9] == 1.0 and rows.A.sum() == 2.0
    assert rows.lower[0] == -np.inf and rows.upper[0] == 0.2
    with pytest.raises(UnknownNameError, match="zeta component 'x'"):
        LinearInequality(A=[[1.0]], upper=[0.0], columns=["x"]).bind(rov)
    with pytest.raises(InputError, match="expected 10 columns"):
        LinearInequality(A=[[1.0, 2.0]], upper=[0.0]).bind(rov)
    with pytest.raises(BoundsError):
        LinearInequality(A=[[1.0]], lower=[1.0], upper=[0.0], columns=["u"])


@pytest.mark.parametrize("cls, kwargs, match", [
    (JointPositionBounds, {"gain": 1.5}, "gain"),
    (JointPositionBounds, {"margin": -0.1}, "margin"),
    (JointVelocityBounds, {"limits": [0.0, 1.0]}, "positive"),
    (VehicleRateBounds, {"linear": -1.0}, "linear"),
])
def test_bad_constraint_arguments(cls, kwargs, match):
    with pytest.raises(InputError, match=match):
        cls(**kwargs)


def _outside_states(model, n=10, seed=11):
    """States with joints drawn up to 20 % of the range beyond either limit."""
    rng = np.random.default_rng(seed)
    lo, hi = model.joint_lower, model.joint_upper
    span = hi - lo
    out = []
    for _ in range(n):
        eta, _ = model.split(model.random_configuration(rng))
        joints = rng.uniform(lo - 0.2 * span, hi + 0.2 * span)
        out.append(model.state(model.configuration(eta, joints)))
    return out


@pytest.mark.parametrize("joints", [None, ["axis_d", "axis_b"],
                                    ["axis_b", "axis_c", "axis_d", "axis_e"]])
def test_joint_position_bounds_intersect_a_filled_box(rov, joints):
    """``max(box, min(band, 0))`` / ``min(box, max(band, 0))``, inside and outside the limits."""
    con = JointPositionBounds(gain=0.7, margin=0.02, joints=joints).bind(rov)
    idx = np.array([rov.joint_names.index(j) for j in (joints or rov.joint_names)])
    cols = rov.n_vehicle + idx
    rng = np.random.default_rng(12)
    inside = [rov.state(rov.random_configuration(rng)) for _ in range(10)]
    for state in inside + _outside_states(rov):
        box_lo = -rng.uniform(0.0, 3.0, rov.nv)
        box_hi = rng.uniform(0.0, 3.0, rov.nv)
        lower, upper = box_lo.copy(), box_hi.copy()
        con.fill_box(state, 0.05, lower, upper)
        q = state.joints[idx]
        k = 0.7 / 0.05
        band_lo = np.minimum((rov.joint_lower[idx] + 0.02 - q) * k, 0.0)
        band_hi = np.maximum((rov.joint_upper[idx] - 0.02 - q) * k, 0.0)
        ref_lo, ref_hi = box_lo.copy(), box_hi.copy()
        ref_lo[cols] = np.maximum(box_lo[cols], band_lo)
        ref_hi[cols] = np.minimum(box_hi[cols], band_hi)
        np.testing.assert_array_equal(lower, ref_lo)
        np.testing.assert_array_equal(upper, ref_hi)
        assert np.all(lower <= 0.0) and np.all(upper >= 0.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"upper": True}, r"linear_inequality\.upper: expected real numbers, got booleans"),
        ({"lower": [False]}, r"linear_inequality\.lower: expected real numbers, got booleans"),
        ({"A_row": ["1"] * 10}, r"linear_inequality\.A: expected real numbers, got strings"),
        ({"A_row": [1j] * 10}, r"linear_inequality\.A: expected real numbers, got complex"),
    ],
)
def test_linear_inequality_takes_real_numbers_only(kwargs, match):
    """``upper=True`` used to become 1.0 and a complex row lost its imaginary part."""
    row = kwargs.pop("A_row", [1.0] * 10)
    with pytest.raises(InputError, match=match):
        LinearInequality(A=[row], **kwargs)


# ------------------------------------------------------------------------ constraint arguments
# (id, callable taking the model, error type, fragment of the message naming the culprit)
BAD_CONSTRAINTS = [
    ("rate limit NaN", lambda m: JointVelocityBounds(limits=[math.nan, 1.0, 1.0, 1.0]),
     NonFiniteError, "limits"),
    ("rate limit negative", lambda m: VehicleRateBounds(angular=-0.1), InputError, "angular"),
    ("rate limit NaN (vehicle)", lambda m: VehicleRateBounds(linear=math.nan), NonFiniteError,
     "linear"),
    ("position-bound gain NaN", lambda m: JointPositionBounds(gain=math.nan), NonFiniteError,
     "gain"),
    ("hard row lower > upper", lambda m: LinearInequality(A=[[1.0]], lower=[1.0], upper=[0.5],
                                                          columns=["u"]), BoundsError,
     "lower > upper"),
    ("hard row NaN", lambda m: LinearInequality(A=[[math.nan]], upper=[0.5], columns=["u"]),
     NonFiniteError, "A"),
    ("constraint not a constraint", lambda m: Stack(levels=[Level(PostureTask())],
                                                    constraints=["joint_velocity_bounds"]),
     InputError, "constraints[0]"),
]


@pytest.mark.parametrize("build, error, fragment", bad_cases(BAD_CONSTRAINTS))
def test_bad_constraint_argument_is_raised_with_its_culprit(rov, build, error, fragment):
    assert_names_culprit(build, error, fragment, rov)
