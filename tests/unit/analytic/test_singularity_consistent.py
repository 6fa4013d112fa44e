import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.analytic import (
    column_augmented_jacobian,
    end_point_field,
    sc_arm_jacobian,
    sc_arm_position,
    sc_blend,
    sc_vector_field,
    self_motion_field,
    shoulder_term,
    signed_minor_null_vector,
    singularity_crossings,
)
from uvms_qp.errors import InputError, ShapeError

angles = st.lists(st.floats(-3.1, 3.1), min_size=4, max_size=4).map(np.array)
units = (
    st.lists(st.floats(-1, 1), min_size=3, max_size=3)
    .map(np.array)
    .filter(lambda v: np.linalg.norm(v) > 0.1)
)


@given(st.integers(0, 10_000), st.integers(1, 6))
def test_signed_minor_vector_is_the_svd_null_direction(seed, m):
    H = np.random.default_rng(seed).normal(size=(m, m + 1))
    f = signed_minor_null_vector(H)
    assert np.allclose(H @ f, 0.0, atol=1e-9 * max(1.0, np.linalg.norm(f)))
    v = np.linalg.svd(H)[2][-1]
    assert np.isclose(abs(f @ v), np.linalg.norm(f), rtol=1e-8)  # parallel
    # its norm is the product of the singular values
    assert np.isclose(np.linalg.norm(f), np.prod(np.linalg.svd(H, compute_uv=False)))


def test_sc_field_of_two_link_arm_stops_the_end_point_at_singularity():
    # 2-link arm, unit links, q2 -> 0 (stretched): dp = (-1)^n det J = det J = sin q2
    for q2 in (0.5, 0.0):
        s1, c1 = np.sin(0.3), np.cos(0.3)
        s12, c12 = np.sin(0.3 + q2), np.cos(0.3 + q2)
        J = np.array([[-s1 - s12, -s12], [c1 + c12, c12]])
        f = sc_vector_field(J, [1.0, 0.0])
        assert np.isclose(f[-1], np.sin(q2))
        assert np.allclose(column_augmented_jacobian(J, [2.0, 0.0]) @ f, 0.0)
    assert abs(f[0]) + abs(f[1]) > 0  # joints still move at the singularity


@given(angles)
def test_arm_jacobian_matches_finite_differences_of_position(q):
    h = 1e-6
    fd = np.stack(
        [(sc_arm_position(q + h * e) - sc_arm_position(q - h * e)) / (2 * h) for e in np.eye(4)],
        axis=1,
    )
    assert np.allclose(sc_arm_jacobian(q), fd, atol=1e-7)


def test_paper_initial_wrist_positions():
    assert np.allclose(sc_arm_position(np.deg2rad([0, 0, 0, -90])), [1, 0, 1], atol=1e-12)
    assert np.isclose(np.linalg.norm(sc_arm_position(np.deg2rad([0, 0, 60, -90]))), np.sqrt(2))


@given(angles, units)
def test_fields_lie_in_kernel_and_have_paper_zero_components(q, v):
    if abs(shoulder_term(q)) < 1e-3:
        return
    H = column_augmented_jacobian(sc_arm_jacobian(q), v)
    fsm = self_motion_field(q)
    fep = end_point_field(q, v)
    scale = max(1.0, np.abs(fsm).max(), np.abs(fep).max())
    assert np.allclose(H @ fsm, 0.0, atol=1e-9 * scale)
    assert np.allclose(H @ fep, 0.0, atol=1e-9 * scale)
    assert fsm[3] == 0.0 and fsm[4] == 0.0  # no q4 rate, no end-point motion
    assert fep[2] == 0.0  # arm-plane angle kept
    assert np.isclose(fep[4], np.sin(q[3]))  # paper: fifth component S4
    # the printed closed form of f_sm
    c = shoulder_term(q)
    s2, s3, s4, c3 = np.sin(q[1]), np.sin(q[2]), np.sin(q[3]), np.cos(q[2])
    assert np.allclose(fsm, [-c3 * s4**2 / c, s2 * s3 * s4**2 / c, s4, 0.0, 0.0], atol=1e-9 * scale)


@given(angles, units)
def test_minors_scale_is_d3_d5_c_times_paper_scale(q, v):
    if abs(shoulder_term(q, 1.0, 0.7)) < 1e-3:
        return
    c = shoulder_term(q, 1.0, 0.7)
    for paper, minors in (
        (self_motion_field(q, 1.0, 0.7), self_motion_field(q, 1.0, 0.7, "minors")),
        (end_point_field(q, v, 1.0, 0.7), end_point_field(q, v, 1.0, 0.7, "minors")),
    ):
        assert np.allclose(minors, 0.7 * c * paper, atol=1e-9)


def test_raw_det_of_first_three_columns_is_identically_zero():
    rng = np.random.default_rng(3)
    for _ in range(20):
        J = sc_arm_jacobian(rng.uniform(-3, 3, 4), 1.0, 0.8)
        assert abs(np.linalg.det(J[:, :3])) < 1e-12


def test_fields_at_extended_arm_singularity():
    q = np.array([0.3, 0.4, 0.5, 0.0])  # extended arm: S4 = 0
    assert np.allclose(self_motion_field(q), 0.0)
    fep = end_point_field(q, [1.0, 0.0, 0.0])
    assert fep[4] == 0.0 and np.abs(fep[:4]).max() > 0  # end point at rest, joints move


def test_blend_and_minors_scale_at_shoulder_singularity():
    q = np.deg2rad([0, 0, 60, -90])
    v = [1.0, 0.0, 0.0]
    both = sc_blend(q, v, 1.0, 1.0)
    assert np.allclose(both, self_motion_field(q) + end_point_field(q, v))
    assert np.allclose(column_augmented_jacobian(sc_arm_jacobian(q), v) @ both, 0.0)
    q_sh = np.array([0.0, 0.0, 0.0, 0.0])  # wrist on the Z axis: c = 0
    with pytest.raises(InputError, match="shoulder"):
        end_point_field(q_sh, v)
    assert np.isfinite(end_point_field(q_sh, v, scale="minors")).all()


def test_sc_validation():
    with pytest.raises(ShapeError, match="H"):
        signed_minor_null_vector(np.ones((2, 2)))
    with pytest.raises(InputError, match="direction"):
        column_augmented_jacobian(np.eye(2), [0.0, 0.0])
    with pytest.raises(ShapeError, match="q"):
        sc_arm_jacobian([0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="scale"):
        self_motion_field([0.1, 0.2, 0.3, 0.4], scale="bogus")
    with pytest.raises(InputError, match="d3"):
        sc_arm_position([0, 0, 0, 0], d3=-1.0)


def test_natural_motion_crosses_extended_arm_singularity_on_the_line():
    # Nenchev and Tsumaki, run 1: start (0, 0, 0, -90) deg, v_hat = (1, 0, 0), b_sm = 0. With the
    # printed Jacobian, f_ep5 = S4 = -1 at the start, so b_ep = -1 moves the wrist toward +x first.
    q = np.deg2rad([0.0, 0.0, 0.0, -90.0])
    v = [1.0, 0.0, 0.0]
    dt = 0.005

    def f(q):
        return sc_blend(q, v, 0.0, -1.0)[:4]

    s4, rates, pos = [], [], []
    for _ in range(300):  # 1.5 s, RK4
        k1 = f(q)
        k2 = f(q + dt / 2 * k1)
        k3 = f(q + dt / 2 * k2)
        k4 = f(q + dt * k3)
        q = q + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        s4.append(np.sin(q[3]))
        rates.append(np.abs(k1).max())
        pos.append(sc_arm_position(q))
    pos = np.array(pos)
    assert np.allclose(pos[:, 1:], [0.0, 1.0], atol=1e-9)  # stays on the straight line
    assert pos[:, 0].max() > np.sqrt(3) - 1e-3  # reaches the workspace boundary x = sqrt(3)
    assert np.any(np.diff(np.sign(s4)) != 0)  # q4 passes through 0: singularity crossed
    assert max(rates) < 2.0  # with bounded joint rates
    assert pos[-1, 0] < pos[:, 0].max()  # and the motion reverses


def _history(rows):
    return np.array(rows, dtype=float), np.linspace(0.0, 1.0, len(rows))


def test_crossings_of_the_extended_and_folded_arm():
    q4 = np.linspace(-0.5, 0.3, 9)  # through 0 at t = 0.625
    joints, t = _history([[0.2, 0.4, 0.1, a] for a in q4])
    assert singularity_crossings(joints, t) == [(pytest.approx(0.625), "extended")]
    q4 = np.linspace(3.0, 3.3, 7)  # through pi (d5 < d3: the folded wrist is off the Z axis)
    joints, t = _history([[0.2, 0.4, 0.1, a] for a in q4])
    [(t_cross, kind)] = singularity_crossings(joints, t, d3=1.0, d5=0.5)
    assert kind == "folded" and t_cross == pytest.approx((np.pi - 3.0) / 0.3, abs=1e-3)


def test_crossing_of_the_shoulder_singularity_and_not_of_c_elsewhere():
    # q3 = 0, q4 = -1.2: the wrist is on the Z axis at q2 = 0.6
    joints, t = _history([[0.0, a, 0.0, -1.2] for a in np.linspace(0.5, 0.7, 11)])
    [(t_cross, kind)] = singularity_crossings(joints, t)
    assert kind == "shoulder" and t_cross == pytest.approx(0.5, abs=1e-3)
    # c = d5 C3 S4 changes sign at q3 = pi/2 with the wrist 1 m from the axis: not singular
    joints, t = _history([[0.0, 0.0, a, -np.pi / 2] for a in np.linspace(1.4, 1.7, 7)])
    assert singularity_crossings(joints, t) == []
    with pytest.raises(ShapeError, match="joints"):
        singularity_crossings(np.zeros((3, 3)), np.zeros(3))
