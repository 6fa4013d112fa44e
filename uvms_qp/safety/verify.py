"""Verification of a back-end's answer, whatever the back-end reports.

A solution ``x`` (zeta for a robot: [m/s, rad/s]) is *verified* when

* it has the problem's length and every entry is finite;
* the hard box holds: ``lower - tol <= x <= upper + tol``;
* the hard rows hold: ``lo_H - tol <= A_H x <= hi_H + tol``;
* the reported status is a solution status (``optimal`` or ``level_infeasible``).

``tol = hard_tol * max(1, max |finite hard side|)`` (relative, the solver's own hard tolerance;
1e-9 for every registered back-end). Everything is vectorised numpy: the happy path costs a few
microseconds at the sizes of a UVMS (n ~ 10, tens of rows).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray
from ..hqp.problem import Problem
from ..hqp.result import HierarchyResult, Status

#: Reasons a verification fails (the vocabulary of :attr:`Verdict.reason`).
REASONS: tuple[str, ...] = (
    "",  # verified
    "wrong_shape",
    "non_finite",
    "box_violated",
    "hard_rows_violated",
    "not_a_solution",  # the status says the back-end did not solve the problem
)


@dataclass(frozen=True, slots=True)
class Verdict:
    """Outcome of :func:`verify_solution`.

    Attributes:
        ok: True when ``x`` is finite, inside the hard set and the status is a solution status.
        reason: Empty when ``ok``; otherwise one of :data:`REASONS`.
        violation: Largest violation of the hard box and hard rows at ``x`` (``inf`` when ``x``
            is not finite) [units of zeta].
    """

    ok: bool
    reason: str
    violation: float


def hard_violation_of(problem: Problem, x: FloatArray) -> float:
    """Largest violation of the hard box and hard rows at ``x`` (0 when they hold).

    Args:
        problem: The normalised problem (box ``lower``/``upper``, hard rows).
        x: A finite point, shape (n,).
    """
    v = max(0.0, float(np.max(problem.lower - x)), float(np.max(x - problem.upper)))
    hard = problem.hard
    if hard.m:
        y = hard.A @ x
        v = max(v, float(np.max(hard.lo - y)), float(np.max(y - hard.hi)))
    return v


def verify_point(problem: Problem, x: FloatArray | None, tol: float) -> Verdict:
    """Check a point against the hard set only (no status involved).

    Args:
        problem: The normalised problem.
        x: Candidate point, shape (n,), or None.
        tol: Absolute tolerance on every hard side.
    """
    if x is None or np.shape(x) != (problem.n,):
        return Verdict(False, "wrong_shape", math.inf)
    if not math.isfinite(float(np.sum(x))) or not np.all(np.isfinite(x)):
        return Verdict(False, "non_finite", math.inf)
    box = max(0.0, float(np.max(problem.lower - x)), float(np.max(x - problem.upper)))
    if box > tol:
        return Verdict(False, "box_violated", box)
    v = box
    hard = problem.hard
    if hard.m:
        y = hard.A @ x
        v = max(v, float(np.max(hard.lo - y)), float(np.max(y - hard.hi)))
        if v > tol:
            return Verdict(False, "hard_rows_violated", v)
    return Verdict(True, "", v)


def hard_tolerance(problem: Problem, hard_tol: float) -> float:
    """Absolute hard tolerance ``hard_tol * max(1, max |finite hard side|)``."""
    return hard_tol * problem.hard_scale


def verify_solution(problem: Problem, result: HierarchyResult, tol: float) -> Verdict:
    """Verify a solver result: finite ``x`` inside the hard set, and a solution status.

    The check is independent of the back-end's own verdict and of the evaluation that built
    ``result``: a result claiming ``optimal`` whose ``x`` breaks a hard row fails here too.

    Args:
        problem: The normalised problem the result answers.
        result: The solver's result.
        tol: Absolute tolerance on every hard side (see :func:`hard_tolerance`).
    """
    verdict = verify_point(problem, result.x, tol)
    if not verdict.ok:
        return verdict
    if result.status not in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE):
        return Verdict(False, "not_a_solution", verdict.violation)
    return verdict
