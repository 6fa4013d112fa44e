"""Runners: applicability rules, Pink side by side, verified success on real problems, timing."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.bench.pink_adapter import pink_available
from uvms_qp.bench.record import HARD_TOL, OWN_PROBLEM, SATURATED
from uvms_qp.bench.runners import make_runner, select_runners
from uvms_qp.bench.sets import SetConfig, build_sets


@pytest.fixture(scope="module")
def random_problems():
    return build_sets(["random"], 0, SetConfig(random_count=24))


def test_nullspace_and_pink_apply_only_where_they_can(random_problems):
    null, pink = make_runner("nullspace"), make_runner("pink")
    reasons = {p.name: (null.applies(p), pink.applies(p)) for p in random_problems}
    assert any(r[0] == "inequality tasks" for r in reasons.values())
    assert any(r[0] is None for r in reasons.values())
    one_level = [p for p in random_problems if p.info["pink"]]
    assert one_level and all(reasons[p.name][1] is None for p in one_level)
    assert all(reasons[p.name][1] == "stack has strict priorities"
               for p in random_problems if not p.info["pink"])
    scheme = make_runner("scheme:santos_sr_task_priority")
    scen = {p.name: p for p in build_sets(["scenarios"], 0, SetConfig())}
    assert scheme.applies(scen["paper001_circle"]) is None
    assert "does not name" in scheme.applies(scen["bluerov2_demo"])
    assert scheme.applies(random_problems[0]) is not None


@pytest.mark.skipif(not pink_available(), reason="pin-pink not installed")
def test_pink_and_daqp_solve_the_same_one_level_problems(random_problems):
    one_level = [p for p in random_problems if p.info["pink"]][:2]
    for p in one_level:
        ours = make_runner("daqp").run(p, 2)
        exact = make_runner("cascade:quadprog").run(p, 2)
        theirs = make_runner("pink").run(p, 2)
        for rec in (ours, exact, theirs):
            assert rec.successes == rec.trials == 2, rec
            assert rec.hard_violation <= HARD_TOL and len(rec.times_us) == 2
        # the same rows judge all: Pink's answer satisfies our hard rows, so its weighted
        # violation cannot beat the exact weighted least-squares optimum of the level
        assert theirs.levels[0] >= exact.levels[0] * (1 - 1e-6) - 1e-9


def test_select_runners_globs_and_order():
    runners, _ = select_runners(["cascade:*", "daqp"])
    names = [r.name for r in runners]
    assert names[0] == "daqp" and all(n.startswith("cascade:") for n in names[1:])
    assert len(names) >= 3


def _scenario(name, steps):
    return build_sets(["scenarios"], 0, SetConfig(max_steps=steps, scenarios=(name,)))[0]


def test_scenario_record_counts_every_step_and_times_all_but_the_warm_up():
    """Every step is verified and counted; the first (cold) one is the warm-up, not timed, as
    the warm-up call of a random or raw problem."""
    rec = make_runner("daqp").run(_scenario("paper001_circle", 5), 1)
    assert rec.trials == 5 and rec.successes == 5
    assert len(rec.times_us) == 4 and rec.info["first_step_us"] > 0.0
    assert rec.info["first_step_us"] not in rec.times_us
    assert np.isfinite(rec.backend_us) and rec.backend_us < np.median(rec.times_us)


def test_raw_nullspace_answers_are_saturated_and_unproven_not_backend_errors():
    """The closed form cannot enforce the box: as the controller's scheme, its answer is clipped
    into it; a clipped answer the certificate cannot prove is ``unproven`` (inside the hard set),
    never a ``backend_error``."""
    raw = [p for p in build_sets(["raw"], 0, SetConfig(raw_per_case=1)) if p.all_equality]
    records = [make_runner("nullspace").run(p, 2) for p in raw]
    clipped = [r for r in records if r.note.startswith(SATURATED)]
    assert clipped and len(clipped) < len(records)  # the wide boxes are never reached
    for rec in records:
        assert "backend_error" not in rec.failures, rec
        assert rec.hard_violation <= HARD_TOL  # inside the box, whatever the status
        assert rec.trials == rec.successes + rec.failed
    assert sum(r.failures.get("unproven", 0) for r in clipped) > 0
    for rec in records:  # an answer left as it was is the exact lexicographic one
        if not rec.note.startswith(SATURATED):
            assert rec.successes == rec.trials


@pytest.mark.skipif(not pink_available(), reason="pin-pink not installed")
def test_pink_scenario_rows_are_noted_as_its_own_smaller_problem(random_problems):
    rec = make_runner("pink").run(_scenario("paper001_circle", 3), 1)
    assert rec.note.startswith(OWN_PROBLEM) and rec.trials == 3
    one_level = next(p for p in random_problems if p.info["pink"])
    assert not make_runner("pink").run(one_level, 1).note.startswith(OWN_PROBLEM)
