"""One exception hierarchy at every public boundary: the bad inputs not covered elsewhere.

The full table, with the test that covers each row, is in ``docs/reliability.md`` ("Bad
inputs"); rows already tested by the module that owns the boundary (unknown frame/joint/model/
solver/task type, NaN or inf q, non-orthonormal target rotations at construction, duplicate task
names, empty levels, lower > upper in a hierarchy, scenario files) are not repeated here.
Each case checks the error type (a :class:`uvms_qp.UvmsQpError`), that the message names the
culprit, and, for inputs met at step time, that no back-end was called.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from uvms_qp import UvmsQpError
from uvms_qp.constraints import (
    JointPositionBounds,
    JointVelocityBounds,
    LinearInequality,
    VehicleRateBounds,
)
from uvms_qp.controller import Controller
from uvms_qp.errors import BoundsError, InputError, NonFiniteError, ShapeError
from uvms_qp.model import load_model
from uvms_qp.safety import SafeSolver
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, PostureTask, StationKeepingTask
from uvms_qp.testing.faults import Fault, inject

NAN, INF = math.nan, math.inf


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


def _stack(**ee):
    return Stack(levels=[Level(EndEffectorTask(**(ee or {"position": [0.5, 0.0, 0.2]})))],
                 constraints=[JointVelocityBounds()])


# (id, callable taking the model, error type, fragment of the message naming the culprit)
CONSTRUCTION = [
    ("q wrong length", lambda m: m.state(np.zeros(m.nq - 1)), ShapeError, "q"),
    ("q inf", lambda m: m.state(np.full(m.nq, INF)), NonFiniteError, "q"),
    ("quaternion far from unit", lambda m: m.state(np.r_[np.zeros(3), 0, 0, 0, 3.0,
                                                         np.zeros(4)]), InputError, "quaternion"),
    ("eta wrong length", lambda m: m.configuration(np.zeros(5), np.zeros(4)), ShapeError,
     "eta"),
    ("target NaN", lambda m: EndEffectorTask(position=[0.0, NAN, 0.0]), NonFiniteError,
     "position"),
    ("target wrong length", lambda m: EndEffectorTask(position=[0.0, 1.0, 2.0, 3.0]),
     ShapeError, "position"),
    ("gain negative", lambda m: EndEffectorTask(position=[0, 0, 0], gain=-1.0), InputError,
     "gain"),
    ("gain NaN", lambda m: PostureTask(gain=NAN), NonFiniteError, "gain"),
    ("gains list with a negative", lambda m: PostureTask(gain=[1.0, -1.0, 1.0, 1.0]),
     InputError, "gain"),
    ("weight zero", lambda m: PostureTask(weight=0.0), InputError, "weight"),
    ("weight NaN", lambda m: PostureTask(weight=NAN), NonFiniteError, "weight"),
    ("weight negative", lambda m: StationKeepingTask(weight=-2.0), InputError, "weight"),
    ("rate limit NaN", lambda m: JointVelocityBounds(limits=[NAN, 1.0, 1.0, 1.0]),
     NonFiniteError, "limits"),
    ("rate limit negative", lambda m: VehicleRateBounds(angular=-0.1), InputError, "angular"),
    ("rate limit NaN (vehicle)", lambda m: VehicleRateBounds(linear=NAN), NonFiniteError,
     "linear"),
    ("position-bound gain NaN", lambda m: JointPositionBounds(gain=NAN), NonFiniteError,
     "gain"),
    ("hard row lower > upper", lambda m: LinearInequality(A=[[1.0]], lower=[1.0], upper=[0.5],
                                                          columns=["u"]), BoundsError,
     "lower > upper"),
    ("hard row NaN", lambda m: LinearInequality(A=[[NAN]], upper=[0.5], columns=["u"]),
     NonFiniteError, "A"),
    ("dt negative", lambda m: Controller(m, _stack(), dt=-0.05), InputError, "dt"),
    ("dt NaN", lambda m: Controller(m, _stack(), dt=NAN), NonFiniteError, "dt"),
    ("dt inf", lambda m: Controller(m, _stack(), dt=INF), NonFiniteError, "dt"),
    ("metric negative", lambda m: Controller(m, _stack(), metric=[-1.0] + [1.0] * 9),
     InputError, "metric"),
    ("metric NaN", lambda m: Controller(m, _stack(), metric=[NAN] + [1.0] * 9),
     NonFiniteError, "metric"),
    ("metric wrong length", lambda m: Controller(m, _stack(), metric=[1.0] * 3), ShapeError,
     "metric"),
    ("deadline negative", lambda m: Controller(m, _stack(), deadline=-1.0), InputError,
     "deadline"),
    ("deadline NaN", lambda m: SafeSolver("daqp", deadline=NAN), NonFiniteError, "deadline"),
    ("scheme unknown", lambda m: Controller(m, _stack(), scheme="magic"), InputError,
     "scheme"),
    ("stack not a Stack", lambda m: Controller(m, [PostureTask()]), InputError, "stack"),
    ("level not a task", lambda m: Level("posture"), InputError, "Task"),
    ("constraint not a constraint", lambda m: Stack(levels=[Level(PostureTask())],
                                                    constraints=["joint_velocity_bounds"]),
     InputError, "constraints[0]"),
    ("axis unknown", lambda m: StationKeepingTask(axes=["x", "w"]).bind(m), InputError, "w"),
]


@pytest.mark.parametrize("build, error, fragment",
                         [c[1:] for c in CONSTRUCTION], ids=[c[0] for c in CONSTRUCTION])
def test_bad_input_is_raised_with_its_culprit(rov, build, error, fragment):
    with pytest.raises(error) as info:
        build(rov)
    assert isinstance(info.value, UvmsQpError)
    assert fragment in str(info.value)


class _NaNTrajectory:
    """A trajectory that turns NaN after t = 1 s (a broken sensor or planner)."""

    duration = 10.0

    def sample(self, t):
        class S:
            position = np.array([0.5, 0.0, NAN if t > 1.0 else 0.2])
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
def test_bad_input_at_run_time_never_reaches_a_back_end(rov, case, error, fragment):
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
            tool.set_target(position=[0.0, NAN, 0.0])
        elif case == "set_target_rotation":
            tool.set_target(rotation=[[1, 0, 0], [0, 1, 0], [0, 0, 1.5]])
        elif case == "update_gain":
            tool.update(gain=-3.0)
        else:
            ctrl.step(load_model("wang_9dof").state(load_model("wang_9dof").home()), 0.0)
    assert isinstance(info.value, UvmsQpError)
    assert fragment in str(info.value)
    assert sum(s.n_calls for s in spies) == calls  # nothing reached a back-end
