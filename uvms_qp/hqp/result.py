"""The result of a lexicographic solve: the status vocabulary and per-level diagnostics."""

from __future__ import annotations

from enum import StrEnum
from typing import TYPE_CHECKING

import numpy as np

from .._validation import FloatArray
from .tolerances import TIGHT_TOL

if TYPE_CHECKING:  # pragma: no cover - the certificate module sits above the result
    from .certificate import Certificate


class Status(StrEnum):
    """Outcome of a hierarchy solve.

    Members:
        OPTIMAL: ``x`` is the lexicographic optimum, proven: the hard rows hold and every level
            is met (to tolerance) or, where it cannot be met, proven optimal by the certificate
            (:mod:`uvms_qp.hqp.certificate`). Which levels are met is per level:
            ``HierarchyResult.unmet_levels`` (empty when every level is met) and
            ``infeasible_level`` (the first unmet one). Lower levels that a higher one leaves
            unmet are the normal case of a priority stack, not a failure.
        UNPROVEN: ``x`` is finite and inside the hard set, but it is not proven to be the
            lexicographic optimum: the optimality certificate of an unmet level failed (an
            improving direction, an ill-posed level, or a closed form's damping);
            ``HierarchyResult.certificate`` and the message say which level and why.
        HARD_INFEASIBLE: the hard box and hard rows admit no point; ``x`` is only a finite
            placeholder (the closest point the back-end reached).
        BACKEND_ERROR: the back-end failed or could not enforce a requirement (message says which);
            ``x`` is finite but must not be used as a lexicographic optimum.
        DAMPED: ``x`` is the lexicographic optimum of the problem with damping rows added to some
            levels near a singularity (:mod:`uvms_qp.hqp.damping`), not of the problem without
            them: those levels trade residual for bounded rates.
        BLENDED: ``x`` is a convex combination of the optima with and without tasks whose
            activation ramps between 0 and 1: the optimum of neither.
        COORDINATED: arm-vehicle coordination (a controller option on a floating vehicle): the
            vehicle's rates are the answer of the whole stack, the joints' rates the proven
            lexicographic optimum of the stack with the vehicle's rates fixed at their measured
            values; the command as a whole is the optimum of neither problem.

    Migration: versions before this vocabulary called a proven optimum with an unmet level
    ``level_infeasible``; ``Status("level_infeasible")`` reads it as :attr:`OPTIMAL` (e.g. a
    ``results.json`` written then).
    """

    OPTIMAL = "optimal"
    UNPROVEN = "unproven"
    HARD_INFEASIBLE = "hard_infeasible"
    BACKEND_ERROR = "backend_error"
    DAMPED = "damped"
    BLENDED = "blended"
    COORDINATED = "coordinated"

    @classmethod
    def _missing_(cls, value: object) -> Status | None:
        """Old names: ``level_infeasible`` is :attr:`OPTIMAL` (with an unmet level)."""
        return cls.OPTIMAL if value == "level_infeasible" else None


#: How a summary reads the certificate's verdict on a level.
_VERDICTS = {"met": "met", "certified": "NOT met, proven optimal",
             "ill_posed": "NOT met, ill-posed (not proven)", "improvable": "NOT met, improvable",
             "unproven": "NOT met, not proven optimal",
             "late": "NOT met, not proven optimal (deadline)"}

#: Statuses that claim the lexicographic optimum.
OK_STATUSES = (Status.OPTIMAL,)
#: Old status names and the status each now reads as (``Status(old)`` applies it).
RENAMED = {"level_infeasible": "optimal"}


class HierarchyResult:
    """Solution of a lexicographic problem with diagnostics; never None, ``x`` never NaN.

    Built by :func:`uvms_qp.hqp.measure.evaluate` from one product of the stacked rows with ``x``
    (the signed slack of every box bound, hard row and level row); the per-level slacks and the
    active-bound masks are views of that product and of the result's own copy of the box, built
    on first access.

    Attributes:
        x: Solution, shape (n,), always finite (units of the decision vector, e.g. [m/s], [rad/s]).
        status: Outcome, see :class:`Status`.
        solver: Name of the back-end that produced ``x``.
        level_residuals: Weighted violation norm ``sqrt(sum_i w_i s_i^2)`` per level.
        infeasible_level: Index of the first level not met (to tolerance), or None.
        unmet_levels: Indices of every level not met (to tolerance), highest first (empty when
            every level is met); with status ``optimal`` each of them is proven optimal.
        hard_violation: Largest violation of the hard box and hard rows at ``x`` (0 when they
            hold) [units of the rows].
        solve_time: Wall time of the solve [s], validation excluded.
        message: Human-readable detail (back-end exit flags, which bound, ...).
        info: Back-end specific extras (e.g. DAQP's own reported solve time, iterations).
        slacks: Signed slack ``s = A x - clip(A x, lo, hi)`` of every row of the stacked problem
            ``[box; hard rows; level rows]`` (> 0 above ``hi``, < 0 below ``lo``).
        box: The hard box of the solve, shape (2, n): rows ``lower`` and ``upper`` (the
            result's own copy).
        certificate: The optimality certificate of the unmet levels
            (:class:`~uvms_qp.hqp.certificate.Certificate`), or None when every level is met or
            none was asked.
    """

    __slots__ = (
        "_active",
        "_spans",
        "box",
        "certificate",
        "hard_violation",
        "infeasible_level",
        "info",
        "level_residuals",
        "message",
        "slacks",
        "solve_time",
        "solver",
        "status",
        "unmet_levels",
        "x",
    )

    def __init__(self, x: FloatArray, status: Status, solver: str,
                 level_residuals: list[float], infeasible_level: int | None,
                 hard_violation: float, solve_time: float, message: str,
                 info: dict[str, object], slacks: FloatArray,
                 spans: tuple[tuple[int, int], ...], box: FloatArray,
                 certificate: Certificate | None = None,
                 unmet_levels: tuple[int, ...] | None = None) -> None:
        self.x = x
        self.status = status
        self.solver = solver
        self.level_residuals = level_residuals
        self.infeasible_level = infeasible_level
        self.hard_violation = hard_violation
        self.solve_time = solve_time
        self.message = message
        self.info = info
        self.slacks = slacks
        self._spans = spans
        self.box = box
        self.certificate = certificate
        self.unmet_levels = (unmet_levels if unmet_levels is not None
                             else () if infeasible_level is None else (infeasible_level,))
        self._active: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def ok(self) -> bool:
        """True when ``x`` is the proven lexicographic optimum (status ``optimal``)."""
        return self.status in OK_STATUSES

    @property
    def ill_posed(self) -> bool:
        """True for an ``unproven`` answer whose first unproven level is ill-posed.

        The exact optimum of its frozen set, but a 1e-9 change of the levels above could change
        it by more than the tolerance (no solver can prove better).
        """
        cert = self.certificate
        return self.status is Status.UNPROVEN and cert is not None and cert.ill_posed

    @property
    def level_slacks(self) -> list[FloatArray]:
        """Signed slack per level, ``s = A_k x - clip(A_k x, lo_k, hi_k)`` (views of ``slacks``)."""
        s = self.slacks
        return [s[a:b] for a, b in self._spans]

    @property
    def stacked_slacks(self) -> FloatArray:
        """Signed slacks of every level row in priority order (a view of ``slacks``)."""
        spans = self._spans
        start = spans[0][0] if spans else self.slacks.shape[0]
        return self.slacks[start:]

    def _masks(self) -> tuple[np.ndarray, np.ndarray]:
        if self._active is None:
            lo, hi = self.box
            x = self.x
            tol_lo = TIGHT_TOL * (1.0 + np.abs(np.where(np.isfinite(lo), lo, 0.0)))
            tol_hi = TIGHT_TOL * (1.0 + np.abs(np.where(np.isfinite(hi), hi, 0.0)))
            self._active = (x - lo <= tol_lo, hi - x <= tol_hi)
        return self._active

    @property
    def active_lower(self) -> np.ndarray:
        """Mask of variables at their lower bound (``x - lower <= 1e-9 (1 + |lower|)``)."""
        return self._masks()[0]

    @property
    def active_upper(self) -> np.ndarray:
        """Mask of variables at their upper bound (``upper - x <= 1e-9 (1 + |upper|)``)."""
        return self._masks()[1]

    def summary(self) -> str:
        """Return a short multi-line report a person can read."""
        lines = [f"solver {self.solver}: {self.status.value}{levels_note(self)}"
                 f" in {self.solve_time * 1e6:.1f} us"]
        cert = self.certificate
        for k, (r, (a, b)) in enumerate(zip(self.level_residuals, self._spans, strict=True)):
            mark = ""
            if cert is not None:
                mark = _VERDICTS.get(cert.levels[k].verdict, "")
            elif self.ok:
                mark = "NOT met" if k in self.unmet_levels else "met"
            lines.append(f"  level {k}: residual {r:.3e} ({b - a} rows) {mark}".rstrip())
        n_lo, n_hi = int(self.active_lower.sum()), int(self.active_upper.sum())
        lines.append(f"  active bounds: {n_lo} lower, {n_hi} upper; "
                     f"hard violation {self.hard_violation:.1e}")
        if self.message:
            lines.append(f"  {self.message}")
        return "\n".join(lines)


def levels_note(result: HierarchyResult) -> str:
    """`` (every level met)`` or `` (levels 2, 3 unmet, proven optimal)`` for a status line.

    Empty for a result that is not the proven optimum (its message says why).
    """
    if not result.ok:
        return ""
    unmet = result.unmet_levels
    if not unmet:
        return " (every level met)"
    which = f"level {unmet[0]}" if len(unmet) == 1 else "levels " + ", ".join(map(str, unmet))
    return f" ({which} unmet, proven optimal)"
