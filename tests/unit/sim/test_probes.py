"""Recorded manipulability when the stack has no manipulability task.

``paper001_circle`` runs ``santos_planar`` (planar vehicle, three 2 m links moving in the
horizontal plane) without a manipulability task: the probe measures Yoshikawa's ``w`` of the
``x, y`` rows (Soylu et al. (2007), Eq. (18)), the rows a default ManipulabilityTask uses;
the ``z`` row of a planar arm is zero, so the three position rows would always give 0.
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario

LINK = 2.0  # [m] the planar arm of dos Santos et al. (2006): three links


def planar_3r_manipulability(joints):
    """``sqrt(det(J J^T))`` of the closed-form 2x3 position Jacobian of a planar 3R arm."""
    angles = np.cumsum(joints)
    s, c = LINK * np.sin(angles), LINK * np.cos(angles)
    J = np.array([[-s[0:].sum(), -s[1:].sum(), -s[2]],
                  [c[0:].sum(), c[1:].sum(), c[2]]])
    return float(np.sqrt(np.linalg.det(J @ J.T)))


@pytest.fixture(scope="module")
def run():
    scenario = load_scenario("paper001_circle")
    assert not any(t.type_name == "manipulability" for t in scenario.build_stack().tasks)
    return simulate(scenario, duration=1.0)


def test_planar_manipulability_uses_the_planar_rows(run):
    w = run.manipulability
    assert w.shape == (run.steps + 1,)
    assert np.all(w > 1.0)  # 2 m links far from singular: w is several m^2, not 0
    expected = [planar_3r_manipulability(j) for j in run.joints]
    np.testing.assert_allclose(w, expected, rtol=1e-9)
