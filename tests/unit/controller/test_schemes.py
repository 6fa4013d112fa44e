"""Controller: scheme identities from the papers, closed-loop behaviour, results and errors."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.controller import Controller, StepResult
from uvms_qp.errors import InputError, UnknownSolverError
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import (
    EndEffectorTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
    motion_distribution_weights,
)


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


def _equality_stack(model, rng):
    q = model.random_configuration(rng)
    state = model.state(q)
    target = state.position("tool") + rng.normal(scale=0.1, size=3)
    return state, Stack(levels=[
        Level(EndEffectorTask(position=target, gain=1.5)),
        Level(StationKeepingTask(axes=["x", "y", "z", "psi"],
                                 target=list(rng.normal(scale=0.2, size=4)), gain=1.0)),
        Level(PostureTask(posture=list(model.split(q)[1] + 0.1), gain=0.5)),
    ])


@pytest.mark.parametrize("seed", range(4))
def test_nullspace_scheme_equals_hqp_without_active_bounds(rov, seed):
    """Equality levels, no bounds: the lexicographic QP is the recursive null-space solution
    (000 Eq. (10) extended, weighted pseudoinverse of Eq. (17))."""
    rng = np.random.default_rng(seed)
    state, stack = _equality_stack(rov, rng)
    W = motion_distribution_weights(rov, beta=0.7, w_max=0.5)
    qp = Controller(rov, stack, solver="daqp", dt=0.05, metric=W).step(state)
    ns = Controller(rov, stack, dt=0.05, metric=W, scheme="nullspace").step(state)
    assert ns.solver == "nullspace" and not ns.saturated
    np.testing.assert_allclose(qp.zeta, ns.zeta, atol=1e-6)


@pytest.mark.parametrize("weight", [1e-20, 1e12])
def test_nullspace_scheme_ignores_the_scale_of_a_level(rov, weight):
    """Scaling all rows of a level by a weight leaves the priority solution unchanged: the rank
    decision is relative to each level's own rows (a level of tiny weight is not dropped)."""
    rng = np.random.default_rng(11)
    q = rov.random_configuration(rng)
    state = rov.state(q)
    target = state.position("tool") + rng.normal(scale=0.1, size=3)
    posture = list(rov.split(q)[1] + 0.1)

    def stack(w):
        return Stack(levels=[Level(EndEffectorTask(position=target, gain=1.5)),
                             Level(PostureTask(posture=posture, gain=0.5, weight=w))])

    plain = Controller(rov, stack(1.0), dt=0.05, scheme="nullspace").step(state)
    scaled = Controller(rov, stack(weight), dt=0.05, scheme="nullspace").step(state)
    qp = Controller(rov, stack(1.0), solver="daqp", dt=0.05).step(state)
    np.testing.assert_allclose(plain.zeta, qp.zeta, atol=1e-6)
    np.testing.assert_allclose(scaled.zeta, plain.zeta, atol=1e-8)


def test_gradient_projection_identity_eq4():
    """Tracking level + manipulability ascend level = J^+ x_dot + (I - J^+ J) lambda grad w."""
    arm = load_model("nenchev_pa10_arm")
    rng = np.random.default_rng(5)
    q = arm.random_configuration(rng)
    state = arm.state(q)
    target = state.position("tool") + np.array([0.05, -0.02, 0.03])
    ee = EndEffectorTask(position=target, gain=2.0)
    manip = ManipulabilityTask(mode="ascend", gain=0.7)
    result = Controller(arm, Stack(levels=[Level(ee), Level(manip)]), dt=0.05).step(state)
    J = state.jacobian("tool", rows="position")
    Jp = np.linalg.pinv(J)
    _, grad = manip.compute_value(state)
    expected = Jp @ (2.0 * (target - state.position("tool"))) + (
        np.eye(arm.nv) - Jp @ J) @ (0.7 * grad)
    np.testing.assert_allclose(result.zeta, expected, atol=1e-6)


def test_weighted_scheme_only_approaches_priorities(rov):
    """Priorities as weights: the top task gives way (less as the ratio grows); HQP meets it."""
    rng = np.random.default_rng(2)
    state, stack = _equality_stack(rov, rng)
    hqp = Controller(rov, stack, dt=0.05).step(state)
    assert hqp.level_violations[0] < 1e-8
    top = []
    for ratio in (1.0, 1e2, 1e4):
        weighted = Controller(rov, stack, dt=0.05, scheme="weighted", priority_ratio=ratio)
        assert weighted.solver_name == "cascade:daqp"  # DAQP's hierarchy would drop weights
        top.append(weighted.step(state).level_violations[0])
    assert top[0] > 1e-3 and top[0] > top[1] > top[2]


def test_closed_loop_tracks_and_keeps_bounds(rov):
    """Drive the tool toward a far target: joints stay inside their limits, rates within bounds,
    the vehicle moves only when the arm cannot reach."""
    q = rov.home()
    p0 = rov.frame_pose(q, "tool")[:3, 3]
    eta0, joints0 = rov.split(q)
    reachable = rov.frame_pose(rov.configuration(eta0, joints0 + np.array([0.2, 0.15, -0.2, 0.1])),
                               "tool")[:3, 3]  # the arm alone reaches it
    near = EndEffectorTask(position=reachable, gain=1.0, name="ee")
    stack = Stack(
        levels=[Level(near),
                Level(StationKeepingTask(axes=["x", "y", "z", "phi", "theta", "psi"]))],
        constraints=[JointPositionBounds(gain=0.5), JointVelocityBounds(),
                     VehicleRateBounds(linear=0.3, angular=0.2)])
    ctrl = Controller(rov, stack, dt=0.05)
    for k in range(100):
        result = ctrl.step(rov.state(q), 0.05 * k)
        assert result.ok and result.bound_violation <= 1e-7
        q = rov.integrate(q, result.zeta, 0.05)
    assert np.linalg.norm(rov.frame_pose(q, "tool")[:3, 3] - reachable) < 1e-3
    assert np.abs(rov.split(q)[0] - eta0).max() < 1e-6  # reachable: vehicle holds station
    near.set_target(position=p0 + np.array([1.0, 0.0, 0.0]))  # beyond the arm's reach
    for k in range(80):
        result = ctrl.step(rov.state(q), 5.0 + 0.05 * k)
        assert result.bound_violation <= 1e-7
        np.testing.assert_array_less(np.abs(result.zeta[:3]), 0.3 + 1e-9)
        q = rov.integrate(q, result.zeta, 0.05)
        joints = rov.split(q)[1]
        assert np.all(joints >= rov.joint_lower - 1e-9) and np.all(joints <= rov.joint_upper + 1e-9)
    assert np.linalg.norm(rov.split(q)[0][:3] - eta0[:3]) > 0.3  # now the vehicle helps


def test_payload_pickup_reduces_the_moment(rov):
    q = rov.home()
    p0 = rov.frame_pose(q, "tool")[:3, 3]
    payload = PayloadMomentTask(force=0.0, gain=0.3)
    stack = Stack(levels=[Level(EndEffectorTask(position=p0, gain=2.0)),
                          Level(payload), Level(StationKeepingTask())],
                  constraints=[JointPositionBounds(gain=0.5), JointVelocityBounds()])
    ctrl = Controller(rov, stack, dt=0.05)
    for k in range(5):  # no payload: nothing moves
        result = ctrl.step(rov.state(q), 0.05 * k)
        q = rov.integrate(q, result.zeta, 0.05)
    np.testing.assert_allclose(result.zeta, 0.0, atol=1e-9)
    payload.update(force=20.0)  # picked up
    m_start, _ = payload.compute_value(rov.state(q))
    for k in range(100):
        q = rov.integrate(q, ctrl.step(rov.state(q), 0.25 + 0.05 * k).zeta, 0.05)
    m_end, _ = payload.compute_value(rov.state(q))
    assert m_end < 0.8 * m_start
    assert np.linalg.norm(rov.frame_pose(q, "tool")[:3, 3] - p0) < 1e-3  # tool held in place


def test_manipulability_floor_holds_in_closed_loop(rov):
    q = rov.home()
    manip = ManipulabilityTask(mode="floor", minimum=0.0, gain=5.0)
    w0, _ = manip.bind(rov).compute_value(rov.state(q))
    manip.update(minimum=0.8 * w0)
    p0 = rov.frame_pose(q, "tool")[:3, 3]
    far = EndEffectorTask(position=p0 + np.array([0.5, 0.0, 0.0]))
    stack = Stack(levels=[Level(manip), Level(far)],
                  constraints=[JointVelocityBounds(), VehicleRateBounds(linear=0.2, angular=0.2)])
    ctrl = Controller(rov, stack, dt=0.05)
    lowest = w0
    for k in range(80):
        q = rov.integrate(q, ctrl.step(rov.state(q), 0.05 * k).zeta, 0.05)
        lowest = min(lowest, manip.compute_value(rov.state(q))[0])
    assert lowest >= 0.8 * w0 * (1 - 1e-2)


def test_step_result_reports_residuals_with_units(rov):
    state = rov.state(rov.home())
    stack = Stack(levels=[Level(EndEffectorTask(position=[0, 0, 0], name="reach")),
                          Level(PostureTask(), StationKeepingTask())])
    result = Controller(rov, stack, dt=0.05).step(state, 1.5)
    assert isinstance(result, StepResult)
    assert set(result.task_residuals) == {"reach", "posture", "station_keeping"}
    norm, unit = result.task_residuals["reach"]
    assert unit == "m/s" and norm >= 0.0  # position-only: rows in m/s
    assert result.task_errors["reach"][0] == pytest.approx(
        np.linalg.norm(state.position("tool")), rel=1e-12)
    text = result.summary()
    for word in ("reach", "posture", "station_keeping", "[rad/s]", "level 1", result.status.value):
        assert word in text
    assert result.step_time > 0 and result.t == 1.5 and np.all(np.isfinite(result.zeta))


def test_controller_rejects_bad_input(rov):
    stack = Stack(levels=[Level(PostureTask())])
    with pytest.raises(InputError, match="dt"):
        Controller(rov, stack, dt=0.0)
    with pytest.raises(InputError, match="scheme"):
        Controller(rov, stack, scheme="fuzzy")
    with pytest.raises(InputError, match="metric"):
        Controller(rov, stack, metric=[1.0, 2.0])
    with pytest.raises(UnknownSolverError):
        Controller(rov, stack, solver="cplex")
    other = load_model("wang_9dof")
    ctrl = Controller(rov, stack)
    with pytest.raises(InputError, match="another model"):
        ctrl.step(other.state(other.neutral()))


def test_shaping_level_reproduces_eq21_on_the_planar_urvm():
    """Soylu et al. (2007), Eq. (21), unweighted, no bounds: tracking level + [station keeping
    blended by (1 - k); manipulability shaping] level equals the closed form
    J_p^+ (x_dot + K_p e_p) + (I - J_p^+ J_p)((1 - k) J_s^+ K_s e_s + k s lambda grad rho)."""
    model = load_model("soylu_planar")
    q = model.configuration([0.1, -0.2, 0.3], [np.pi / 3, -np.pi / 3, np.pi / 3])
    state = model.state(q)
    manip = ManipulabilityTask(mode="shaping", threshold=1.0, gain=10.0, name="dex")
    w, grad = manip.bind(model).compute_value(state)
    manip.update(threshold=1.5 * w)  # 1/2 < w / threshold < 1: 0 < k < 1
    k = manip.shaping_factor(state)
    assert 0.05 < k < 0.95
    target = state.position("tool") + np.array([0.1, 0.05, 0.0])
    held = np.array([0.0, 0.0, 0.0])
    station = StationKeepingTask(target=list(held), gain=[10.0, 10.0, 100.0], blend="dex")
    stack = Stack(levels=[Level(EndEffectorTask(position=target, gain=10.0)),
                          Level(station, manip)])
    zeta = Controller(model, stack, dt=0.01).step(state, 0.0).zeta  # K_s dt <= 1
    Jp = state.jacobian("tool", rows="position")[:2]
    Js = state.vehicle_pose_jacobian()
    e_s = held - model.split(q)[0]
    rho_grad = np.r_[np.zeros(3), grad]
    Jp_pinv = np.linalg.pinv(Jp)
    secondary = (1 - k) * np.linalg.pinv(Js) @ (np.array([10.0, 10.0, 100.0]) * e_s) \
        + k * 10.0 * rho_grad  # sign switch open at the first tick (rho_dot = 0)
    expected = Jp_pinv @ (10.0 * (target - state.position("tool"))[:2]) \
        + (np.eye(6) - Jp_pinv @ Jp) @ secondary
    np.testing.assert_allclose(zeta, expected, atol=1e-6)


def test_blend_must_name_a_shaping_task(rov):
    with pytest.raises(InputError, match="no task named 'dex'"):
        Stack(levels=[Level(StationKeepingTask(blend="dex"))]).bind(rov)
    with pytest.raises(InputError, match="mode 'shaping'"):
        Stack(levels=[Level(StationKeepingTask(blend="m"),
                            ManipulabilityTask(mode="ascend", name="m"))]).bind(rov)


def test_controller_follows_per_tick_row_weights(rov):
    """Row weights that change every tick (joint-limit damping, Eq. (17)) reach the solver."""
    from uvms_qp.tasks import JointLimitTask

    damping = JointLimitTask(mode="damping")
    stack = Stack(levels=[Level(EndEffectorTask(position=[0.6, 0.1, -0.1])), Level(damping)])
    ctrl = Controller(rov, stack, dt=0.05)
    for joints in ([0.1, 1.9, 3.3, 3.1], [3.0, 0.2, 1.0, 6.0]):
        state = rov.state(rov.configuration(np.zeros(6), joints))
        ctrl.step(state)
        weights = ctrl.slot("joint_limit").row_weights  # this tick's, in the controller's slot
        np.testing.assert_allclose(weights[[0, 2]], [630.8361082206034, 88.17860422405862]
                                   if joints[0] == 0.1 else weights[[0, 2]])
        np.testing.assert_allclose(ctrl.assembler.problem.w[3:], weights)
        np.testing.assert_allclose(ctrl.level_rows(state)[1].weights, weights)
        np.testing.assert_allclose(damping.rows(state).weights, weights)


def test_non_finite_rows_name_the_task(rov):
    from uvms_qp.errors import NonFiniteError

    class Broken(PostureTask):
        type_name = "broken"

        def error_rows(self, state, t, slot):
            J, e, ff = super().error_rows(state, t, slot)
            e[1] = np.nan
            return J, e, ff

    stack = Stack(levels=[Level(EndEffectorTask(position=[0.5, 0.0, 0.0])),
                          Level(Broken(name="bad"))])
    with pytest.raises(NonFiniteError, match="'bad'"):
        Controller(rov, stack).step(rov.state(rov.home()))


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
@pytest.mark.parametrize("where", ["A_nan", "A_inf", "side_nan"])
def test_non_finite_rows_name_the_task_and_the_next_tick_recovers(solver, where):
    from uvms_qp.errors import NonFiniteError
    from uvms_qp.model import load_model
    from uvms_qp.stack import Level, Stack
    from uvms_qp.tasks import EndEffectorTask, PostureTask

    class Flaky(PostureTask):
        broken = False

        def error_rows(self, state, t, slot):
            J, e, ff = super().error_rows(state, t, slot)
            if self.broken:
                J = np.array(J)
                if where == "A_nan":
                    J[0, -1] = np.nan
                elif where == "A_inf":
                    J[0, -1] = np.inf
                else:
                    e[0] = np.nan
            return J, e, ff

    model = load_model("bluerov2_heavy_alpha5")
    flaky = Flaky(gain=0.5, name="flaky_posture")
    stack = Stack(levels=[Level(EndEffectorTask(position=[0.5, 0.1, 0.4], gain=1.0)),
                          Level(flaky)])
    ctrl = Controller(model, stack, solver=solver, dt=0.05)
    state = model.state(model.neutral())
    good = ctrl.step(state, 0.0)
    flaky.broken = True
    with pytest.raises(NonFiniteError, match="flaky_posture"):
        ctrl.step(state, 0.05)
    flaky.broken = False
    again = ctrl.step(state, 0.1)
    assert again.ok and again.stage == "primary"
    np.testing.assert_allclose(again.zeta, good.zeta, atol=1e-9)


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
def test_weight_update_at_run_time_reaches_the_solver(solver):
    """Two conflicting posture tasks in one level: the joint rates are their weighted mean."""
    from uvms_qp.model import load_model
    from uvms_qp.stack import Level, Stack
    from uvms_qp.tasks import PostureTask

    model = load_model("bluerov2_heavy_alpha5")
    q = model.home()
    joints = model.split(q)[1]
    a = PostureTask(posture=(joints + 0.2).tolist(), gain=1.0, name="a")
    b = PostureTask(posture=(joints - 0.2).tolist(), gain=1.0, name="b")
    ctrl = Controller(model, Stack(levels=[Level(a, b)]), solver=solver, dt=0.05)
    state = model.state(q)
    nj = model.n_joints
    for wa, wb in ((1.0, 1.0), (3.0, 1.0), (1.0, 4.0)):
        a.update(weight=wa)
        b.update(weight=wb)
        result = ctrl.step(state, 0.0)
        rates = result.zeta[-nj:]
        # the reported level residual is the weighted one, with the new weights
        ra, rb = rates - 0.2, rates + 0.2  # row values minus targets (K = 1)
        weighted = np.sqrt(wa * ra @ ra + wb * rb @ rb)
        assert result.hierarchy.level_residuals[0] == pytest.approx(weighted, rel=1e-9)
        # the weighted compromise on every back-end (DAQP through per-row soft weights)
        np.testing.assert_allclose(rates, (wa * 0.2 - wb * 0.2) / (wa + wb), atol=1e-7)


@pytest.mark.parametrize("kwargs", [{"scheme": "nullspace"}, {"solver": "nullspace"},
                                    {"scheme": "weighted", "solver": "nullspace"}])
def test_equality_only_solvers_refuse_inequality_tasks_at_construction(rov, kwargs):
    """The closed form cannot solve inequality rows: refused up front, naming the tasks, instead
    of failing over to another back-end on every step."""
    from uvms_qp.tasks import JointLimitTask

    stack = Stack(levels=[Level(EndEffectorTask(position=[0.5, 0.0, 0.0])),
                          Level(JointLimitTask(mode="margin", name="limits"), PostureTask())])
    with pytest.raises(InputError, match="inequality tasks: limits"):
        Controller(rov, stack, **kwargs)


def test_counts_of_stages_and_statuses(rov):
    stack = Stack(levels=[Level(EndEffectorTask(position=[0.5, 0.1, 0.0])), Level(PostureTask())],
                  constraints=[JointVelocityBounds()])
    ctrl = Controller(rov, stack)
    state = rov.state(rov.home())
    for k in range(4):
        ctrl.step(state, 0.05 * k)
    assert ctrl.stage_counts == {"primary": 4}
    assert sum(ctrl.status_counts.values()) == 4
    assert set(ctrl.status_counts) <= {"optimal"}
