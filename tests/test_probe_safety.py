"""Safety of the control step against overflowing targets, runaway back-ends and bad arguments.

* A target side that is ``+inf`` (lower) or ``-inf`` (upper), e.g. ``gain * error`` overflowing
  for a finite but absurd target, is bad task output: ``step`` raises NonFiniteError naming the
  task for every scheme and solver, instead of commanding inf or relaxing the level.
* Whatever the closed-form solution is, ``step`` never returns a non-finite zeta.
* ProxQP is capped: a badly scaled level fails truthfully within a bounded time.
* Controller arguments of the wrong type raise InputError naming the argument.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from uvms_qp import Controller, Level, Stack, load_model, solve_hierarchy
from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.errors import InputError, NonFiniteError
from uvms_qp.hqp import Status, available_solvers
from uvms_qp.sim.trajectories import TrajectorySample
from uvms_qp.tasks import EndEffectorTask, StationKeepingTask
from uvms_qp.testing.faults import Fault, inject


@pytest.fixture(scope="module")
def model():  # type: ignore[no-untyped-def]
    return load_model("bluerov2_heavy_alpha5")


def _stack(task: EndEffectorTask, second: bool = False) -> Stack:
    levels = [Level(task)] + ([Level(StationKeepingTask())] if second else [])
    return Stack(constraints=[JointPositionBounds(), JointVelocityBounds(), VehicleRateBounds()],
                 levels=levels)


class _InfTrajectory:
    """A user trajectory whose sample is +inf [m] along x."""

    duration = 1.0

    def sample(self, t: float) -> TrajectorySample:
        return TrajectorySample(np.array([np.inf, 0.0, 0.0]), np.zeros(3))


# the tasks warn about the overflow of gain * error itself (RuntimeWarning); what is checked here
# is what the controller does with it
_OVERFLOW_WARNS = pytest.mark.filterwarnings("ignore::RuntimeWarning")


@_OVERFLOW_WARNS
@pytest.mark.parametrize(("scheme", "solver"), [
    ("nullspace", "daqp"), ("hqp", "daqp"), ("hqp", "cascade:quadprog"),
    ("weighted", "daqp")])
@pytest.mark.parametrize("second", [False, True])
def test_overflowing_target_is_rejected_naming_the_task(model, scheme, solver,  # type: ignore[no-untyped-def]
                                                        second):
    # 10 * (1e308 - x) overflows to +inf: the equality row's lower side is +inf
    for task in (EndEffectorTask(position=[1e308, 0.0, 0.0], gain=10.0, name="reach"),
                 EndEffectorTask(trajectory=_InfTrajectory(), name="reach")):
        c = Controller(model, _stack(task, second), solver=solver, scheme=scheme)
        with pytest.raises(NonFiniteError, match="reach"):
            c.step(model.state(model.home()))


@_OVERFLOW_WARNS
def test_negative_overflow_is_rejected(model):  # type: ignore[no-untyped-def]
    # -inf in an upper side (and a lower side of -inf, legitimate on its own)
    c = Controller(model, _stack(EndEffectorTask(position=[-1e308, 0.0, 0.0], gain=10.0,
                                                 name="reach")))
    with pytest.raises(NonFiniteError, match="reach"):
        c.step(model.state(model.home()))


@_OVERFLOW_WARNS
def test_large_finite_targets_still_solve(model):  # type: ignore[no-untyped-def]
    # sides whose SUM overflows while every entry is finite are not bad input
    c = Controller(model, _stack(EndEffectorTask(position=[1e307, 1e307, 0.0], gain=10.0)))
    r = c.step(model.state(model.home()))
    assert np.all(np.isfinite(r.zeta))
    assert r.bound_violation <= 1e-9


@pytest.mark.parametrize("fault", [Fault.NAN_SUCCESS, Fault.WILD_FAILURE, Fault.MEMORY])
def test_nullspace_never_returns_a_non_finite_zeta(model, fault):  # type: ignore[no-untyped-def]
    c = Controller(model, _stack(EndEffectorTask(position=[1.0, 0.0, 0.0]), True),
                   scheme="nullspace")
    state = model.state(model.home())
    clean = c.step(state)
    inject(c, fault, count=2)  # the closed form and its cold retry
    r = c.step(state)
    assert np.all(np.isfinite(r.zeta))
    assert np.all(r.zeta >= r.lower) and np.all(r.zeta <= r.upper)
    assert r.stage == "alternate" and r.ok  # the QP alternate solves the same levels
    again = c.step(state)
    assert again.stage == "primary"
    np.testing.assert_allclose(again.zeta, clean.zeta, atol=1e-12)


@pytest.mark.skipif("cascade:proxqp" not in available_solvers(), reason="proxsuite missing")
def test_proxqp_is_bounded_on_a_badly_scaled_level():
    # BlueROV2 tool rows at home, target 1e6 m away with gain 10 (used to run for a minute)
    A = np.array([
        [1, 0, 0, 0, -0.058358470175360361, -0.099000330993482585, 3.3099348258069927e-07,
         0.017641529824639651, 0.054895711407959361, 0],
        [0, 1, 0, 0.058358470175360361, 0, 0.51461142773189239, -0.27461142773189240, 0,
         -1.3171897158927282e-07, 0],
        [0, 0, 1, 0.099000330993482585, -0.51461142773189239, 0, 0, -0.25461142773189238,
         0.12251131935048581, 0]])
    b = np.array([9.999994853885721e+06, -0.9900033099348259, 0.5835847017536036])
    lo = np.array([-1.5] + [-np.inf] * 5 + [-0.5] * 4)
    t0 = time.perf_counter()
    r = solve_hierarchy([[(A, b)]], lo, -lo, solver="cascade:proxqp")
    elapsed = time.perf_counter() - t0
    assert elapsed < 10.0  # was about 60 s; well under 1 s on an idle machine
    assert np.all(np.isfinite(r.x))
    if r.status == Status.OPTIMAL:  # an answer is only reported optimal when it is one
        assert np.max(np.abs(A @ r.x - b)) <= 1e-6 * np.max(np.abs(b))
    else:
        assert r.status == Status.BACKEND_ERROR


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"solver": None}, "solver"), ({"solver": ["daqp"]}, "solver"),
    ({"options": 3}, "options"), ({"strict": "no"}, "strict"), ({"strict": 1}, "strict")])
def test_controller_arguments_are_checked(model, kwargs, name):  # type: ignore[no-untyped-def]
    with pytest.raises(InputError, match=name):
        Controller(model, _stack(EndEffectorTask(position=[1.0, 0.0, 0.0])), **kwargs)


@pytest.mark.parametrize("bad", [None, "bluerov2_heavy_alpha5"])
def test_controller_model_must_be_a_model(bad):  # type: ignore[no-untyped-def]
    with pytest.raises(InputError, match="model"):
        Controller(bad, _stack(EndEffectorTask(position=[1.0, 0.0, 0.0])))
