"""Controller properties on random (model, state, target, stack) draws.

For the DAQP hierarchical back-end and two qpsolvers cascades: zeta is finite, the hard box and
rows hold to 1e-7, and a lower level never changes what a higher level achieves (solve again
with the lower levels removed: each remaining level's violation vector is unique at the
lexicographic optimum, so its norm must not move). These are properties of the lexicographic
optimum, so the controllers run undamped (``damping=0``); the damped hierarchy has its own
(``tests/test_controller_smooth_commands.py``).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_qp.bench.stacks import random_bounds, random_stack
from uvms_qp.controller import Controller
from uvms_qp.hqp import Status
from uvms_qp.stack import Stack

SOLVERS = ["daqp", "cascade:quadprog", "cascade:piqp"]


def random_problem(model, rng):
    """A random state and a random 2-6 level stack under random hard bounds (the benchmark's
    random-set draw, :func:`uvms_qp.bench.stacks.random_stack`)."""
    state = model.state(model.random_configuration(rng))
    return state, random_stack(model, state, rng, random_bounds(model, rng))


def check_draw(model, seed, solver):
    rng = np.random.default_rng(seed)
    state, stack = random_problem(model, rng)
    full = Controller(model, stack, solver=solver, dt=0.05, damping=0.0).step(state, 0.0)
    assert np.all(np.isfinite(full.zeta))
    # ok (proven), or honestly not: never an ok status on an answer the certificate rejects
    assert full.ok or full.status is Status.UNPROVEN, full.summary()
    assert full.bound_violation <= 1e-7, full.summary()
    for k in range(len(stack.levels) - 1):
        partial = Stack(levels=list(stack.levels[: k + 1]), constraints=list(stack.constraints))
        sub = Controller(model, partial, solver=solver, dt=0.05, damping=0.0).step(state, 0.0)
        assert sub.ok or sub.status is Status.UNPROVEN
        for j in range(k + 1):
            a, b = full.level_violations[j], sub.level_violations[j]
            assert abs(a - b) <= 1e-5 * (1.0 + b), (
                f"{model.name} seed {seed} {solver}: level {j} violation {a:.3e} with levels "
                f"below, {b:.3e} without\n{full.summary()}\n{sub.summary()}")


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("name", ["bluerov2_heavy_alpha5", "wang_9dof", "soylu_planar"])
@settings(max_examples=25)
@given(seed=st.integers(0, 2**31 - 1))
def test_random_stacks_finite_bounded_and_prioritised(models, name, solver, seed):
    check_draw(models[name], seed, solver)
