"""Verification of a back-end's answer, whatever the back-end reports.

A solution ``x`` (zeta for a robot: [m/s, rad/s]) is *verified* when

* it has the problem's length and every entry is finite;
* the hard box holds: ``lower - tol <= x <= upper + tol``;
* the hard rows hold at the saturated command ``x_sat = clip(x, lower, upper)``:
  ``lo_H - tol <= A_H x_sat <= hi_H + tol``;
* the reported status is a solution status (``optimal`` or ``level_infeasible``).

``tol = hard_tol * max(1, max |finite hard side|)`` (relative, the solver's own hard tolerance;
1e-9 for every registered back-end). Everything is vectorised numpy: the happy path costs a few
microseconds at the sizes of a UVMS (n ~ 10, tens of rows), and the saturation computed for the
box check is the one the command goes out with.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray
from ..hqp.problem import Problem
from ..hqp.result import HierarchyResult, Status
from .saturation import Saturation, saturate

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
    verdict, _ = verify_command(problem, x, tol)
    return verdict


def verify_command(problem: Problem, x: FloatArray | None,
                   tol: float) -> tuple[Verdict, Saturation | None]:
    """Saturate ``x`` into the box and check it: the happy path of every control step.

    The box violation of ``x`` is exactly the amount the saturation removes, so the clip is
    computed once and reused: ``x_sat = min(max(x, lower), upper)``, ``box = max |x_sat - x|``.
    NaN and inf need no separate pass: they make ``box`` NaN or inf, which fails ``box <= tol``
    (only then is the reason refined). The hard rows are checked at ``x_sat``, the command that
    is actually sent.

    Args:
        problem: The normalised problem.
        x: Candidate point, shape (n,), or None.
        tol: Absolute tolerance on every hard side.

    Returns:
        The verdict, and the saturation of ``x`` (None when ``x`` has the wrong shape).
    """
    if x is None or getattr(x, "shape", None) != (problem.n,):
        return Verdict(False, "wrong_shape", math.inf), None
    sat = saturate(x, problem.lower, problem.upper)
    box = sat.clipped
    if not box <= tol:
        if not np.all(np.isfinite(x)):
            return Verdict(False, "non_finite", math.inf), sat
        return Verdict(False, "box_violated", box), sat
    hard = problem.hard
    if hard.m:
        y = hard.A @ sat.x
        v = float(np.max(np.maximum(hard.lo - y, y - hard.hi)))
        if not v <= tol:
            return Verdict(False, "hard_rows_violated", v), sat
        box = max(box, v)
    return Verdict(True, "", box), sat


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
    return verify_result(problem, result, tol)[0]


def verify_result(problem: Problem, result: HierarchyResult,
                  tol: float) -> tuple[Verdict, Saturation | None]:
    """:func:`verify_solution` that also returns the saturation of ``result.x``."""
    verdict, sat = verify_command(problem, result.x, tol)
    if verdict.ok and result.status not in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE):
        return Verdict(False, "not_a_solution", verdict.violation), sat
    return verdict, sat
