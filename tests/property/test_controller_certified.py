"""The controller on stacks where two tasks share a row: every ok step is the optimum.

1000 random BlueROV2 Heavy + Reach Alpha 5 states and tool targets (a normal draw of 0.3 m around
the tool), for each of the two stacks of :func:`uvms_qp.bench.problems.controller_stack` whose
tasks share rows: station keeping holds the yaw that current alignment asks for; a joint-limit
margin task sits above a posture task on the same joint rates. On such stacks DAQP 0.11 left the
lower level far from its optimum with exit flag 1 on about half of the states. Every step with
a status that claims the lexicographic optimum (``optimal``) is judged by
the independent oracle (``tests/support/oracle/lexicographic.py``) on the problem the controller
solved: no level may be improvable by more than 1e-6 of its scale. A step the certificate cannot
prove says so (``unproven``), inside the box. Damping is off: a damped step is the optimum of
another problem (the stack with damping rows), and says so.
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from tests.support.oracle.lexicographic import TOL, Oracle, first_wrong
from uvms_qp.bench.problems import controller_stack
from uvms_qp.controller import Controller
from uvms_qp.hqp import Status
from uvms_qp.hqp.result import OK_STATUSES
from uvms_qp.tasks import EndEffectorTask

STATES = 1000


@pytest.mark.slow
@pytest.mark.parametrize("name", ["shared_yaw", "shared_joint"])
def test_no_ok_step_is_improvable_on_stacks_with_a_shared_row(rov, name):
    model = rov
    rng = np.random.default_rng([STATES, len(name)])
    stack = controller_stack(name, [0.0, 0.0, 0.0])
    tool = stack.levels[0].tasks[0]
    assert isinstance(tool, EndEffectorTask)
    ctrl = Controller(model, stack, dt=0.05, damping=0.0)
    problem = ctrl.assembler.problem
    wrong, statuses, stages = [], Counter(), Counter()
    for i in range(STATES):
        state = model.state(model.random_configuration(rng))
        tool.set_target(position=state.position("tool") + rng.normal(scale=0.3, size=3))
        ctrl.reset()
        step = ctrl.step(state, 0.0)
        assert np.all(np.isfinite(step.zeta)) and step.bound_violation <= 1e-9, step.summary()
        statuses[step.status.value] += 1
        stages[step.stage] += 1
        if step.status in OK_STATUSES:
            oracle = Oracle(problem.A, problem.lo, problem.hi, problem.n, problem.mh,
                            problem.sizes, problem.w)
            judged = oracle.judge(step.zeta, met=TOL)
            k = first_wrong(judged)
            if k is not None:
                wrong.append((i, k, judged[k].improvement, step.hierarchy.message))
        else:
            assert step.status is Status.UNPROVEN, step.summary()
    print(f"\n{name}: statuses {dict(statuses)}, stages {dict(stages)}")
    assert not wrong, f"{name}: {len(wrong)} ok steps the oracle improves: {wrong[:5]}"
    assert statuses["unproven"] <= 0.05 * STATES
