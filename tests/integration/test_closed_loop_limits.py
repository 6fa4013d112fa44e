"""Closed loops that push against every limit, and a CI-sized soak of the demo with faults.

* 5x10^3 steps toward targets beyond reach, with every joint pushed toward one of its limits at
  5 rad/s: after every Euler step the joints are inside their limits to 1e-9 rad, and every
  command respects the rate bounds exactly (saturation is bit-exact).
* 10^4 steps of the bundled demo with re-drawn targets and 1 % injected back-end faults
  (``uvms_qp.testing.soak``): 0 unsafe outputs, 0 limit excursions, tracemalloc growth after the
  warm-up <= 1 MiB. The 10^6-step run is ``benchmarks/soak.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.pushing import JointRateTask
from tests.support.reliability_models import random_model
from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.controller import Controller
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask
from uvms_qp.testing.soak import run_soak

STEPS = 5000
DT = 0.05


@pytest.mark.parametrize("case", [("bluerov2_heavy_alpha5", "daqp", 1.0),
                                  ("random_planar_5", "cascade:quadprog", 0.5)])
def test_closed_loop_against_the_limits(case):
    name, solver, gain = case
    model = load_model(name) if not name.startswith("random") else random_model("planar", 5)
    rng = np.random.default_rng(7)
    lo, hi = model.joint_lower, model.joint_upper
    push = np.where(rng.uniform(size=model.n_joints) < 0.5, -5.0, 5.0)  # [rad/s]
    tool = EndEffectorTask(mode="position", position=[0.0, 0.0, 0.0], gain=3.0)
    stack = Stack(levels=[Level(JointRateTask(push)), Level(tool)],
                  constraints=[JointPositionBounds(gain=gain), JointVelocityBounds(),
                               VehicleRateBounds(limits=[0.2] * model.n_vehicle)])
    ctrl = Controller(model, stack, solver=solver, dt=DT)
    rate = np.concatenate((np.full(model.n_vehicle, 0.2), model.joint_rate_limit))
    q = model.home()
    worst = 0.0
    at_limit = 0
    for k in range(STEPS):
        if k % 250 == 0:  # a new target 3 m away: beyond reach
            centre = model.state(q).position("vehicle")
            target = centre + 3.0 * rng.normal(size=3)
            if model.vehicle_kind == "planar":
                target[2] = model.state(q).position("tool")[2]
            tool.set_target(position=target)
        res = ctrl.step(model.state(q), k * DT)
        z = res.zeta
        assert np.all(np.abs(z) <= rate), res.summary()
        assert np.all(z >= res.lower) and np.all(z <= res.upper)
        q = model.integrate(q, z, DT)
        joints = model.split(q)[1]
        excess = max(float(np.max(lo - joints)), float(np.max(joints - hi)), 0.0)
        worst = max(worst, excess)
        at_limit += int(np.any(np.minimum(joints - lo, hi - joints) < 1e-6))
    assert worst <= 1e-9, worst
    assert at_limit > STEPS // 2  # the loop really lives on the limits


def test_soak_ci():
    report = run_soak(10_000, seed=3, fault_rate=0.01, restart=2500, warmup=5000)
    print("\n" + "\n".join(report.lines()))
    assert report.steps == 10_000
    assert report.unsafe == 0 and report.limit_excursions == 0
    assert sum(report.faults.values()) > 50  # faults really were injected
    assert report.stages["primary"] > 9000
    assert report.memory_growth <= 1024 * 1024


def test_a_soak_too_short_to_measure_reports_n_a_not_zero():
    short = run_soak(150, fault_rate=0.0, warmup=100, restart=100)  # no cycle after the warm-up
    assert short.median_first_us is None and short.drift is None
    assert short.memory_growth is not None  # traced from step 100 on
    text = "\n".join(short.lines())
    assert "first/last cycle: n/a" in text and "at least 200 steps" in text
    assert " 0.0 us" not in text
    untraced = run_soak(50, fault_rate=0.0, warmup=100, restart=100)
    assert untraced.memory_growth is None
    assert "tracemalloc growth after warm-up: n/a" in "\n".join(untraced.lines())
    measured = run_soak(200, fault_rate=0.0, warmup=100, restart=100, trace_memory=False)
    assert measured.median_first_us > 0.0 and measured.drift is not None
    assert "step time median first cycle" in "\n".join(measured.lines())
