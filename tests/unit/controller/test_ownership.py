"""A stack's tasks and constraints serve one controller; ``Stack.copy`` gives another its own."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.constraints import (
    CommandRateBounds,
    JointPositionBounds,
    JointVelocityBounds,
    VehicleRateBounds,
)
from uvms_qp.controller import Controller
from uvms_qp.errors import InputError
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, PostureTask, StationKeepingTask

DT = 0.05
JOINT_ACCELERATION = 1.0  # [rad/s^2]


def _stack(model):
    goal = model.frame_pose(model.home(), "tool")[:3, 3] + [0.3, 0.1, 0.0]
    return Stack(constraints=[JointPositionBounds(), JointVelocityBounds(),
                              VehicleRateBounds(linear=0.5, angular=0.3),
                              CommandRateBounds(joint=JOINT_ACCELERATION)],
                 levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0)),
                         Level(StationKeepingTask(gain=1.0))])


def _run(model, controllers, steps):
    """Step the controllers in turn from home; the largest joint rate change of each [rad/s^2]."""
    q = {name: model.home() for name in controllers}
    previous = {name: np.zeros(model.nv) for name in controllers}
    worst = dict.fromkeys(controllers, 0.0)
    for k in range(steps):
        for name, ctrl in controllers.items():
            zeta = ctrl.step(model.state(q[name]), k * DT).zeta
            change = np.abs(zeta - previous[name])[model.n_vehicle:] / DT
            worst[name] = max(worst[name], float(change.max()))
            previous[name] = zeta
            q[name] = model.integrate(q[name], zeta, DT)
    return worst


def test_a_controller_whose_stack_was_taken_over_refuses_to_step(rov):
    stack = _stack(rov)
    first = Controller(rov, stack)
    first.step(rov.state(rov.home()), 0.0)
    second = Controller(rov, stack, solver="cascade:quadprog")
    with pytest.raises(InputError, match=r"stack: a Controller built later took over.*"
                                         r"stack\.copy\(\)"):
        first.step(rov.state(rov.home()), DT)
    assert second.step(rov.state(rov.home()), 0.0).stage == "primary"


def test_a_superseded_controller_cannot_reset_or_bound_the_tasks_it_lost(rov):
    """Its reset would put the later controller's command-rate bound back at rest."""
    stack = _stack(rov)
    first = Controller(rov, stack)
    second = Controller(rov, stack)
    state = rov.state(rov.home())
    second.step(state, 0.0)
    window = stack.constraints[-1].previous
    assert np.any(window)  # the second controller has moved away from rest
    for call in (first.reset, lambda: first.bounds(state)):
        with pytest.raises(InputError, match="took over"):
            call()
    np.testing.assert_array_equal(stack.constraints[-1].previous, window)


def test_a_controller_that_fails_to_build_takes_nothing_over(rov):
    stack = _stack(rov)
    first = Controller(rov, stack)
    with pytest.raises(InputError, match="gain"):
        Controller(rov, stack, dt=1.0)  # the tool gain of 2 would not settle at this period
    first.step(rov.state(rov.home()), 0.0)


def test_a_task_shared_by_two_stacks_serves_the_later_controller_only(rov):
    posture = PostureTask(gain=1.0)
    first = Controller(rov, Stack(levels=[Level(posture)]))
    Controller(rov, Stack(levels=[Level(posture), Level(StationKeepingTask())]))
    with pytest.raises(InputError, match="took over"):
        first.step(rov.state(rov.home()), 0.0)


def test_a_stack_rebound_to_another_model_is_refused_by_the_first_controller(models):
    rov, other = models["bluerov2_heavy_alpha5"], models["wang_9dof"]
    stack = Stack(levels=[Level(PostureTask(gain=1.0))], constraints=[JointVelocityBounds()])
    first = Controller(rov, stack)
    Controller(other, stack)
    with pytest.raises(InputError, match="took over"):
        first.step(rov.state(rov.home()), 0.0)


def test_copies_keep_each_controllers_command_rate_bound(rov):
    """Two controllers compared side by side, each on its own copy: each one's command moves by
    at most its acceleration bound per period (one command history each)."""
    stack = _stack(rov)
    controllers = {"daqp": Controller(rov, stack),
                   "quadprog": Controller(rov, stack.copy(), solver="cascade:quadprog")}
    worst = _run(rov, controllers, 40)
    assert max(worst.values()) <= JOINT_ACCELERATION * (1.0 + 1e-6)
    assert min(worst.values()) > 0.5 * JOINT_ACCELERATION  # the bound was reached, not idle


def test_a_copy_is_independent_and_answers_the_same(rov):
    stack = _stack(rov)
    twin = stack.copy()
    assert twin.model is stack.model
    assert not set(map(id, twin.tasks)) & set(map(id, stack.tasks))
    assert not set(map(id, twin.constraints)) & set(map(id, stack.constraints))
    state = rov.state(rov.home())
    ours, theirs = Controller(rov, stack), Controller(rov, twin)
    np.testing.assert_array_equal(ours.step(state, 0.0).zeta, theirs.step(state, 0.0).zeta)
    assert all(t.owner is None for t in stack.copy().tasks)  # a copy of a driven stack: free
