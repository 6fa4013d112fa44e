"""Tasks written by users: rows that do not fit their slot are reported naming the task."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.controller import Controller
from uvms_qp.errors import ShapeError
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import ErrorTask, Task


class DepthTask(ErrorTask):
    """Hold the depth z [m] (one row); ``defect`` makes it return a wrong shape."""

    type_name = "depth"
    error_unit = "m"
    rate_unit = "m/s"

    def __init__(self, defect: str = "", rows: int = 1, **kwargs):
        super().__init__(**kwargs)
        self.defect, self.n_rows = defect, rows

    def _bind(self, model):
        self._row = model.eta_names.index("z")
        return self.n_rows

    def error_rows(self, state, t, slot):
        J = np.repeat(state.vehicle_pose_jacobian()[self._row:self._row + 1], self.n_rows, 0)
        e = np.full(self.n_rows, 0.5 - state.eta[self._row])
        if self.defect == "one_row":  # numpy would broadcast these into every row
            return J[:1], e, None
        if self.defect == "flat":
            return J[0], e, None
        if self.defect == "one_error":
            return J, e[:1], None
        if self.defect == "columns":
            J = J[:, :-1]
        elif self.defect == "rows":
            J, e = np.vstack([J, J]), np.r_[e, e]
        elif self.defect == "error":
            e = np.r_[e, e]
        elif self.defect == "feedforward":
            return J, e, np.zeros(3)
        return J, e, None


class SurgeFloor(Task):
    """``u >= lower`` [m/s] (one inequality row); ``defect`` makes it return a wrong shape."""

    type_name = "surge_floor"
    rate_unit = "m/s"

    def __init__(self, defect: str = "", **kwargs):
        super().__init__(**kwargs)
        self.defect = defect

    def _bind(self, model):
        return 1

    def evaluate(self, state, t, slot):
        J = np.zeros((1, self.model.nv))
        J[0, 0] = 1.0
        lower = np.zeros(2) if self.defect == "sides" else np.zeros(1)
        if self.defect == "columns":
            J = np.zeros((1, 3))
        return J, lower, np.inf


@pytest.mark.parametrize("defect, shown", [
    ("columns", r"J \(1, 9\), e \(1,\), ff None; expected J \(1, 10\)"),
    ("rows", r"J \(2, 10\), e \(2,\)"),
    ("error", r"e \(2,\)"),
    ("feedforward", r"ff \(3,\)"),
])
def test_error_rows_of_the_wrong_shape_name_the_task_and_the_expected_shape(rov, defect, shown):
    controller = Controller(rov, Stack(levels=[Level(DepthTask(defect=defect))]))
    with pytest.raises(ShapeError,
                       match=r"^task 'depth': DepthTask\.error_rows returned .*" + shown):
        controller.step(rov.state(rov.home()), 0.0)


@pytest.mark.parametrize("defect, shown", [
    ("one_row", r"J \(1, 10\), e \(2,\)"),
    ("flat", r"J \(10,\)"),
    ("one_error", r"e \(1,\)"),
])
def test_rows_that_numpy_would_broadcast_are_refused_too(rov, defect, shown):
    controller = Controller(rov, Stack(levels=[Level(DepthTask(defect=defect, rows=2))]))
    with pytest.raises(ShapeError, match=r"DepthTask\.error_rows returned .*" + shown +
                       r".*expected J \(2, 10\)"):
        controller.step(rov.state(rov.home()), 0.0)


@pytest.mark.parametrize("defect, shown", [
    ("columns", r"^task 'surge_floor': SurgeFloor\.evaluate returned J \(1, 3\).*"
                r"expected J \(1, 10\)"),
    ("sides", r"lower \(2,\), upper \(\)"),
])
def test_evaluated_rows_of_the_wrong_shape_name_the_task(rov, defect, shown):
    controller = Controller(rov, Stack(levels=[Level(SurgeFloor(defect=defect))]))
    with pytest.raises(ShapeError, match=shown):
        controller.step(rov.state(rov.home()), 0.0)


def test_well_formed_user_tasks_step(rov):
    stack = Stack(levels=[Level(SurgeFloor()), Level(DepthTask(gain=0.5))])
    result = Controller(rov, stack).step(rov.state(rov.home()), 0.0)
    assert result.ok and result.zeta[0] >= -1e-9
