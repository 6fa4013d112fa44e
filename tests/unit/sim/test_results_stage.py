"""results.json records the fallback stage of every step, the clipped amount and deadline misses.

The demo controller runs clean (every step ``primary``), then with faults injected into its
back-ends (:mod:`uvms_qp.testing.faults`): the recorded stages must be those the controller
reported, step by step, and the summary counts must add up to the number of steps.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from uvms_qp.cli.run import _summary as run_summary
from uvms_qp.safety import DEGRADED_STAGES, STAGES
from uvms_qp.schemes import build_scheme
from uvms_qp.sim.comparison import Comparison, SchemeRun
from uvms_qp.sim.results import results_dict, write_results
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario
from uvms_qp.testing.faults import Fault, inject

STEPS = 20  # 1 s of the demo at dt = 0.05 s
DURATION = 1.0
FAULT_STEP = 7


class _Logged:
    """Pass a controller through and keep the stage and deadline flag of each of its results."""

    def __init__(self, controller):
        self.controller = controller
        self.solver_name = controller.solver_name
        self.stages: list[str] = []
        self.missed: list[bool] = []

    def reset(self):
        self.controller.reset()

    def step(self, state, t):
        result = self.controller.step(state, t)
        self.stages.append(result.stage)
        self.missed.append(result.deadline_missed)
        return result


def read(path):
    return json.loads(path.read_text(encoding="utf-8"))


def test_clean_demo_run_writes_one_primary_stage_per_step(tmp_path):
    result = simulate(load_scenario("bluerov2_demo"), duration=DURATION)
    data = read(write_results(result, tmp_path))
    series = data["series"]
    assert data["steps"] == STEPS
    assert series["stage"] == ["primary"] * STEPS
    assert series["deadline_missed"] == [False] * STEPS
    assert len(series["clipped"]) == STEPS
    # a verified solve is clipped by round-off only (the hard tolerance, docs/reliability.md)
    assert max(series["clipped"]) <= 1e-9
    metrics = data["metrics"]
    assert metrics["stage_counts"] == {"primary": STEPS}
    assert metrics["deadline_missed_steps"] == 0
    assert metrics["clipped_max"] == pytest.approx(max(series["clipped"]))
    # the fields that were there before are unchanged
    assert len(series["status"]) == len(series["zeta"]) == STEPS
    assert {"ee_error_max", "nan_steps", "status_counts", "step_time_median_us"} <= set(metrics)


def test_one_injected_failure_is_recorded_at_its_step():
    scenario = load_scenario("bluerov2_demo")
    controller = scenario.make_controller()
    # the primary back-end is called once per clean step: call FAULT_STEP fails
    inject(controller.safe.primary, Fault.RAISE_OWN, calls=[FAULT_STEP])
    logged = _Logged(controller)
    result = simulate(scenario, logged, stack=controller.stack, duration=DURATION)
    assert result.stage == logged.stages
    expected = ["primary"] * STEPS
    expected[FAULT_STEP] = "cold_retry"
    assert result.stage == expected
    assert result.metrics()["stage_counts"] == {"primary": STEPS - 1, "cold_retry": 1}
    assert results_dict(result)["series"]["stage"] == expected


def test_all_back_ends_down_records_degraded_stages_with_their_status():
    scenario = load_scenario("bluerov2_demo")
    controller = scenario.make_controller()
    for solver in (controller.safe.primary, controller.safe.alternate):
        inject(solver, Fault.NAN_SUCCESS).armed = True
    result = simulate(scenario, controller, duration=DURATION)
    assert len(result.stage) == STEPS
    assert set(result.stage) <= DEGRADED_STAGES
    assert result.stage[-1] == "hold_zero"  # after max_fallbacks degraded steps in a row
    assert set(result.status) == {"backend_error"}
    assert result.nan_steps == 0
    counts = result.metrics()["stage_counts"]
    assert sum(counts.values()) == STEPS
    assert list(counts) == [s for s in STAGES if s in counts]  # ladder order
    assert counts == {s: result.stage.count(s) for s in set(result.stage)}


def test_a_slow_step_is_flagged_as_a_deadline_miss():
    # [s], as `deadline = 0.01` in the file
    scenario = dataclasses.replace(load_scenario("bluerov2_demo"), deadline=0.01)
    controller = scenario.make_controller()
    inject(controller.safe.primary, Fault.SLEEP, calls=[FAULT_STEP], sleep=0.03)
    logged = _Logged(controller)
    result = simulate(scenario, logged, stack=controller.stack, duration=DURATION)
    assert result.deadline_missed == logged.missed
    assert result.deadline_missed[FAULT_STEP] is True
    # the late answer is verified and used: the command still comes from the primary stage
    assert result.stage[FAULT_STEP] == "primary"
    assert result.metrics()["deadline_missed_steps"] == sum(result.deadline_missed) >= 1
    assert results_dict(result)["series"]["deadline_missed"][FAULT_STEP] is True


def test_closed_form_schemes_record_the_primary_stage():
    scenario = load_scenario("paper003_case2_pseudoinverse")
    scheme = build_scheme("wang_pseudoinverse", scenario)
    result = simulate(scenario, scheme, scheme_name="wang_pseudoinverse", duration=0.1)
    assert result.stage == ["primary"] * result.steps
    np.testing.assert_array_equal(result.clipped, 0.0)
    assert result.metrics()["stage_counts"] == {"primary": result.steps}


def test_a_scheme_without_a_ladder_counts_as_primary():
    class Plain:
        def __init__(self, nv):
            self.zeta = np.zeros(nv)

        def step(self, state, t):
            return type("R", (), {"zeta": self.zeta, "status": "custom", "step_time": 0.0})()

    scenario = load_scenario("bluerov2_demo")
    result = simulate(scenario, Plain(scenario.model.nv), duration=0.2)
    assert result.stage == ["primary"] * result.steps
    assert result.deadline_missed == [False] * result.steps
    assert result.metrics()["clipped_max"] == 0.0


def test_run_and_compare_tables_show_stage_and_status_counts():
    """The counts were in results.json only: the run summary and the comparison say them too."""
    metrics = {"bound_violation_max": 0.0,
               "stage_counts": {"primary": 598, "alternate": 2},
               "status_counts": {"optimal": 590, "unproven": 10}}
    summary = run_summary(metrics).splitlines()
    assert "  stage_counts                 primary 598, alternate 2" in summary
    assert "  status_counts                optimal 590, unproven 10" in summary
    comparison = Comparison("s", "d", [SchemeRun("hqp", result=None, metrics=metrics)])  # type: ignore[arg-type]
    markdown = comparison.markdown()
    assert "| stage_counts | steps | primary 598, alternate 2 |" in markdown
    assert "| status_counts | steps | optimal 590, unproven 10 |" in markdown
