"""Measure an answer against its problem: slacks, residuals, the hard violation and the status.

Every answer of every back-end (and every fallback command of :mod:`uvms_qp.safety`) ends here,
so statuses mean the same thing everywhere. On the stacked layout of
:class:`~uvms_qp.hqp.problem.Problem` one product gives the signed slack of every row,

    z = A x,    s = z - min(max(z, lo), hi)          (> 0 above hi, < 0 below lo)

and one more the squared residuals ``G (s * s)``: the box and hard rows (0 when they hold) and
each level's weighted ``r_k^2 = sum_i w_i s_i^2``. The decision:

* no finite ``x`` (None, wrong length, NaN/inf): ``backend_error`` at a placeholder (zero clipped
  into the box);
* a claimed success whose hard violation exceeds ``hard_tol * max(1, max |finite hard side|)``:
  ``backend_error`` (the message names the bound or row);
* otherwise ``optimal`` when every ``r_k <= level_tol * max(1, max |finite side of level k|)``,
  and, when some are not, still ``optimal`` (with those levels in ``unmet_levels``) once the
  optimality certificate (a solver's :class:`uvms_qp.hqp.certificate.Certifier`, asked about
  every answer with an unmet level) has proven every unmet level optimal; a level it cannot
  prove makes the answer ``unproven`` (feasible, not proven optimal; the certificate is kept
  in the result).

:func:`hard_violation` is the one measure of "how far is x outside the hard set" on plain arrays,
for callers that hold the box and rows themselves (simulation logs, benchmarks).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from .linalg import minimum as _minimum
from .linalg import multiply as _multiply
from .linalg import subtract as _subtract
from .problem import Problem
from .result import OK_STATUSES, HierarchyResult, Status
from .tolerances import HARD_TOL, LEVEL_TOL

if TYPE_CHECKING:  # pragma: no cover - the certificate is handed in by the solver
    from .certificate import Certificate

#: ``certify(problem, x, s, residuals, hard_violation, scales) -> Certificate``: the
#: optimality certificate asked about an answer with an unmet level (a solver's
#: :class:`uvms_qp.hqp.certificate.Certifier`, or a stand-in a test installs), given the
#: measurement's slacks, level residuals, hard violation and the level scales it computed
#: (``Problem.level_scale(k)`` of each level whose residual exceeds the bare tolerance, None
#: for the others).
Certify = Callable[[Problem, FloatArray, FloatArray, list[float], float, list[float | None]],
                   "Certificate"]

_OPTIMAL = Status.OPTIMAL
_SQRT = math.sqrt
_INF = math.inf

Measured = tuple[FloatArray, FloatArray, list[float]]
"""``(s, x_clipped, squares)``: slacks at x, x clipped into the box (a view of a fresh array),
``[sum of squared box/hard slacks, r_0^2, ..., r_p-1^2]``."""


def measure(problem: Problem, x: FloatArray) -> Measured:
    """Slacks of every row at ``x`` and the squared residuals, in one product each.

    Args:
        problem: The problem.
        x: A point of shape (n,) (finite for meaningful values: NaN/inf make ``squares`` NaN).
    """
    z = problem.A.dot(x)
    c = np.maximum(z, problem.lo)
    _minimum(c, problem.hi, out=c)
    s = _subtract(z, c, out=z)
    squares = problem.squares
    _multiply(s, s, out=squares)
    return s, c[:problem.n], problem.G.dot(squares).tolist()


def _largest(s: FloatArray) -> tuple[float, int]:
    """``max |s|`` (inf if any entry is NaN) and its index (-1 when ``s`` is empty).

    ``argmax`` takes NaN for the largest value (the index of the first NaN), so a NaN anywhere
    is the entry it returns.
    """
    if not s.size:
        return 0.0, -1
    a = np.abs(s)
    i = int(a.argmax())
    v = float(a[i])
    return (math.inf if v != v else v), i


def hard_violation(x: FloatArray, lower: FloatArray, upper: FloatArray,
                   A: FloatArray | None = None, lo: FloatArray | None = None,
                   hi: FloatArray | None = None) -> float:
    """Largest violation of ``lower <= x <= upper`` and ``lo <= A x <= hi`` (0 when they hold).

    Args:
        x: Point (n,) [units of x].
        lower: Lower bounds (n,), ``-inf`` allowed.
        upper: Upper bounds (n,), ``+inf`` allowed.
        A: Hard rows (m, n), or None.
        lo: Their lower sides (m,).
        hi: Their upper sides (m,).

    Returns:
        The largest distance of ``x`` (box) or ``A x`` (rows) outside its interval [units of the
        rows]; inf when ``x`` is not finite.
    """
    v = _largest(x - np.minimum(np.maximum(x, lower), upper))[0]
    if A is not None and A.shape[0]:
        if lo is None or hi is None:
            raise ValueError("hard_violation: rows A need their sides lo and hi")
        z = A @ x
        v = max(v, _largest(z - np.minimum(np.maximum(z, lo), hi))[0])
    return v


def _where(problem: Problem, s: FloatArray, i: int) -> str:
    """Name of stacked row ``i`` of the box or the hard rows, with the side it violates."""
    side = "upper" if s[i] > 0 else "lower"
    if i < problem.n:
        return f"{side} bound {i}"
    return f"hard row {i - problem.n} ({side} side)"


def clip_to_box(x: FloatArray, lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, float]:
    """``x`` clipped into ``[lower, upper]`` and the largest change made [units of x].

    The clip is exact (``min(max(x, lower), upper)``, a fresh array); the change is NaN if ``x``
    holds NaN.
    """
    clipped = np.minimum(np.maximum(x, lower), upper)
    return clipped, float(np.abs(clipped - x).max(initial=0.0))


def placeholder(problem: Problem) -> FloatArray:
    """A finite stand-in for a missing answer: zero clipped into the box."""
    return np.minimum(np.maximum(np.zeros(problem.n), problem.lower), problem.upper)


def evaluate(problem: Problem, x: Any, claim: Status, solver: str, message: str = "",
             info: dict[str, object] | None = None, level_tol: float = LEVEL_TOL,
             hard_tol: float = HARD_TOL, solve_time: float = 0.0, measured: Measured | None = None,
             certify: Certify | None = None) -> HierarchyResult:
    """Measure ``x`` against ``problem`` and decide its status (see the module docstring).

    Args:
        problem: The problem ``x`` answers.
        x: The back-end's answer (anything: None, a wrong length and NaN are reported).
        claim: The back-end's own verdict; ``optimal`` claims success (the measurement and the
            certificate decide), any other status is kept.
        solver: Back-end name for the report.
        message: Back-end detail to keep.
        info: Back-end extras.
        level_tol: Relative tolerance deciding whether a level is met.
        hard_tol: Relative tolerance on the hard box and rows.
        solve_time: Wall time of the solve [s].
        measured: :func:`measure` of ``x`` when the caller has it already.
        certify: The optimality certificate, asked about an answer with an unmet level (None:
            not asked; the status then only says that the hard rows hold and which level is
            unmet, which is not a proof).

    Returns:
        The result; ``x`` is always finite.
    """
    n = problem.n
    if measured is None:
        if not (isinstance(x, np.ndarray) and x.shape == (n,) and x.dtype == np.float64
                and math.isfinite(float(x.dot(x)))):
            try:
                arr = np.asarray(x, dtype=np.float64)
            except (TypeError, ValueError):
                arr = np.zeros(0)
            if x is None or arr.shape != (n,) or not np.isfinite(arr).all():
                what = ("no x" if x is None else f"x of shape {arr.shape}, expected ({n},)"
                        if arr.shape != (n,) else "a non-finite x")
                if claim in OK_STATUSES:
                    claim = Status.BACKEND_ERROR
                message = (message + "; " if message else "") + f"back-end returned {what}"
                arr = placeholder(problem)
            x = arr
        measured = measure(problem, x)
    s, _, squares = measured
    hv = 0.0
    where = -1
    if squares[0]:  # something outside the box or a hard row (or NaN)
        hv, where = _largest(s[:problem.head])
    total = sum(squares)
    if total == total:  # no NaN (an inf residual stays inf)
        residuals = list(map(_SQRT, squares[1:]))
    else:
        residuals = [_INF if v != v else _SQRT(v) for v in squares[1:]]
    status, infeasible = claim, None
    unmet: tuple[int, ...] = ()
    cert: Certificate | None = None
    if claim is _OPTIMAL:
        if hv > hard_tol and hv > hard_tol * problem.hard_scale:
            status = Status.BACKEND_ERROR
            message = (message + "; " if message else "") + (
                f"{_where(problem, s, where)} violated by {hv:.2e}")
        elif total == _INF or total != total:
            status = Status.BACKEND_ERROR
            message = (message + "; " if message else "") + "non-finite level residual"
        else:
            status = _OPTIMAL
            # a level's scale only where its residual exceeds the bare tolerance (kept for the
            # certificate, which judges the same levels)
            scales: list[float | None] = []
            unmet_levels = []
            for k, r in enumerate(residuals):
                if r > level_tol:
                    scale = problem.level_scale(k)
                    if r > level_tol * scale:
                        unmet_levels.append(k)
                    scales.append(scale)
                else:
                    scales.append(None)
            if unmet_levels:
                unmet = tuple(unmet_levels)
                infeasible = unmet[0]
            if infeasible is not None and certify is not None:
                cert = certify(problem, x, s, residuals, hv, scales)
                if not cert.ok:
                    status = Status.UNPROVEN
                    message = (message + "; " if message else "") + cert.reason()
    return HierarchyResult(x, status, solver, residuals, infeasible, hv, solve_time, message,
                           info or {}, s, problem.spans, problem.box.copy(), cert, unmet)
