"""Forward kinematics of the bundled paper models against the numbers printed in the papers."""

import math

import numpy as np
import pytest

from uvms_qp import load_model
from uvms_qp.analytic.singularity_consistent import sc_arm_jacobian
from uvms_qp.model.bundled import WANG_MOUNT


def test_soylu_initial_tool_position_000_section_3():
    # Soylu et al. (2007), Section 3: q = [0 0 0 pi/3 -pi/3 pi/3] -> x_p = [3, 1.7321] m
    model = load_model("soylu_planar")
    q = model.configuration([0.0, 0.0, 0.0], [math.pi / 3, -math.pi / 3, math.pi / 3])
    tool = model.frame_pose(q, "tool")
    assert tool[:2, 3] == pytest.approx([3.0, 1.7321], abs=1e-4)
    assert tool[2, 3] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(model.home(), q)


def test_soylu_arm_base_is_one_metre_ahead_of_the_vehicle():
    model = load_model("soylu_planar")
    q = model.configuration([2.0, -1.0, math.pi / 2], [0.0, 0.0, 0.0])
    state = model.state(q)
    # heading east (psi = pi/2 in NED): the arm base is 1 m east of the vehicle, links stretched
    assert state.position("arm_base") == pytest.approx([2.0, 0.0, 0.0], abs=1e-12)
    assert state.position("tool") == pytest.approx([2.0, 3.0, 0.0], abs=1e-12)


def test_santos_initial_tool_pose_001_simulation():
    # dos Santos et al. (2006): q = [1.47 -1 0.3] -> x_E = 5.92 m, y_E = 4.29 m, psi_E = 0.77 rad
    model = load_model("santos_planar")
    q = model.configuration([0.0, 0.0, 0.0], [1.47, -1.0, 0.3])
    tool = model.frame_pose(q, "tool")
    assert tool[:2, 3] == pytest.approx([5.92, 4.29], abs=5e-3)
    heading = math.atan2(tool[1, 0], tool[0, 0])
    assert heading == pytest.approx(0.77, abs=1e-12)
    np.testing.assert_allclose(model.home(), q)


def test_wang_tool_relative_to_arm_base_003_simulation_setup():
    # Wang et al. (2017): q = [0 -45 90 45 0] deg -> x = 0.5907 m, |z| = 0.363 m in the base
    # frame. The table gives y = -0.068 m (the paper prints 0.053; see docs/models.md).
    model = load_model("wang_9dof")
    q = model.configuration(np.zeros(6), np.radians([0.0, -45.0, 90.0, 45.0, 0.0]))
    state = model.state(q)
    p = state.pose_in("tool", "arm_base")[:3, 3]
    assert p[0] == pytest.approx(0.5907, abs=1e-4)
    assert abs(p[2]) == pytest.approx(0.363, abs=1e-4)
    assert p[1] == pytest.approx(-0.068, abs=1e-4)
    # arm base axes are the FRD body axes: the tool hangs below (z down) the mount point
    assert state.position("tool") == pytest.approx(np.add(WANG_MOUNT["xyz"], p), abs=1e-12)
    assert p[2] > 0.0
    np.testing.assert_allclose(model.home(), q)


def test_wang_joint_limits_from_003_simulation_setup():
    model = load_model("wang_9dof")
    expected = np.radians([60.0, 90.0, 110.0, 120.0, 120.0])
    np.testing.assert_allclose(model.joint_upper, expected)
    np.testing.assert_allclose(model.joint_lower, -expected)
    assert model.actuated == ("u", "v", "w", "r")
    assert model.passive == ("p", "q")


def test_nenchev_wrist_centre_002_section_4():
    # Nenchev and Tsumaki, Section 4: (0, 0, 0, -90) deg -> wrist centre (1, 0, 1) m
    model = load_model("nenchev_pa10_arm")
    q = model.configuration([], np.radians([0.0, 0.0, 0.0, -90.0]))
    assert model.frame_pose(q, "tool")[:3, 3] == pytest.approx([1.0, 0.0, 1.0], abs=1e-12)


def test_nenchev_jacobian_matches_the_printed_entries():
    # the printed entries j11 .. j34 (Nenchev and Tsumaki, Section 3; j11's typo corrected, see
    # docs/models.md), checked against finite differences in tests/unit/analytic
    model = load_model("nenchev_pa10_arm")
    rng = np.random.default_rng(2)
    for _ in range(20):
        joints = rng.uniform(-math.pi, math.pi, 4)
        state = model.state(model.configuration([], joints))
        np.testing.assert_allclose(
            state.jacobian("tool", rows="position"), sc_arm_jacobian(joints), atol=1e-12
        )
        np.testing.assert_allclose(
            state.arm_jacobian("tool", rows="position"), sc_arm_jacobian(joints), atol=1e-12
        )
