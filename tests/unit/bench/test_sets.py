"""Benchmark test sets: deterministic, the promised shapes and the promised difficulty."""

from __future__ import annotations

import numpy as np

from uvms_qp.bench.sets import (
    RAW_LEVEL_SIZES,
    SetConfig,
    build_sets,
    random_uvms_problem,
)
from uvms_qp.controller import Controller
from uvms_qp.hqp import solve_hierarchy


def test_raw_set_shapes_and_bound_activity():
    problems = build_sets(["raw"], 3, SetConfig(raw_per_case=2))
    assert len(problems) == 3 * 3 * 2
    active = {"wide": [], "tight": [], "saturated": []}
    for p in problems:
        n = p.info["n"]
        assert [lvl[0][0].shape for lvl in p.levels] == [(m, n) for m in RAW_LEVEL_SIZES]
        r = solve_hierarchy(p.levels, p.lower, p.upper, solver="cascade:quadprog")
        assert r.ok
        active[p.info["bounds"]].append((r.active_lower | r.active_upper).mean())
    assert max(active["wide"]) == 0.0
    assert 0.0 < np.mean(active["tight"]) < np.mean(active["saturated"])
    assert np.mean(active["saturated"]) >= 0.5
    again = build_sets(["raw"], 3, SetConfig(raw_per_case=2))
    assert all(np.array_equal(a.levels[0][0][0], b.levels[0][0][0])
               for a, b in zip(problems, again, strict=True))


def test_random_uvms_draws_cover_the_promised_space():
    models = {}
    levels, kinds, tags, mixed = set(), set(), set(), 0
    for seed in range(40):
        d = random_uvms_problem(seed, models)
        levels.add(len(d.stack.levels))
        kinds.add(d.model.vehicle_kind)
        tags.update(d.notes)
        rows = Controller(d.model, d.stack, dt=d.dt).level_rows(d.model.state(d.q))
        eq = np.concatenate([r.lower == r.upper for r in rows])
        mixed += bool(eq.any() and (~eq).any())
        assert all(np.isfinite(r.A).all() for r in rows)
    assert {"planar", "spatial", "fixed"} <= kinds
    assert {"singular", "at-limits", "one-level"} <= tags
    assert any(t.startswith("dh") for t in tags)
    assert set(range(2, 7)) <= levels | {1}
    assert mixed >= 10


def test_random_draw_is_deterministic_and_bounds_are_active():
    a, b = random_uvms_problem(11), random_uvms_problem(11)
    assert np.array_equal(a.q, b.q) and a.stack.describe() == b.stack.describe()
    active = 0
    for seed in range(12):
        d = random_uvms_problem(seed)
        r = Controller(d.model, d.stack, solver="daqp", dt=d.dt).step(d.model.state(d.q))
        active += bool(r.hierarchy.active_lower.any() or r.hierarchy.active_upper.any())
    assert active >= 6
