"""The result of a lexicographic solve: status vocabulary and per-level diagnostics."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np

from .._validation import FloatArray


class Status(StrEnum):
    """Outcome of a hierarchy solve.

    Members:
        OPTIMAL: every level is met (to tolerance) and the hard rows hold.
        LEVEL_INFEASIBLE: ``x`` is the lexicographic optimum, but some level cannot be met exactly;
            ``HierarchyResult.infeasible_level`` is the first such level.
        HARD_INFEASIBLE: the hard box and hard rows admit no point; ``x`` is only a finite
            placeholder (the closest point the back-end reached).
        BACKEND_ERROR: the back-end failed or could not enforce a requirement (message says which);
            ``x`` is finite but must not be used as a lexicographic optimum.
    """

    OPTIMAL = "optimal"
    LEVEL_INFEASIBLE = "level_infeasible"
    HARD_INFEASIBLE = "hard_infeasible"
    BACKEND_ERROR = "backend_error"


@dataclass(eq=False)
class HierarchyResult:
    """Solution of a lexicographic problem with diagnostics; never None, ``x`` never NaN.

    Attributes:
        x: Solution, shape (n,), always finite (units of the decision vector, e.g. [m/s], [rad/s]).
        status: Outcome, see :class:`Status`.
        solver: Name of the back-end that produced ``x``.
        level_residuals: Weighted violation norm ``sqrt(sum_i w_i s_i^2)`` per level.
        level_slacks: Signed slack per level, ``s = A x - clip(A x, lo, hi)``.
        infeasible_level: Index of the first level not met exactly, or None.
        active_lower: Mask of variables at their lower bound (to tolerance).
        active_upper: Mask of variables at their upper bound (to tolerance).
        hard_violation: Largest violation of the hard box and hard rows at ``x``.
        solve_time: Wall time of the solve [s], validation excluded.
        message: Human-readable detail (back-end exit flags, which bound, ...).
        info: Back-end specific extras (e.g. DAQP's own reported solve time, iterations).
    """

    x: FloatArray
    status: Status
    solver: str
    level_residuals: list[float] = field(default_factory=list)
    level_slacks: list[FloatArray] = field(default_factory=list)
    infeasible_level: int | None = None
    active_lower: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    active_upper: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    hard_violation: float = 0.0
    solve_time: float = 0.0
    message: str = ""
    info: dict[str, object] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when ``x`` is the lexicographic optimum (optimal or level_infeasible)."""
        return self.status in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE)

    @property
    def stacked_slacks(self) -> FloatArray:
        """Signed slacks of every level row in priority order (``level_slacks`` end to end).

        E.g. the squared violation of rows ``a:b`` of the stacked levels is
        ``(s[a:b] ** 2).sum()`` without another product with the rows.
        """
        return np.concatenate(self.level_slacks) if self.level_slacks else np.zeros(0)

    def summary(self) -> str:
        """Return a short multi-line report a person can read."""
        lines = [
            f"solver {self.solver}: {self.status.value}"
            + (f" (first unmet level {self.infeasible_level})"
               if self.infeasible_level is not None else "")
            + f" in {self.solve_time * 1e6:.1f} us",
        ]
        for k, r in enumerate(self.level_residuals):
            mark = ""
            if self.ok:
                mark = "NOT met" if k == self.infeasible_level else (
                    "met" if self.infeasible_level is None or k < self.infeasible_level else "")
            lines.append(f"  level {k}: residual {r:.3e} ({self.level_slacks[k].size} rows) {mark}"
                         .rstrip())
        n_lo, n_hi = int(self.active_lower.sum()), int(self.active_upper.sum())
        lines.append(f"  active bounds: {n_lo} lower, {n_hi} upper; "
                     f"hard violation {self.hard_violation:.1e}")
        if self.message:
            lines.append(f"  {self.message}")
        return "\n".join(lines)


class StackedResult(HierarchyResult):
    """A :class:`HierarchyResult` whose slacks and active-bound masks are built on first access.

    The hot path measures every slack in one stacked vector (see :mod:`uvms_qp.hqp.workspace`);
    ``level_slacks`` are views of it and ``active_lower``/``active_upper`` are computed from
    fresh copies of the bounds only when read. Every attribute has the value and meaning it has
    on :class:`HierarchyResult`; all of them can be assigned.

    The first nine arguments are the :class:`HierarchyResult` fields of the same names; then

    Args:
        slacks: Stacked signed slacks (box, hard rows, level rows), owned by the result.
        head: Number of box and hard-row entries before the level rows in ``slacks``.
        spans: ``(start, end)`` of each level inside the level rows.
        lower: Array whose first n entries are the lower bounds (e.g. the stacked lower sides);
            owned by the result (never a reused buffer).
        upper: Same for the upper bounds.
    """

    def __init__(
        self,
        x: FloatArray,
        status: Status,
        solver: str,
        level_residuals: list[float],
        infeasible_level: int | None,
        hard_violation: float,
        solve_time: float,
        message: str,
        info: dict[str, object],
        *,
        slacks: FloatArray,
        head: int,
        spans: tuple[tuple[int, int], ...],
        lower: FloatArray,
        upper: FloatArray,
    ) -> None:
        self.x = x
        self.status = status
        self.solver = solver
        self.level_residuals = level_residuals
        self.infeasible_level = infeasible_level
        self.hard_violation = hard_violation
        self.solve_time = solve_time
        self.message = message
        self.info = info
        self._s = slacks
        self._head = head
        self._spans = spans
        self._bounds = (lower, upper)
        self._slacks: list[FloatArray] | None = None
        self._assigned = False
        self._active: tuple[np.ndarray, np.ndarray] | None = None

    @property  # type: ignore[override]
    def level_slacks(self) -> list[FloatArray]:
        """Signed slack per level, ``s = A x - clip(A x, lo, hi)`` (views of one array)."""
        if self._slacks is None:
            s, h = self._s, self._head
            self._slacks = [s[h + a: h + b] for a, b in self._spans]
        return self._slacks

    @level_slacks.setter
    def level_slacks(self, value: list[FloatArray]) -> None:
        self._slacks = value
        self._assigned = True

    @property
    def stacked_slacks(self) -> FloatArray:
        """Signed slacks of every level row in priority order (a view, no copy)."""
        if self._assigned:  # level_slacks were replaced from outside: follow them
            return super().stacked_slacks
        return self._s[self._head:]

    @property
    def box(self) -> tuple[FloatArray, FloatArray]:
        """The hard box ``(lower, upper)`` of the solve (views of the result's own copies)."""
        n = self.x.shape[0]
        return self._bounds[0][:n], self._bounds[1][:n]

    def _masks(self) -> tuple[np.ndarray, np.ndarray]:
        if self._active is None:
            n = self.x.shape[0]
            lo, hi, x = self._bounds[0][:n], self._bounds[1][:n], self.x
            tol_lo = 1e-9 * (1.0 + np.abs(np.where(np.isfinite(lo), lo, 0.0)))
            tol_hi = 1e-9 * (1.0 + np.abs(np.where(np.isfinite(hi), hi, 0.0)))
            self._active = (x - lo <= tol_lo, hi - x <= tol_hi)
        return self._active

    @property  # type: ignore[override]
    def active_lower(self) -> np.ndarray:
        """Mask of variables at their lower bound (``x - lower <= 1e-9 (1 + |lower|)``)."""
        return self._masks()[0]

    @active_lower.setter
    def active_lower(self, value: np.ndarray) -> None:
        self._active = (value, self._masks()[1])

    @property  # type: ignore[override]
    def active_upper(self) -> np.ndarray:
        """Mask of variables at their upper bound (``upper - x <= 1e-9 (1 + |upper|)``)."""
        return self._masks()[1]

    @active_upper.setter
    def active_upper(self, value: np.ndarray) -> None:
        self._active = (self._masks()[0], value)
