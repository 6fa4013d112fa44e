"""The controller's in-place DAQP path (uvms_qp.hqp.inplace) against its general path.

The in-place path only shortens the happy path of ``scheme="hqp"`` with ``"daqp"``: on random
UVMS problems (2-6 levels, equality and inequality tasks, active joint/vehicle bounds, hard
linear inequalities) it must give the general path's command, statuses and residuals, and any
answer it does not accept must reach the general path (and its safety ladder) unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.bench.sets import random_uvms_problem
from uvms_qp.controller import Controller
from uvms_qp.hqp import Status


def _pair(seed: int, models: dict) -> tuple[Controller, Controller, object]:
    fast_draw = random_uvms_problem(seed, models)
    ref_draw = random_uvms_problem(seed, models)  # fresh task objects for the reference
    ref_draw.model = fast_draw.model  # random DH models are rebuilt per draw: share one
    fast = Controller(fast_draw.model, fast_draw.stack, solver="daqp", dt=fast_draw.dt)
    ref = Controller(ref_draw.model, ref_draw.stack, solver="daqp", dt=ref_draw.dt)
    ref._inplace = None  # the general path: Problem, back-end, verification, ladder
    return fast, ref, fast_draw


def test_in_place_path_matches_general_path_on_random_problems():
    models: dict = {}
    used = steps = 0
    for seed in range(40):
        fast, ref, draw = _pair(seed, models)
        assert fast._inplace is not None
        q = draw.q
        for k in range(4):
            state = draw.model.state(q)
            a = fast.step(state, k * draw.dt)
            b = ref.step(state, k * draw.dt)
            steps += 1
            used += fast._inplace.rejected == ""
            assert a.status == b.status, (seed, k)
            # the same answers to DAQP's accuracy (a tick the in-place solve declines is
            # answered by each controller's own general path, warm-started differently)
            np.testing.assert_allclose(a.zeta, b.zeta, rtol=0, atol=1e-8, err_msg=f"{seed}")
            np.testing.assert_allclose(a.lower, b.lower)
            np.testing.assert_allclose(a.upper, b.upper)
            for name, (r, unit) in b.task_residuals.items():
                assert a.task_residuals[name][1] == unit
                assert a.task_residuals[name][0] == pytest.approx(r, abs=1e-8), (seed, name)
            np.testing.assert_allclose(a.hierarchy.level_residuals,
                                       b.hierarchy.level_residuals, atol=1e-8)
            assert a.bound_violation <= 1e-9
            assert np.all(a.zeta >= a.lower) and np.all(a.zeta <= a.upper)
            q = draw.model.integrate(q, a.zeta, draw.dt)
    assert used >= 0.9 * steps  # the happy path is the common path


def test_rejected_in_place_answer_goes_to_the_general_path():
    models: dict = {}
    fast, ref, draw = _pair(4, models)
    state = draw.model.state(draw.q)
    fast.step(state, 0.0)  # sets the in-place model up
    model = fast._inplace._model.model  # the DAQP model under the in-place solver
    original = model.solve_in_place

    def broken() -> int:
        original()
        model.x[:] = np.nan  # a NaN answer that claims success
        return 1

    model.solve_in_place = broken
    result = fast.step(state, 0.0)
    assert fast._inplace.rejected.startswith("non-finite")
    ref.step(state, 0.0)
    expected = ref.step(state, 0.0)
    assert result.ok and np.all(np.isfinite(result.zeta))
    np.testing.assert_allclose(result.zeta, expected.zeta, atol=1e-9)
    assert result.status == expected.status


def test_in_place_box_and_hard_rows_are_verified():
    models: dict = {}
    fast, _, draw = _pair(11, models)
    state = draw.model.state(draw.q)
    fast.step(state, 0.0)
    model = fast._inplace._model.model  # the DAQP model under the in-place solver
    original = model.solve_in_place

    def outside() -> int:
        original()
        model.x[:] = fast._upper + 0.1  # claims success 0.1 beyond the box
        return 1

    model.solve_in_place = outside
    result = fast.step(state, 0.0)
    assert fast._inplace.rejected.startswith("box violated")
    assert result.bound_violation <= 1e-9
    assert np.all(result.zeta <= result.upper)
    assert result.status in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE)


def test_in_place_path_only_for_hqp_with_daqp():
    models: dict = {}
    draw = random_uvms_problem(2, models)
    assert Controller(draw.model, draw.stack, solver="cascade:quadprog",
                      dt=draw.dt)._inplace is None
    draw = random_uvms_problem(2, models)
    assert Controller(draw.model, draw.stack, dt=draw.dt, scheme="weighted")._inplace is None


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
@pytest.mark.parametrize("where", ["A_nan", "A_inf", "side_nan"])
def test_non_finite_rows_name_the_task_and_the_next_tick_recovers(solver, where):
    from uvms_qp.errors import NonFiniteError
    from uvms_qp.model import load_model
    from uvms_qp.stack import Level, Stack
    from uvms_qp.tasks import EndEffectorTask, PostureTask

    class Flaky(PostureTask):
        broken = False

        def error_rows(self, state, t):
            J, e, ff = super().error_rows(state, t)
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


def test_round_off_outside_the_box_is_clipped_exactly():
    """An answer a hair beyond an active bound is accepted and clipped onto the bound exactly."""
    models: dict = {}
    for seed in range(40):  # a problem with an active upper bound
        fast, _, draw = _pair(seed, models)
        state = draw.model.state(draw.q)
        first = fast.step(state, 0.0)
        active = np.flatnonzero(np.isfinite(first.upper) & (first.zeta >= first.upper))
        if active.size and fast._inplace.rejected == "":
            break
    else:  # pragma: no cover - the random set always has active bounds
        pytest.skip("no active upper bound")
    model = fast._inplace._model.model  # the DAQP model under the in-place solver
    original = model.solve_in_place
    upper = fast._upper

    def just_outside() -> int:
        flag = original()
        model.x[active] = upper[active] + 3e-12 * (1.0 + np.abs(upper[active]))
        return flag

    model.solve_in_place = just_outside
    result = fast.step(state, 0.0)
    assert fast._inplace.rejected == ""  # accepted: round-off, clipped
    assert 0.0 < fast._inplace.clipped <= 1e-7
    assert np.all(result.zeta <= result.upper) and np.all(result.zeta >= result.lower)
    assert np.array_equal(result.zeta[active], result.upper[active])


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
