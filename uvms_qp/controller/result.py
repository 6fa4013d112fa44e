"""The outcome of one control step, for every scheme: :class:`StepResult`."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping

import numpy as np

from .._validation import FloatArray
from ..hqp import HierarchyResult, Status, hard_violation
from ..hqp.damping import Damping
from ..hqp.result import OK_STATUSES, levels_note
from .history import HISTORY_WINDOW, CommandHistory, reversals_per_s

#: Statuses of a verified answer of a scheme: the lexicographic optimum, damped or blended.
USABLE_STATUSES = (*OK_STATUSES, Status.DAMPED, Status.BLENDED, Status.COORDINATED)

Report = Mapping[str, tuple[float, str]]
"""Task name -> (value, unit)."""


class TaskLayout:
    """Where each task's rows sit in a stacked problem, with the units of its reports.

    Args:
        names: Task names, highest priority first.
        spans: ``(start, end)`` of each task's rows in the stacked rows of the problem.
        rate_units: Unit of each task's rows (e.g. ``"m/s"``).
        error_units: Unit of each task's error or objective (e.g. ``"m"``).
    """

    __slots__ = ("error_units", "names", "rate_units", "spans")

    def __init__(self, names: tuple[str, ...], spans: tuple[tuple[int, int], ...],
                 rate_units: tuple[str, ...], error_units: tuple[str, ...]) -> None:
        self.names, self.spans = names, spans
        self.rate_units, self.error_units = rate_units, error_units


class _Lazy(Mapping[str, tuple[float, str]]):
    """A read-only report computed on first access (most steps never read it)."""

    __slots__ = ("_data", "_layout", "_source")

    def __init__(self, layout: TaskLayout, source: object) -> None:
        self._layout, self._source = layout, source
        self._data: dict[str, tuple[float, str]] | None = None

    def _compute(self) -> dict[str, tuple[float, str]]:
        raise NotImplementedError

    def _values(self) -> dict[str, tuple[float, str]]:
        if self._data is None:
            self._data = self._compute()
        return self._data

    def __getitem__(self, key: str) -> tuple[float, str]:
        return self._values()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values())

    def __len__(self) -> int:
        return len(self._layout.names)

    def __repr__(self) -> str:
        return repr(self._values())


class TaskResiduals(_Lazy):
    """Task name -> (norm of its row violation at the command, unit of its rows) [rate unit].

    Read from the slacks of the hierarchy result (no second product with the rows).
    """

    __slots__ = ()

    def _compute(self) -> dict[str, tuple[float, str]]:
        s = self._source.slacks  # type: ignore[attr-defined]
        layout = self._layout
        return {name: (math.sqrt(float(s[a:b] @ s[a:b])), unit) for name, (a, b), unit in
                zip(layout.names, layout.spans, layout.rate_units, strict=True)}


class TaskErrors(_Lazy):
    """Task name -> (norm of its error or objective value this tick, unit); NaN if none."""

    __slots__ = ()

    def _compute(self) -> dict[str, tuple[float, str]]:
        layout = self._layout
        out = {}
        for name, e, unit in zip(layout.names, self._source,  # type: ignore[call-overload]
                                 layout.error_units, strict=True):
            if e is None:
                out[name] = (math.nan, unit)
            else:
                a = np.asarray(e, dtype=np.float64)
                out[name] = (float(np.sqrt(a @ a)), unit)
        return out


class Reversals:
    """The controller's reversal figure at one step, computed when first asked.

    Args:
        history: The controller's command history (bounds, period).
        ring: A copy of its ring after this step's command.
        count: Commands recorded up to and including this one.
        names: Names of the entries of zeta.
    """

    __slots__ = ("_count", "_history", "_names", "_ring", "_value")

    def __init__(self, history: CommandHistory, ring: FloatArray, count: int,
                 names: tuple[str, ...]) -> None:
        self._history, self._ring, self._count, self._names = history, ring, count, names
        self._value: float | None = None

    @property
    def per_s(self) -> float:
        """The worst entry's reversals per second over the last second of commands [1/s]."""
        if self._value is None:
            self._value = reversals_per_s(self._history, self._ring, self._count)
        return self._value


class StepResult:
    """Outcome of one control tick; never None, ``zeta`` always finite.

    Args and attributes:
        zeta: Commanded ``[vehicle body rates; joint rates]`` (nv,) [m/s, rad/s].
        status: Solver status (:class:`~uvms_qp.hqp.Status`).
        hierarchy: The measured :class:`~uvms_qp.hqp.HierarchyResult` of ``zeta`` (per-level
            residuals, slacks, active bounds, solve time), or None for a scheme that solves no
            hierarchy (the papers' closed forms).
        t: Time of the tick [s].
        step_time: Wall time of the whole step (rows, bounds, solve, measurement) [s].
        scheme: Name of the scheme (``"hqp"``, ``"weighted"``, ``"nullspace"``, a paper's).
        solver: Back-end name (``"closed-form"`` for the papers' schemes).
        lower: Hard lower bounds on zeta used this tick (nv,).
        upper: Hard upper bounds on zeta used this tick (nv,).
        saturated: zeta was clipped into the box by more than round-off (a closed form's
            saturation; see ``clipped``).
        level_names: Task names of each level.
        stage: Stage of the fallback ladder that produced zeta (:mod:`uvms_qp.safety`):
            ``primary`` on the happy path; ``cold_retry``, ``alternate``, ``relaxed`` (verified
            solves), ``decayed_previous``, ``zero``, ``hold_zero`` (degraded commands).
        clipped: Amount the box clip removed from the solver's zeta [m/s, rad/s].
        deadline_missed: The step took longer than the controller's ``deadline``.
        attempts: Why each earlier stage was rejected (empty on the happy path).
        task_residuals: Task name -> (norm of its row violation at zeta, unit of its rows).
        task_errors: Task name -> (norm of its error or objective value this tick, unit).
        damping: The damping rows added to the levels this tick and each level's smallest
            singular value (:class:`~uvms_qp.hqp.damping.Damping`), or None when no level was
            damped. With it the status is ``damped`` and ``hierarchy`` measures zeta against the
            problem with the damping rows.
        inactive: Names of the tasks out of the stack this tick (activation 0).
        ramping: Task name -> activation of the tasks ramping in or out (status ``blended``).
        reversals: The controller's reversal figure (:attr:`reversals_per_s`), or None.
    """

    __slots__ = ("attempts", "clipped", "damping", "deadline_missed", "hierarchy", "inactive",
                 "level_names", "lower", "ramping", "reversals", "saturated", "scheme", "solver",
                 "stage", "status", "step_time", "t", "task_errors", "task_residuals", "upper",
                 "zeta")

    def __init__(self, zeta: FloatArray, status: Status, hierarchy: HierarchyResult | None,
                 t: float, step_time: float, scheme: str, solver: str, lower: FloatArray,
                 upper: FloatArray, saturated: bool = False,
                 level_names: tuple[tuple[str, ...], ...] = (), stage: str = "primary",
                 clipped: float = 0.0, deadline_missed: bool = False,
                 attempts: tuple[str, ...] = (), task_residuals: Report | None = None,
                 task_errors: Report | None = None, *, damping: Damping | None = None,
                 inactive: tuple[str, ...] = (), ramping: Mapping[str, float] | None = None,
                 reversals: Reversals | None = None) -> None:
        self.zeta, self.status, self.hierarchy = zeta, status, hierarchy
        self.t, self.step_time, self.scheme, self.solver = t, step_time, scheme, solver
        self.lower, self.upper, self.saturated = lower, upper, saturated
        self.level_names, self.stage, self.clipped = level_names, stage, clipped
        self.deadline_missed, self.attempts = deadline_missed, attempts
        self.task_residuals: Report = {} if task_residuals is None else task_residuals
        self.task_errors: Report = {} if task_errors is None else task_errors
        self.damping, self.inactive = damping, inactive
        self.ramping: Mapping[str, float] = {} if ramping is None else ramping
        self.reversals = reversals

    @property
    def ok(self) -> bool:
        """True when zeta is the scheme's verified answer.

        The proven lexicographic optimum (``optimal``), or the controller's
        smoothed form of it: ``damped`` (the optimum of the stack with damping rows near a
        singularity) and ``blended`` (tasks ramping in or out); the hierarchy's own claim of
        the lexicographic optimum is :attr:`HierarchyResult.ok` of :attr:`hierarchy`.
        """
        return self.status in USABLE_STATUSES

    @property
    def damped_levels(self) -> tuple[int, ...]:
        """Indices of the levels damped this tick (empty when none)."""
        return () if self.damping is None else self.damping.damped_levels

    @property
    def reversals_per_s(self) -> float | None:
        """Worst entry's command reversals per second over the last second [1/s], or None.

        Counted on the controller's own commands (:mod:`uvms_qp.controller.history`); None for a
        scheme that keeps no history.
        """
        return None if self.reversals is None else self.reversals.per_s

    @property
    def degraded(self) -> bool:
        """True when zeta did not come from the primary back-end (see ``stage``)."""
        return self.stage != "primary"

    @property
    def level_violations(self) -> list[float]:
        """Per level: unweighted norm of the row violation at zeta (scheme-independent)."""
        res = self.task_residuals
        return [math.sqrt(sum(res[name][0] ** 2 for name in names))
                for names in self.level_names]

    @property
    def bound_violation(self) -> float:
        """Largest violation of the hard box and hard rows at zeta (0 when they hold)."""
        if self.hierarchy is not None:
            return self.hierarchy.hard_violation
        return hard_violation(self.zeta, self.lower, self.upper)

    def summary(self) -> str:
        """A readable report: status, time, per-level and per-task residuals with units."""
        note = levels_note(self.hierarchy) if self.hierarchy is not None else ""
        lines = [f"t = {self.t:.3f} s  {self.scheme}/{self.solver}: {self.status.value}{note}  "
                 f"step {self.step_time * 1e6:.0f} us"
                 + ("  (saturated into the box)" if self.saturated else "")
                 + (f"  [fallback: {self.stage}]" if self.stage != "primary" else "")]
        res = self.task_residuals
        err = self.task_errors
        for k, (names, violation) in enumerate(zip(self.level_names, self.level_violations,
                                                   strict=True)):
            mark = ""
            if self.hierarchy is not None and self.hierarchy.ok and k < len(
                    self.hierarchy.level_residuals):
                mark = ("  unmet, proven optimal" if k in self.hierarchy.unmet_levels
                        else "  met")
            lines.append(f"  level {k}: violation {violation:.3e}{mark}")
            for name in names:
                r, ru = res[name]
                e, eu = err.get(name, (math.nan, ""))
                lines.append(f"    {name:<22} residual {r:.3e} [{ru}]   error {e:.3e} [{eu}]")
        lines.append(f"  zeta = {np.array2string(self.zeta, precision=4, suppress_small=True)}")
        lines.append(f"  hard bound violation {self.bound_violation:.1e}")
        if self.reversals is not None:
            lines.append(f"  command reversals {self.reversals.per_s:.3g} /s (worst entry, last "
                         f"{HISTORY_WINDOW:g} s)")
        if self.damping is not None:
            sigma = self.damping.sigma_min
            lines.append("  damped near a singularity (not the stack's lexicographic optimum): "
                         + ", ".join(f"level {k} (sigma_min {sigma[k]:.3g})"
                                     for k in self.damping.damped_levels))
        if self.inactive:
            lines.append(f"  out of the stack: {', '.join(self.inactive)}")
        if self.ramping:
            lines.append("  ramping (blend of the optima with and without): " + ", ".join(
                f"{name} at {a:.3g}" for name, a in self.ramping.items()))
        message = self.hierarchy.message if self.hierarchy is not None else ""
        if message:
            lines.append(f"  {message}")
        lines.extend(f"  rejected: {a}" for a in self.attempts)
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"StepResult(t={self.t:g}, {self.scheme}/{self.solver}: {self.status.value}, "
                f"stage={self.stage})")
