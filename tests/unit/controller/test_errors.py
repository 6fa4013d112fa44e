"""Controller and scheme inputs: every bad argument, state, time or task output raises an error
of the library naming the culprit, at construction or at the step, before any back-end is called.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.culprit import assert_names_culprit, bad_cases
from uvms_qp import UvmsQpError
from uvms_qp.bench.stacks import demo_stack
from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.controller import Controller
from uvms_qp.errors import InputError, NonFiniteError, ShapeError
from uvms_qp.safety import SafeSolver
from uvms_qp.schemes import WangPseudoinverse
from uvms_qp.sim.trajectories import TrajectorySample
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, PostureTask, StationKeepingTask
from uvms_qp.testing.faults import Fault, inject


def _stack(**ee):
    return Stack(levels=[Level(EndEffectorTask(**(ee or {"position": [0.5, 0.0, 0.2]})))],
                 constraints=[JointVelocityBounds()])


# ------------------------------------------------------------------------ controller arguments
# (id, callable taking the model, error type, fragment of the message naming the culprit)
BAD_CONTROLLER = [
    ("dt negative", lambda m: Controller(m, _stack(), dt=-0.05), InputError, "dt"),
    ("dt NaN", lambda m: Controller(m, _stack(), dt=math.nan), NonFiniteError, "dt"),
    ("dt inf", lambda m: Controller(m, _stack(), dt=math.inf), NonFiniteError, "dt"),
    ("metric negative", lambda m: Controller(m, _stack(), metric=[-1.0] + [1.0] * 9),
     InputError, "metric"),
    ("metric NaN", lambda m: Controller(m, _stack(), metric=[math.nan] + [1.0] * 9),
     NonFiniteError, "metric"),
    ("metric wrong length", lambda m: Controller(m, _stack(), metric=[1.0] * 3), ShapeError,
     "metric"),
    ("deadline negative", lambda m: Controller(m, _stack(), deadline=-1.0), InputError,
     "deadline"),
    ("deadline NaN", lambda m: SafeSolver("daqp", deadline=math.nan), NonFiniteError, "deadline"),
    ("scheme unknown", lambda m: Controller(m, _stack(), scheme="magic"), InputError,
     "scheme"),
    ("stack not a Stack", lambda m: Controller(m, [PostureTask()]), InputError, "stack"),
]


@pytest.mark.parametrize("build, error, fragment", bad_cases(BAD_CONTROLLER))
def test_bad_controller_argument_is_raised_with_its_culprit(rov, build, error, fragment):
    assert_names_culprit(build, error, fragment, rov)


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"solver": None}, "solver"), ({"solver": ["daqp"]}, "solver"),
    ({"options": 3}, "options"), ({"strict": "no"}, "strict"), ({"strict": 1}, "strict")])
def test_controller_arguments_are_checked(rov, kwargs, name):
    with pytest.raises(InputError, match=name):
        Controller(rov, _bounded_stack(EndEffectorTask(position=[1.0, 0.0, 0.0])), **kwargs)


@pytest.mark.parametrize("bad", [None, "bluerov2_heavy_alpha5"])
def test_controller_model_must_be_a_model(bad):
    with pytest.raises(InputError, match="model"):
        Controller(bad, _bounded_stack(EndEffectorTask(position=[1.0, 0.0, 0.0])))


@pytest.mark.parametrize("metric", [["1"] * 10, [True] * 10, np.ones(10, dtype=complex)])
def test_a_controller_metric_must_be_real(rov, metric):
    with pytest.raises(InputError, match="metric: expected real numbers"):
        Controller(rov, demo_stack(position=[0.5, 0.0, 0.0]), metric=metric)


# ----------------------------------------------------------------------- what step() is given
@pytest.mark.parametrize("t", [math.nan, math.inf, -math.inf, "0", None, True, 1j])
def test_step_time_must_be_a_finite_real_number(rov, models, t):
    """``t`` is read by trajectories and recorded in results: never converted, never NaN."""
    state = rov.state(rov.home())
    error = NonFiniteError if isinstance(t, float) else InputError
    for scheme in ("hqp", "nullspace"):
        controller = Controller(rov, Stack(levels=[Level(PostureTask())]), scheme=scheme)
        with pytest.raises(error, match=r"^t: expected a "):
            controller.step(state, t)
        assert controller.step(state, 1).t == 1.0  # an integer time is a real number
    wang = models["wang_9dof"]
    scheme = WangPseudoinverse().bind(wang, 0.01)
    with pytest.raises(error, match=r"^t: expected a "):
        scheme.step(wang.state(wang.home()), t)


def test_controller_step_with_a_configuration_says_to_build_a_state(rov):
    model = rov
    controller = Controller(model, Stack(levels=[Level(PostureTask())]))
    with pytest.raises(InputError, match=r"expects a State.*model\.state\(q\)"):
        controller.step(model.home(), 0.0)
    assert controller.step(model.state(model.home()), 0.0).status == "optimal"


def test_scheme_step_with_a_configuration_says_to_build_a_state(models):
    model = models["wang_9dof"]
    scheme = WangPseudoinverse().bind(model, 0.01)
    with pytest.raises(InputError, match=r"expects a State.*model\.state\(q\)"):
        scheme.step(model.home(), 0.0)


# ------------------------------------------- bad input at run time, before any back-end
class _NaNTrajectory:
    """A trajectory that turns NaN after t = 1 s (a broken sensor or planner)."""

    duration = 10.0

    def sample(self, t):
        class S:
            position = np.array([0.5, 0.0, math.nan if t > 1.0 else 0.2])
            velocity = np.zeros(3)
            rotation = None
            angular_velocity = None
        return S()


def _spy(ctrl):
    """A never-armed fault wrapper around the back-ends: counts the calls that reach them."""
    return [inject(ctrl.safe.primary, Fault.NAN_SUCCESS), inject(ctrl.safe.alternate,
                                                                 Fault.NAN_SUCCESS)]


RUN_TIME = [
    ("target NaN from a trajectory", "trajectory", NonFiniteError, "'tool'"),
    ("set_target NaN", "set_target_nan", NonFiniteError, "position"),
    ("set_target non-orthonormal rotation", "set_target_rotation", InputError, "rotation"),
    ("update with a negative gain", "update_gain", InputError, "gain"),
    ("state of another model", "other_model", InputError, "another model"),
]


@pytest.mark.parametrize("case, error, fragment", [c[1:] for c in RUN_TIME],
                         ids=[c[0] for c in RUN_TIME])
def test_bad_input_at_run_time_never_reaches_a_back_end(rov, models, case, error, fragment):
    tool = EndEffectorTask(mode="position", name="tool", trajectory=_NaNTrajectory())
    if case in ("set_target_rotation",):
        tool = EndEffectorTask(mode="pose", name="tool", position=[0.5, 0.0, 0.2],
                               rotation=np.eye(3))
    ctrl = Controller(rov, Stack(levels=[Level(tool)], constraints=[JointVelocityBounds()]))
    spies = _spy(ctrl)
    state = rov.state(rov.home())
    ctrl.step(state, 0.0)
    calls = sum(s.n_calls for s in spies)
    with pytest.raises(error) as info:
        if case == "trajectory":
            ctrl.step(state, 2.0)
        elif case == "set_target_nan":
            tool.set_target(position=[0.0, math.nan, 0.0])
        elif case == "set_target_rotation":
            tool.set_target(rotation=[[1, 0, 0], [0, 1, 0], [0, 0, 1.5]])
        elif case == "update_gain":
            tool.update(gain=-3.0)
        else:
            ctrl.step(models["wang_9dof"].state(models["wang_9dof"].home()), 0.0)
    assert isinstance(info.value, UvmsQpError)
    assert fragment in str(info.value)
    assert sum(s.n_calls for s in spies) == calls  # nothing reached a back-end


# ------------------------------------------ task output that overflows, or is merely large
def _bounded_stack(task: EndEffectorTask, second: bool = False) -> Stack:
    levels = [Level(task)] + ([Level(StationKeepingTask())] if second else [])
    return Stack(constraints=[JointPositionBounds(), JointVelocityBounds(), VehicleRateBounds()],
                 levels=levels)


class _InfTrajectory:
    """A user trajectory whose sample is +inf [m] along x."""

    duration = 1.0

    def sample(self, t: float) -> TrajectorySample:
        return TrajectorySample(np.array([np.inf, 0.0, 0.0]), np.zeros(3))


_OVERFLOW_WARNS = pytest.mark.filterwarnings("ignore::RuntimeWarning")


@_OVERFLOW_WARNS
@pytest.mark.parametrize(("scheme", "solver"), [
    ("nullspace", "daqp"), ("hqp", "daqp"), ("hqp", "cascade:quadprog"),
    ("weighted", "daqp")])
@pytest.mark.parametrize("second", [False, True])
def test_overflowing_target_is_rejected_naming_the_task(rov, scheme, solver, second):
    # 10 * (1e308 - x) overflows to +inf: the equality row's lower side is +inf
    for task in (EndEffectorTask(position=[1e308, 0.0, 0.0], gain=10.0, name="reach"),
                 EndEffectorTask(trajectory=_InfTrajectory(), name="reach")):
        c = Controller(rov, _bounded_stack(task, second), solver=solver, scheme=scheme)
        with pytest.raises(NonFiniteError, match="reach"):
            c.step(rov.state(rov.home()))


@_OVERFLOW_WARNS
def test_negative_overflow_is_rejected(rov):
    # -inf in an upper side (and a lower side of -inf, legitimate on its own)
    c = Controller(rov, _bounded_stack(EndEffectorTask(position=[-1e308, 0.0, 0.0], gain=10.0,
                                                       name="reach")))
    with pytest.raises(NonFiniteError, match="reach"):
        c.step(rov.state(rov.home()))


@_OVERFLOW_WARNS
def test_large_finite_targets_still_solve(rov):
    # sides whose SUM overflows while every entry is finite are not bad input
    c = Controller(rov, _bounded_stack(EndEffectorTask(position=[1e307, 1e307, 0.0], gain=10.0)))
    r = c.step(rov.state(rov.home()))
    assert np.all(np.isfinite(r.zeta))
    assert r.bound_violation <= 1e-9


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog", "cascade:proxqp", "cascade:osqp"])
def test_huge_demand_without_vehicle_bound_keeps_the_joint_rate_limit(rov, solver):
    """A tool demand of about 1e9 m/s (a gain of 1e9, refused now, once gave a backend_error
    step 0.0067 rad/s beyond the joint rate limit): every command is saturated into the box,
    whatever the back-end returns."""
    far = [1.5e8, 0.5e8, 0.5e8]  # [m]: 10 [1/s] times this is the same demand
    stack = Stack(levels=[Level(EndEffectorTask(position=far, gain=10.0)),
                          Level(PostureTask())],
                  constraints=[JointPositionBounds(), JointVelocityBounds()])
    ctrl = Controller(rov, stack, solver=solver, dt=0.05, deadline=0.5)
    res = ctrl.step(rov.state(rov.home()), 0.0)
    assert np.all(np.isfinite(res.zeta))
    assert np.all(np.abs(res.zeta[6:]) <= rov.joint_rate_limit)  # exactly, no tolerance
    assert np.all(res.zeta >= res.lower) and np.all(res.zeta <= res.upper)
