"""Seeds and draws: one master seed decides every run, and any run is drawn again from its seed."""

from __future__ import annotations

import dataclasses

import numpy as np

from uvms_qp.sweep import draw, run_seed
from uvms_qp.sweep.distributions import Choice, Normal, Uniform
from uvms_qp.sweep.spec import Variable


def test_run_seeds_are_the_spawned_children_of_the_master_seed():
    children = np.random.SeedSequence(2024).spawn(7)
    expected = [int(c.generate_state(1, np.uint64)[0]) >> 1 for c in children]
    assert [run_seed(2024, i) for i in range(7)] == expected
    assert len(set(expected)) == 7
    assert all(0 <= s < 2**63 for s in expected)


def test_a_run_draws_the_same_values_from_its_seed_alone():
    variables = [Variable("current.speed", Uniform(low=0.0, high=0.3)),
                 Variable("initial.joints", Normal(mean=0.0, std=0.1), 4)]
    seed = run_seed(5, 3)
    assert draw(variables, seed) == draw(variables, seed)
    assert draw(variables, seed) != draw(variables, run_seed(5, 4))


def test_one_more_variable_leaves_the_others_draws_unchanged():
    speed = Variable("current.speed", Uniform(low=0.0, high=0.3))
    mass = Variable("payload.mass", Uniform(low=0.0, high=4.0))
    seed = run_seed(1, 0)
    assert draw([speed], seed)["current.speed"] == draw([mass, speed], seed)["current.speed"]


def test_laws_stay_in_their_support():
    rng = np.random.default_rng(0)
    truncated = Normal(mean=0.0, std=1.0, low=-0.1, high=0.3)
    values = np.array([truncated.sample(rng) for _ in range(2000)])
    assert values.min() >= -0.1 and values.max() <= 0.3
    # a truncated law, not a clipped one: no mass piles up on the bounds
    assert np.count_nonzero((values == -0.1) | (values == 0.3)) == 0
    uniform = Uniform(low=2.0, high=3.0)
    drawn = np.array([uniform.sample(rng) for _ in range(2000)])
    assert drawn.min() >= 2.0 and drawn.max() <= 3.0 and abs(drawn.mean() - 2.5) < 0.03
    choice = Choice(options=("a", "b"))
    picks = [choice.sample(rng) for _ in range(400)]
    assert set(picks) == {"a", "b"} and 150 < picks.count("a") < 250


def test_a_variable_of_count_n_draws_n_independent_values():
    variable = Variable("initial.joints", Uniform(low=-1.0, high=1.0), 4)
    values = draw([variable], 123)["initial.joints"]
    assert len(values) == 4 and len(set(values)) == 4
    single = dataclasses.replace(variable, count=1)
    assert draw([single], 123)["initial.joints"] == values[0]
