"""Closed loop: the command is a signal a vehicle and an arm can follow.

The README's stack and two arms with a goal just beyond their reach (a DH-built and a URDF arm,
whose elbows end at the stretched-arm singularity) are run in closed loop with the library's
default options; without damping the first bangs its pitch rate and two joints between their
bounds every tick, the others their elbow and shoulder.
"""

from __future__ import annotations

import numpy as np
import pytest

import uvms_qp
from tests.support.closed_loop_examples import (
    ARMS,
    DT,
    arm_stack,
    beyond_reach,
    dh_arm,
    readme_bounds,
    readme_goal,
    readme_model,
    readme_stack,
    run,
)
from tests.support.pushing import JointRateTask
from uvms_qp import Controller, Level, Stack
from uvms_qp.constraints import (
    CommandRateBounds,
    JointPositionBounds,
    JointVelocityBounds,
    VehicleRateBounds,
)
from uvms_qp.controller.history import command_reversals
from uvms_qp.errors import InputError, SolverError
from uvms_qp.hqp import Status
from uvms_qp.hqp.backends.daqp_binding import open_daqp
from uvms_qp.hqp.certificate import certify
from uvms_qp.tasks import (
    EndEffectorTask,
    ManipulabilityTask,
    PostureTask,
    StationKeepingTask,
    Task,
)


@pytest.fixture(scope="module")
def readme_run():
    model = readme_model()
    goal = readme_goal(model)
    commands, results, q = run(model, readme_stack(goal), model.home(), 200)
    return model, goal, commands, results, q


def test_the_readme_stack_settles_without_chatter(readme_run):
    model, goal, commands, _, q = readme_run
    bounds = readme_bounds(model)
    reversals = command_reversals(commands[50:], bounds)  # the last 150 steps
    assert reversals.max() <= 10, dict(zip(model.zeta_names, reversals.tolist(), strict=True))
    state = model.state(q)
    assert np.linalg.norm(state.position("tool") - goal) < 1e-3
    roll, pitch = state.eta[3:5]
    assert abs(roll) < 0.05 and abs(pitch) < 0.05
    # once settled, the command changes by a small fraction of the bang-bang figure 2 bound / dt
    change = np.abs(np.diff(commands[20:], axis=0)) / DT
    assert np.all(change.max(axis=0) < 0.1 * 2 * bounds / DT)


def test_a_station_keeping_level_in_conflict_with_the_tool_does_not_chatter():
    """The README's stack holding only x, y, z and yaw: the station-keeping level, unmet and
    nearly singular in the freedom the tool level leaves, is damped instead of banging the
    vehicle's angular rates and two joints between their bounds."""
    model = readme_model()
    goal = readme_goal(model)
    station = StationKeepingTask(axes=["x", "y", "z", "psi"], gain=1.0)
    commands, results, q = run(model, readme_stack(goal, station), model.home(), 200)
    assert command_reversals(commands[50:], readme_bounds(model)).max() <= 10
    assert np.linalg.norm(model.state(q).position("tool") - goal) < 1e-3
    assert any(r.damped_levels for r in results[50:])


def test_the_step_result_reports_the_controllers_reversals(readme_run):
    results = readme_run[3]
    last = results[-1]
    assert last.reversals_per_s == pytest.approx(0.0)
    assert "reversals" in last.summary()


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_an_arm_at_its_singularity_does_not_bang_between_its_bounds(arm):
    make, shoulder = ARMS[arm]
    model = make()
    goal, reach = beyond_reach(model, shoulder)
    stack = arm_stack(goal)
    commands, _, q = run(model, stack, model.home(), 200)
    rates = np.asarray(model.joint_rate_limit)
    assert np.all(np.abs(commands) <= rates + 1e-9)
    late = commands[round(1.0 / DT):]
    per_second = command_reversals(late, rates) / (late.shape[0] * DT)
    assert per_second.max() <= 0.5
    # the largest change per step [rad/s^2]: never a jump across the box (the bang-bang figure
    # 2 bound / dt), and once the arm has stretched (last 5 s) a small fraction of it
    bang = 2 * rates / DT
    change = np.abs(np.diff(late, axis=0)) / DT
    assert np.all(change.max(axis=0) < 0.25 * bang)
    assert np.all(change[-100:].max(axis=0) < 0.01 * bang)
    state = model.state(q)  # the arm ends stretched toward the goal, as close as it can be
    assert np.linalg.norm(state.position("tool") - goal) == pytest.approx(0.02 * reach, rel=0.02)


# ------------------------------------------------------------------------------- damping


class _RateTask(Task):
    """The tool's linear velocity equal to a fixed rate [m/s] (a reference level)."""

    type_name = "tool_rate"

    def __init__(self, rate):
        super().__init__(name="tool_rate")
        self.rate = np.asarray(rate, dtype=float)

    def _bind(self, model):
        return 3

    def evaluate(self, state, t, slot):
        return state.jacobian("tool", "position"), self.rate, self.rate


def _arm_stack(model, goal, *lower):
    return Stack(constraints=[JointVelocityBounds(scale=100.0)],
                 levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0)), *lower])


def test_away_from_singularities_damping_changes_nothing():
    """Along the README's run, at every step where no level is near a singularity, the damped
    controller adds no row and returns the undamped controller's answer, which the certificate
    proves the lexicographic optimum of the user's problem (every level met or certified), or
    which both report unproven (a level the certificate cannot prove to 1e-6)."""
    model = readme_model()
    q = model.home()
    stack = readme_stack(readme_goal(model))
    damped = Controller(model, stack, dt=DT)
    plain = Controller(model, stack.copy(), dt=DT, damping=0.0)
    compared = proven = 0
    for k in range(200):
        state = model.state(q)
        result, reference = damped.step(state, k * DT), plain.step(state, k * DT)
        if not result.damped_levels:
            assert result.status == reference.status
            np.testing.assert_allclose(result.zeta, reference.zeta, rtol=1e-9, atol=1e-12)
            certificate = certify(damped.assembler.problem, result.zeta,
                                  least_distance=open_daqp)
            assert certificate.ok or result.status is Status.UNPROVEN, certificate
            proven += certificate.ok
            compared += 1
        q = model.integrate(q, result.zeta, DT)
    assert compared > 150 and proven > 0.9 * compared


def _stretched_dh():
    """The DH arm stretched toward a goal 2 % beyond its reach, elbow 0.02 rad from straight."""
    model = dh_arm()
    goal, _ = beyond_reach(model, "link1")
    state = model.state(model.home())
    joints = np.array(state.joints)
    joints[2] = 0.02
    return model, goal, model.state(model.configuration(state.eta, joints))


def test_the_closed_form_and_the_qp_agree_on_a_damped_level():
    """Equality levels and no active bound: the null-space scheme and the QP solve the same
    damped problem (the damping rows are rows of the level)."""
    model, goal, state = _stretched_dh()
    posture = PostureTask(posture=[0.5, 0.2, 0.1], gain=0.5)
    stack = _arm_stack(model, goal, Level(posture))
    qp = Controller(model, stack, dt=DT).step(state)
    closed = Controller(model, stack, dt=DT, scheme="nullspace").step(state)
    assert qp.damped_levels == closed.damped_levels == (0,)
    assert qp.status == closed.status == "damped" and not closed.saturated
    np.testing.assert_allclose(qp.zeta, closed.zeta, atol=1e-7)
    weighted = Controller(model, stack, dt=DT, scheme="weighted").step(state)
    assert weighted.damped_levels == (0,) and weighted.ok


def test_a_damped_level_leaves_the_lower_levels_their_freedom():
    """The damped tool level fixes what its rows achieve, nothing more: the posture level below
    gets exactly what it gets when the tool level asks for that achieved rate undamped."""
    model, goal, state = _stretched_dh()
    posture = Level(PostureTask(posture=[0.5, 0.2, 0.1], gain=0.5))
    damped = Controller(model, _arm_stack(model, goal, posture), dt=DT).step(state)
    assert damped.damped_levels == (0,)
    assert "damped near a singularity" in damped.summary()
    achieved = state.jacobian("tool", "position") @ damped.zeta  # [m/s]
    still = Stack(constraints=[JointVelocityBounds(scale=100.0)], levels=[
        Level(_RateTask(achieved)), Level(PostureTask(posture=[0.5, 0.2, 0.1], gain=0.5))])
    reference = Controller(model, still, dt=DT, damping=0.0).step(state)
    np.testing.assert_allclose(damped.zeta, reference.zeta, atol=1e-7)
    assert damped.task_residuals["posture"][0] == pytest.approx(
        reference.task_residuals["posture"][0], abs=1e-7)


def _primary_fails_on_damped_problems(controller, monkeypatch):
    """Make the primary back-end fail on every problem but the stack's own (the damped ones), as
    a cascade past its time cap does."""
    primary, own = controller.safe.primary, controller.assembler.problem
    solve = primary.solve_problem

    def failing(problem, *args, **kwargs):
        if problem is not own:
            raise SolverError("deadline reached")
        return solve(problem, *args, **kwargs)

    monkeypatch.setattr(primary, "solve_problem", failing)


def test_a_damped_problem_the_primary_cannot_answer_goes_to_the_alternate(monkeypatch):
    """The stretched DH arm with a primary that fails on every damped problem: the alternate
    back-end answers them (stage ``alternate``, the report says why) and the command stays
    as smooth as with a working primary."""
    model = dh_arm()
    goal, _ = beyond_reach(model, "link1")
    controller = Controller(model, arm_stack(goal), solver="cascade:quadprog", dt=DT)
    _primary_fails_on_damped_problems(controller, monkeypatch)
    q, commands, damped = model.home(), [], 0
    for k in range(200):
        result = controller.step(model.state(q), k * DT)
        if result.damped_levels:
            damped += 1
            assert result.stage == "alternate"
            assert any("primary: no verified answer to the damped problem" in a
                       for a in result.attempts)
        commands.append(result.zeta)
        q = model.integrate(q, result.zeta, DT)
    rates = np.asarray(model.joint_rate_limit)
    late = np.array(commands)[round(1.0 / DT):]
    assert damped > 100
    assert (command_reversals(late, rates) / (late.shape[0] * DT)).max() <= 0.5


def test_a_damped_problem_past_the_deadline_goes_to_no_other_back_end(monkeypatch):
    """Past the step's deadline the optional solves stop: no alternate solve of the damped
    problem, the undamped answer kept and the step reported late."""
    model = dh_arm()
    goal, _ = beyond_reach(model, "link1")
    controller = Controller(model, arm_stack(goal), solver="cascade:quadprog", dt=DT,
                            deadline=0.01)
    now = [0.0]
    controller.safe.clock = lambda: now[0]
    primary, own = controller.safe.primary, controller.assembler.problem
    solve = primary.solve_problem

    def slow(problem, *args, **kwargs):  # a primary past the deadline on the damped problems
        if problem is not own:
            now[0] += 1.0
            raise SolverError("deadline reached")
        return solve(problem, *args, **kwargs)

    monkeypatch.setattr(primary, "solve_problem", slow)
    alternate_solve = controller.safe.alternate.solve_problem
    monkeypatch.setattr(controller.safe.alternate, "solve_problem",
                        lambda problem, *args, **kwargs: pytest.fail(
                            "the alternate ran past the deadline")
                        if problem is not own else alternate_solve(problem, *args, **kwargs))
    q, late, said = model.home(), 0, 0
    for k in range(100):
        result = controller.step(model.state(q), k * DT)
        assert not result.damped_levels
        late += result.deadline_missed
        said += any("damping: the step's deadline passed" in a for a in result.attempts)
        q = model.integrate(q, result.zeta, DT)
    assert late > 50  # every step whose damped problem the primary tried
    assert said == late  # and each says why its damping is missing


def test_a_damped_problem_no_back_end_answers_is_reported(monkeypatch):
    model = dh_arm()
    goal, _ = beyond_reach(model, "link1")
    controller = Controller(model, arm_stack(goal), solver="cascade:quadprog", dt=DT)
    _primary_fails_on_damped_problems(controller, monkeypatch)
    monkeypatch.setattr(controller.safe, "alternate", None)
    q = model.home()
    for k in range(60):
        result = controller.step(model.state(q), k * DT)
        q = model.integrate(q, result.zeta, DT)
    assert not result.damped_levels and result.stage == "primary"
    assert any("damping: no back-end answered" in a for a in result.attempts)


# ---------------------------------------------------------------------------- activation


def _posture_run(ramp, steps=100, insert=40):
    """The README's tool task and a posture task that enters the stack at step ``insert``."""
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    q = model.home()
    goal = model.frame_pose(q, "tool")[:3, 3] + [0.1, 0.05, 0.0]
    posture = PostureTask(posture=[2.6, 1.3, 1.3, 2.6], gain=1.0)
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds(),
                               VehicleRateBounds(linear=0.5, angular=0.3)],
                  levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0)),
                          Level(posture), Level(StationKeepingTask(gain=1.0))])
    stack.set_activation("posture", 0.0)
    controller = Controller(model, stack, dt=DT)
    commands, results = [], []
    for k in range(steps):
        if k == insert:
            stack.set_activation("posture", 1.0, ramp=ramp)
        result = controller.step(model.state(q), t=k * DT)
        commands.append(result.zeta.copy())
        results.append(result)
        q = model.integrate(q, result.zeta, DT)
    return np.array(commands), results


def test_a_task_ramped_into_the_stack_does_not_step_the_command():
    stepped, _ = _posture_run(ramp=0.0)
    ramped, results = _posture_run(ramp=1.0)
    assert all(r.inactive == ("posture",) for r in results[:40])
    assert [r.status for r in results[40:41]] != ["blended"]  # activation 0 at the ramp's start
    assert all(r.status == "blended" and 0.0 < r.ramping["posture"] < 1.0
               for r in results[41:60])
    assert all(not r.ramping and not r.inactive for r in results[60:])
    jump = np.abs(np.diff(stepped[38:43], axis=0)).max()  # the insertion as a step
    assert jump > 0.1  # [rad/s]: the posture task asks for a different motion
    smooth = np.abs(np.diff(ramped[38:65], axis=0)).max()
    assert smooth < 0.25 * jump
    np.testing.assert_array_equal(ramped[:40], stepped[:40])  # the same run until then


def test_a_task_ramped_out_leaves_without_a_step():
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    q = model.home()
    goal = model.frame_pose(q, "tool")[:3, 3] + [0.1, 0.05, 0.0]
    posture = PostureTask(posture=[2.6, 1.3, 1.3, 2.6], gain=1.0)
    stack = Stack(constraints=[JointVelocityBounds(), VehicleRateBounds(linear=0.5, angular=0.3)],
                  levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0)),
                          Level(posture)])
    controller = Controller(model, stack, dt=DT)
    commands = []
    for k in range(60):
        if k == 20:
            stack.set_activation("posture", 0.0, ramp=1.0)
        result = controller.step(model.state(q), t=k * DT)
        commands.append(result.zeta.copy())
        q = model.integrate(q, result.zeta, DT)
    assert result.inactive == ("posture",)
    change = np.abs(np.diff(np.array(commands)[15:45], axis=0)).max()
    assert change < 0.05  # [rad/s] per step, against a posture demand of tenths of rad/s


# ------------------------------------------------------------------- command-rate bounds


def test_command_rate_bounds_hold_in_closed_loop_from_rest():
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    q = model.home()
    goal = model.frame_pose(q, "tool")[:3, 3] + [0.3, 0.1, 0.0]
    stack = readme_stack(goal)
    limit = CommandRateBounds(joint=1.0, linear=1.0, angular=2.0)
    stack = Stack(levels=list(stack.levels), constraints=[*stack.constraints, limit])
    commands, _, q = run(model, stack, q, 200)
    change = np.abs(np.diff(commands, axis=0, prepend=0.0)) / DT  # from rest
    assert np.all(change <= np.array([1.0] * 3 + [2.0] * 3 + [1.0] * 4) + 1e-9)
    assert np.linalg.norm(model.state(q).position("tool") - goal) < 1e-3


def test_the_joint_position_limit_wins_over_the_command_rate_bound():
    """axis_c 0.05 rad below its upper limit, moving up at 0.5 rad/s, a task pushing it on: the
    command may lose no more than 0.05 rad/s per step, too slow to stop in time; the position
    bound holds and the command-rate bound gives way at the limit."""
    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    eta, joints = model.split(model.home())
    joints = np.array(joints)
    upper = float(model.joint_upper[2])
    joints[2] = upper - 0.05
    q = model.configuration(eta, joints)
    start = np.zeros(model.nv)
    start[8] = 0.5
    limit = CommandRateBounds(joint=1.0, linear=1.0, angular=1.0, initial=list(start))
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds(), limit],
                  levels=[Level(JointRateTask([0.0, 0.0, 2.0, 0.0]))])  # [rad/s]
    commands, results, _ = [], [], q
    controller = Controller(model, stack, dt=DT)
    for k in range(10):
        result = controller.step(model.state(q), t=k * DT)
        commands.append(result.zeta[8])
        results.append(result)
        q = model.integrate(q, result.zeta, DT)
        assert model.split(q)[1][2] <= upper + 1e-12  # never beyond the limit
    drops = -np.diff(np.array([0.5, *commands]))
    assert drops.max() > 1.0 * DT + 1e-9  # the acceleration bound gave way, once, at the limit
    assert abs(commands[-1]) < 1e-9


# ------------------------------------------------------------------------ set-based rows


@pytest.mark.parametrize("gain", [1.0 / DT, 5.0])
def test_a_floor_within_the_period_condition_settles_on_its_bound(gain):
    """The DH arm stretching toward a goal beyond its reach under a manipulability floor of the
    level above: with ``gain * dt <= 1`` the measure approaches the floor from above, crosses it
    by no more than the second-order error of one Euler step, and the command settles without a
    reversal."""
    model = dh_arm()
    goal, _ = beyond_reach(model, "link1", factor=1.2)
    floor = ManipulabilityTask(mode="floor", minimum=0.02, gain=gain)
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds()],
                  levels=[Level(floor), Level(EndEffectorTask("tool", position=goal, gain=2.0))])
    controller = Controller(model, stack, dt=DT)
    q, measures, commands = model.home(), [], []
    for k in range(200):
        state = model.state(q)
        measures.append(floor.compute_value(state)[0])
        result = controller.step(state, t=k * DT)
        commands.append(result.zeta.copy())
        q = model.integrate(q, result.zeta, DT)
    w = np.array(measures)
    assert w[0] > 0.02 and w.min() >= 0.02 * (1.0 - 5e-3)
    assert w[-1] == pytest.approx(0.02, abs=1e-4)  # on the floor: the arm stretched to it
    late = np.array(commands)[round(1.0 / DT):]
    assert command_reversals(late, np.asarray(model.joint_rate_limit)).max() == 0


def test_a_floor_beyond_the_arms_best_settles_on_the_maximum_of_the_measure():
    """A manipulability floor above anything the arm reaches (its best is about 0.0048 m^3):
    the gradient vanishes at the maximum, where an uncapped floor row asks for rates the box
    clips and the command bangs between its bounds every period. The arm climbs to the maximum
    without ever losing measure and stops there."""
    model = readme_model()
    floor = ManipulabilityTask(mode="floor", minimum=0.006)
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds()],
                  levels=[Level(floor)])
    commands, results, q = run(model, stack, model.home(), 200)
    measures = [r.task_errors["manipulability"][0] for r in results]
    w, grad = floor.compute_value(model.state(q))
    assert np.diff(measures).min() >= 0.0
    assert np.linalg.norm(grad) / w < 1e-2  # [1/rad]: on the maximum, not short of it
    arm = commands[round(1.0 / DT):, model.n_vehicle:]
    assert command_reversals(arm, np.asarray(model.joint_rate_limit)).max() == 0
    assert np.abs(commands[-1]).max() < 1e-3


def test_a_floor_that_overshoots_is_refused_with_the_largest_gain():
    model = dh_arm()
    stack = Stack(levels=[Level(ManipulabilityTask(mode="floor", minimum=0.02, gain=40.0))])
    with pytest.raises(InputError, match=r"levels\[0\].tasks\[0\] \(manipulability\).*"
                                         r"gain \* dt = 40 \* 0.05 = 2 > 1.*gain <= 20"):
        Controller(model, stack, dt=DT)
    Controller(model, stack, dt=0.025)  # the same gain at a shorter period is fine


@pytest.mark.parametrize("task", [
    lambda: EndEffectorTask("tool", position=[0.5, 0.0, 0.2], gain=[2.0, 2.0, 40.0]),
    lambda: PostureTask(gain=50.0),
])
def test_a_tracking_gain_that_never_settles_is_refused(task):
    """``J zeta = K e`` moves the error as ``e_(k+1) = (1 - K dt) e_k``: from ``K dt = 2`` it
    never decays; the largest of per-row gains is the one checked."""
    model = dh_arm()
    stack = Stack(levels=[Level(task())])
    with pytest.raises(InputError, match=r"\.gain: gain \* dt = \d+ \* 0.05 = [\d.]+ >= 2: the "
                                         r"error would never settle.*gain < 40 .*gain <= 20"):
        Controller(model, stack, dt=DT)
    Controller(model, Stack(levels=[Level(task())]), dt=0.02)  # fine at a shorter period


def test_a_gain_updated_at_run_time_is_checked_against_the_period():
    """``update(gain=...)`` once the controller is built: the controller's next step refuses it
    like the constructor's gain (a task serves any number of controllers, each with its own
    period), until the gain is one that settles; an invalid update leaves the task as it was."""
    model = dh_arm()
    tool = EndEffectorTask("tool", position=[0.5, 0.0, 0.2], gain=2.0)
    floor = ManipulabilityTask(mode="floor", minimum=0.001, gain=1.0)
    controller = Controller(model, Stack(levels=[Level(floor), Level(tool)]), dt=DT)
    state = model.state(model.home())
    controller.step(state, 0.0)
    tool.update(gain=40.0, weight=3.0)
    with pytest.raises(InputError, match=r"task 'tool' updated: tool\.gain: gain \* dt = 40 "
                                         r"\* 0.05 = 2 >= 2"):
        controller.step(state, DT)
    with pytest.raises(InputError, match="gain"):
        controller.step(state, DT)  # refused at every step until the gain settles
    tool.update(gain=30.0)  # overshoots, but settles: accepted
    controller.step(state, DT)
    floor.update(gain=30.0)
    with pytest.raises(InputError, match=r"manipulability\.gain: gain \* dt = 30 \* 0.05"):
        controller.step(state, 2 * DT)
    with pytest.raises(InputError, match="gain"):
        floor.update(gain=-1.0, minimum=0.002)
    assert floor.gain == 30.0 and floor.minimum == 0.001  # all or nothing


def test_a_tracking_gain_that_overshoots_reverses_the_command_every_period():
    """Why the check: the DH arm's tool task at ``K dt = 2`` (refused) against ``K dt = 1.9``
    (accepted: its error alternates and decays) and ``K dt = 1`` (monotone), same goal."""
    model = dh_arm()
    goal = model.frame_pose(model.home(), "tool")[:3, 3] + [0.002, 0.001, 0.0]  # [m]
    rates = np.asarray(model.joint_rate_limit)
    errors = {}
    for gain in (20.0, 38.0):
        stack = Stack(levels=[Level(EndEffectorTask("tool", position=goal, gain=gain))],
                      constraints=[JointVelocityBounds()])
        commands, results, _ = run(model, stack, model.home(), 80)
        errors[gain] = [r.task_errors["tool"][0] for r in results]
        flips = command_reversals(commands[:, model.n_vehicle:], rates).max()
        assert (flips == 0) if gain == 20.0 else (flips >= 10)
    assert errors[20.0][3] < 1e-9  # dead-beat: there in one period (and round-off)
    assert errors[38.0][-1] < 1e-2 * errors[38.0][0]  # decays all the same
