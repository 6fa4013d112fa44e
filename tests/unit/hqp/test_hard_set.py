"""The hard set of a problem: feasibility of the box and hard rows, and a point of it."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.hqp import hard_set, normalize_problem
from uvms_qp.hqp.hard_set import hard_feasible, hard_point


def _levels(n: int) -> list:
    return [[(np.eye(n)[:1], np.ones(1), np.ones(1))]]


def test_a_box_without_hard_rows_is_judged_without_an_lp(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_lp(*args: object, **kwargs: object) -> None:
        raise AssertionError("an LP was solved for a box alone")

    monkeypatch.setattr(hard_set, "linprog", no_lp)
    n = 4
    assert hard_feasible(normalize_problem(_levels(n), -np.ones(n), np.ones(n)))
    assert hard_feasible(normalize_problem(_levels(n), np.zeros(n), np.zeros(n)))  # a point
    assert hard_feasible(normalize_problem(_levels(n), None, None))  # no box at all


def test_hard_rows_are_judged_by_the_lp() -> None:
    n = 3
    box = -np.ones(n), np.ones(n)
    reachable = [(np.ones((1, n)), np.array([2.5]), np.array([2.5]))]  # sum x = 2.5 <= 3
    unreachable = [(np.ones((1, n)), np.array([3.5]), np.array([3.5]))]  # sum x = 3.5 > 3
    assert hard_feasible(normalize_problem(_levels(n), *box, hard=reachable))
    assert not hard_feasible(normalize_problem(_levels(n), *box, hard=unreachable))
    point = hard_point(normalize_problem(_levels(n), *box, hard=reachable))
    assert point is not None
    assert abs(point.sum() - 2.5) < 1e-9 and np.all(np.abs(point) <= 1.0 + 1e-12)


def test_an_lp_out_of_time_proves_nothing_empty() -> None:
    n = 3
    box = -np.ones(n), np.ones(n)
    unreachable = [(np.ones((1, n)), np.array([3.5]), np.array([3.5]))]
    problem = normalize_problem(_levels(n), *box, hard=unreachable)
    assert not hard_feasible(problem, time_limit=10.0)
    assert hard_feasible(problem, time_limit=0.0)  # stopped before proving the set empty
