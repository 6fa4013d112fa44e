"""The "daqp" back-end keeps one DAQP model between calls: it must read the current buffers."""

import numpy as np
import pytest

from uvms_qp.errors import InputError
from uvms_qp.hqp import HierarchySolver


def test_model_follows_its_workspace_after_a_call_rejected_while_loading() -> None:
    """A rejected call of another shape replaces the workspace; the model must not read the old one.

    Before the model was keyed by the workspace itself (not its shape), the third solve below ran
    on the first problem's buffers and failed with the first answer, x = [1, 2], outside the box.
    """
    solver = HierarchySolver("daqp")
    first = solver.solve([[(np.eye(2), [3.0, 3.0])]], [1.0, 1.0], [1.0, 2.0])
    np.testing.assert_allclose(first.x, [1.0, 2.0], atol=1e-9)
    with pytest.raises(InputError):  # three variables, NaN side: rejected while loading
        solver.solve([[(np.ones((1, 3)), [np.nan])]], -np.ones(3), np.ones(3))
    result = solver.solve([[(np.eye(2), [0.25, -0.5])]], -np.ones(2), np.ones(2))
    assert result.ok, result.summary()
    np.testing.assert_allclose(result.x, [0.25, -0.5], atol=1e-7)
