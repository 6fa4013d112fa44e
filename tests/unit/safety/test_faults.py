"""Fault injection through the controller: every step safe, the stage named, no after-effects.

The demo stack (bluerov2_demo: all hard bounds but the command-rate bound, which remembers the
previous command by design, so that a faulted step would rightly leave a trace) is stepped along
the states of a
clean reference run; the primary back-end of a second controller fails at step K (or for N steps
from K). Every command is finite and inside the box, the stage that produced it is in the result
and its summary, and once the back-end solves again the commands equal the reference ones: a
failure leaves no trace in later steps (warm starts and fallback memory are not poisoned).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.controller import Controller
from uvms_qp.errors import NoSolutionFound
from uvms_qp.model import load_model
from uvms_qp.safety import DEGRADED_STAGES
from uvms_qp.sim.scenario import load_scenario
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, StationKeepingTask
from uvms_qp.testing.faults import Fault, inject

K = 12
STEPS = 30


def demo():
    """The demo scenario and a new stack of it without its command-rate bound."""
    sc = load_scenario("bluerov2_demo")
    stack = sc.build_stack()
    kept = [c for c in stack.constraints if c.type_name != "command_rate_bounds"]
    assert len(kept) == len(stack.constraints) - 1
    return sc, Stack(levels=stack.levels, constraints=kept)


@pytest.fixture(scope="module")
def reference():
    """States and commands of a clean closed-loop run of the demo (daqp)."""
    sc, stack = demo()
    ctrl = Controller(sc.model, stack, dt=sc.dt, metric=sc.metric)
    q = np.array(sc.q0)
    qs, zetas = [], []
    for k in range(STEPS):
        qs.append(q)
        res = ctrl.step(sc.model.state(q), k * sc.dt)
        assert res.stage == "primary"
        zetas.append(res.zeta)
        q = sc.model.integrate(q, res.zeta, sc.dt)
    return qs, zetas


def replay(qs, fault, *, start=K, count=1, armed=False, everything=False, strict=False,
           deadline=math.inf, sleep=0.05, times=None, at="backend"):
    """Step a fresh demo controller along ``qs``; from step ``start`` the next ``count`` back-end
    calls fail (or, with ``armed``, every call during steps start..start+count-1 fails).
    ``everything`` faults the alternate back-end as well; ``at="binding"`` faults DAQP's C
    binding below the back-end instead of the back-end object."""
    sc, stack = demo()
    ctrl = Controller(sc.model, stack, dt=sc.dt, metric=sc.metric, strict=strict,
                      deadline=deadline)
    wrappers = [inject(ctrl, fault, sleep=sleep, at=at)]
    if everything:
        wrappers.append(inject(ctrl.safe.alternate, fault, sleep=sleep))
    out = []
    for k, q in enumerate(qs):
        for w in wrappers:
            if armed:
                w.armed = start <= k < start + count
            elif k == start:
                w.remaining = count
        t = k * sc.dt if times is None else times[k]
        out.append(ctrl.step(sc.model.state(q), t))
    return out


def assert_safe(res):
    assert np.all(np.isfinite(res.zeta))
    assert np.all(res.zeta >= res.lower) and np.all(res.zeta <= res.upper)


DETECTABLE = [f for f in Fault if f not in (Fault.SLEEP, Fault.FEASIBLE_WRONG)]


@pytest.mark.parametrize("fault", DETECTABLE)
def test_one_failure_is_caught_and_leaves_no_trace(reference, fault):
    qs, zetas = reference
    results = replay(qs, fault)
    for k, res in enumerate(results):
        assert_safe(res)
        if k == K:
            assert res.stage == "cold_retry" and res.attempts, res.summary()
            assert "[fallback: cold_retry]" in res.summary()
            assert "rejected: primary:" in res.summary()
        else:
            assert res.stage == "primary"
        # the cold retry solves the same problem: same command; later steps unchanged
        assert np.max(np.abs(res.zeta - zetas[k])) <= 1e-7, (k, res.summary())


@pytest.mark.parametrize("fault", DETECTABLE)
def test_faults_below_the_default_back_end_are_caught(reference, fault):
    """The default path (DAQP) faulted at its C binding, below the back-end object: every
    step safe and truthful, and once the binding behaves the commands are the clean ones."""
    qs, zetas = reference
    results = replay(qs, fault, at="binding", count=3)
    for k, res in enumerate(results):
        assert_safe(res)
        assert res.ok and res.bound_violation <= 1e-9, res.summary()
        if k > K + 2:
            assert res.stage == "primary"
            assert np.max(np.abs(res.zeta - zetas[k])) <= 1e-7, (k, res.summary())
    assert any(r.stage != "primary" or r.hierarchy.info.get("rho_soft") != 1e-8
               for r in results[K:K + 3])


@pytest.mark.parametrize("count, stages", [
    (1, ["cold_retry", "primary"]),
    (3, ["alternate", "cold_retry", "primary"]),  # 2 failed calls at step K, the 3rd at K+1
    (100, ["alternate"] * 50 + ["primary"]),  # 2 failed calls per step
])
def test_repeated_failures(reference, count, stages):
    qs, zetas = reference
    n = K + len(stages) + 2
    states = (qs * 4)[:n] if n > len(qs) else qs[:n]
    results = replay(states, Fault.NAN_SUCCESS, count=count)
    assert [r.stage for r in results[K: K + len(stages)]] == stages
    for res in results:
        assert_safe(res)
        assert res.ok  # every stage reached solves the full problem
    back = K + len(stages) - 1
    if n <= len(qs):
        assert np.max(np.abs(results[back].zeta - zetas[back])) <= 1e-7


def test_all_back_ends_down_for_100_steps_holds_zero_then_recovers(reference):
    qs, zetas = reference
    long_qs = qs[:K] + [qs[K]] * 100 + qs[K:K + 5]
    dt = 0.05
    times = [k * dt for k in range(K)] + [K * dt] * 100 + [(K + j) * dt for j in range(5)]
    results = replay(long_qs, Fault.RAISE_FOREIGN, count=100, armed=True, everything=True,
                     times=times)
    stages = [r.stage for r in results[K:K + 100]]
    assert stages[:3] == ["decayed_previous"] * 3 or set(stages[:3]) <= {"decayed_previous",
                                                                           "relaxed", "zero"}
    assert set(stages[3:]) == {"hold_zero"}
    for res in results[K + 3:K + 100]:
        assert_safe(res)
        assert not np.any(res.zeta)  # zero held
        assert res.status.value == "backend_error" and res.stage in DEGRADED_STAGES
    back = results[K + 100]
    assert back.stage == "primary" and np.max(np.abs(back.zeta - zetas[K])) <= 1e-7


def test_sleep_past_the_deadline_is_reported_and_used(reference):
    qs, zetas = reference
    results = replay(qs[:K + 2], Fault.SLEEP, armed=True, deadline=0.01, sleep=0.03)
    late = results[K]
    assert late.deadline_missed and late.stage == "primary"
    assert np.max(np.abs(late.zeta - zetas[K])) <= 1e-7
    assert not results[K + 1].deadline_missed


def test_strict_controller_raises_no_solution_found(reference):
    qs, _ = reference
    with pytest.raises(NoSolutionFound) as info:
        replay(qs[:K + 1], Fault.WILD_FAILURE, armed=True, everything=True, strict=True)
    assert info.value.result is not None


def test_weighted_scheme_falls_back_to_a_weight_honouring_cascade(reference):
    """DAQP's hierarchical mode would normalise the weighted rows: the weighted scheme's
    alternate is a cascade on another library, and it gives the primary's answer."""
    qs, _ = reference
    sc, stack = demo()
    ctrl = Controller(sc.model, stack, dt=sc.dt, metric=sc.metric, scheme="weighted",
                      priority_ratio=100.0, deadline=None)  # the stages, not the machine's load
    assert ctrl.solver_name == "cascade:daqp"
    assert ctrl.safe.alternate.name.startswith("cascade:")
    clean = ctrl.step(sc.model.state(qs[K]), K * sc.dt)
    inject(ctrl.safe.primary, Fault.RAISE_FOREIGN).armed = True
    res = ctrl.step(sc.model.state(qs[K]), K * sc.dt)
    assert res.stage == "alternate" and res.ok
    assert np.max(np.abs(res.zeta - clean.zeta)) <= 1e-5


@pytest.mark.parametrize("scheme, solver", [("weighted", "daqp"), ("nullspace", "daqp"),
                                            ("hqp", "cascade:quadprog")])
@pytest.mark.parametrize("fault", [Fault.RAISE_FOREIGN, Fault.MEMORY, Fault.NONE,
                                   Fault.WRONG_LENGTH, Fault.NAN_SUCCESS, Fault.WILD_FAILURE])
def test_every_scheme_runs_under_the_same_guard(scheme, solver, fault):
    """The weighted scheme, the closed form and a cascade: a faulted step gives a safe command
    and a truthful status from another stage, and the next step is the clean one."""
    from uvms_qp.bench.stacks import tool_posture_stack
    from uvms_qp.tasks import EndEffectorTask

    model = load_model("bluerov2_heavy_alpha5")

    def controller():
        stack = tool_posture_stack(EndEffectorTask(position=[0.55, 0.12, 0.05], gain=1.0))
        return Controller(model, stack, solver=solver, dt=0.05, scheme=scheme,
                          deadline=None)  # the stages, not the machine's load

    clean, ctrl = controller(), controller()
    q = model.home()
    injector = inject(ctrl, fault)
    for k in range(4):
        state = model.state(q)
        expected = clean.step(state, 0.05 * k)
        injector.armed = k == 1
        res = ctrl.step(state, 0.05 * k)
        assert_safe(res)
        assert res.bound_violation <= 1e-9
        if k == 1:
            assert res.stage != "primary" and res.attempts and res.ok, res.summary()
        else:
            assert res.stage == "primary"
            np.testing.assert_allclose(res.zeta, expected.zeta, atol=1e-7)
        q = model.integrate(q, expected.zeta, 0.05)


@pytest.mark.parametrize("scheme", ["nullspace", "weighted", "hqp"])
def test_a_slow_step_is_flagged_on_every_scheme(scheme):
    """A 120 ms solve (on a fake clock) against a 50 ms deadline is flagged, on every scheme."""
    from uvms_qp.bench.stacks import tool_posture_stack
    from uvms_qp.tasks import EndEffectorTask

    model = load_model("bluerov2_heavy_alpha5")
    stack = tool_posture_stack(EndEffectorTask(position=[0.55, 0.12, 0.05], gain=1.0))
    ctrl = Controller(model, stack, dt=0.05, scheme=scheme, deadline=0.05)
    now = [0.0]
    ctrl.safe.clock = lambda: now[0]
    injector = inject(ctrl, Fault.SLEEP, count=1, sleep=0.12)
    injector.sleeper = lambda seconds: now.__setitem__(0, now[0] + seconds)
    state = model.state(model.home())
    late = ctrl.step(state, 0.0)
    assert late.deadline_missed and late.stage == "primary" and late.ok
    assert late.step_time == pytest.approx(0.12)
    again = ctrl.step(state, 0.05)
    assert not again.deadline_missed


@pytest.mark.parametrize("fault", [Fault.NAN_SUCCESS, Fault.WILD_FAILURE, Fault.MEMORY])
def test_nullspace_never_returns_a_non_finite_zeta(rov, fault):
    model = rov
    stack = Stack(constraints=[JointPositionBounds(), JointVelocityBounds(), VehicleRateBounds()],
                  levels=[Level(EndEffectorTask(position=[1.0, 0.0, 0.0])),
                          Level(StationKeepingTask())])
    c = Controller(model, stack, scheme="nullspace")
    state = model.state(model.home())
    clean = c.step(state)
    inject(c, fault, count=2)  # the closed form and its cold retry
    r = c.step(state)
    assert np.all(np.isfinite(r.zeta))
    assert np.all(r.zeta >= r.lower) and np.all(r.zeta <= r.upper)
    assert r.stage == "alternate" and r.ok  # the QP alternate solves the same levels
    again = c.step(state)
    assert again.stage == "primary"
    np.testing.assert_allclose(again.zeta, clean.zeta, atol=1e-12)
