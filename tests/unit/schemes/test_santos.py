"""dos Santos et al.'s (2006) screw/Davies construction against the model's kinematics."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_qp.errors import InputError
from uvms_qp.schemes import SantosKinematicConstraint, SantosTaskPriority
from uvms_qp.sim.trajectories import FixedTarget

angle = st.floats(-3.0, 3.0)
coord = st.floats(-10.0, 10.0)


@pytest.fixture(scope="module")
def santos(models):
    return models["santos_planar"]


def _state(santos, x, y, psi, q):
    return santos.state(santos.configuration([x, y, psi], q))


@settings(max_examples=25)
@given(coord, coord, angle, st.lists(angle, min_size=3, max_size=3))
def test_screw_jacobian_equals_model_jacobian(santos, x, y, psi, q):
    scheme = SantosKinematicConstraint().bind(santos, 0.1)
    state = _state(santos, x, y, psi, q)
    J_model = state.jacobian("tool")[[0, 1, 5]]
    np.testing.assert_allclose(scheme.screw_jacobian(state), J_model, atol=1e-10)


@settings(max_examples=25)
@given(angle, st.lists(st.floats(-2.5, 2.5), min_size=3, max_size=3),
       st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3))
def test_kinematic_constraint_meets_tool_rate_with_vehicle_at_rest(santos, psi, q, rate):
    # keep away from the stretched/folded arm, where N_s is singular
    q[1] = float(np.clip(q[1], 0.3, 2.5)) if q[1] >= 0 else float(np.clip(q[1], -2.5, -0.3))
    q[2] = float(np.clip(q[2], 0.3, 2.5)) if q[2] >= 0 else float(np.clip(q[2], -2.5, -0.3))
    state = _state(santos, 0.0, 0.0, psi, q)
    scheme = SantosKinematicConstraint().bind(santos, 0.1)
    vehicle, arm, virtual = scheme.screws(state)
    from uvms_qp.analytic import kinematic_constraint_inverse

    r = 0.2
    arm_rates = kinematic_constraint_inverse(vehicle, arm, virtual, rate, [0.0, 0.0, r])
    zeta = np.concatenate([[0.0, 0.0, r], arm_rates])
    np.testing.assert_allclose(state.jacobian("tool")[[0, 1, 5]] @ zeta, rate, atol=1e-9)


def test_both_schemes_step_and_keep_the_interface(santos):
    state = santos.state(santos.home())
    target = FixedTarget(state.position("tool"))
    for cls in (SantosKinematicConstraint, SantosTaskPriority):
        scheme = cls().bind(santos, 0.1)
        scheme.track(target)
        result = scheme.step(state, 0.0)
        assert result.zeta.shape == (santos.nv,)
        assert np.all(np.isfinite(result.zeta))
        assert "tool" in result.task_residuals
        scheme.reset()


def test_wrong_geometry_is_rejected_at_bind(santos):
    with pytest.raises(InputError, match="do not describe model"):
        SantosKinematicConstraint(link_lengths=[1.0, 2.0, 2.0]).bind(santos, 0.1)
