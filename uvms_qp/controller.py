"""The control loop: model + stack + solver -> one zeta per tick.

Every tick :meth:`Controller.step` writes each task's rows and each constraint's bounds straight
into buffers allocated once (no per-tick assembly of the problem), solves, and returns a
:class:`StepResult`. The same stack can be solved three ways (``scheme``):

* ``"hqp"``: the lexicographic QP (levels are strict priorities; the hard box and hard rows hold
  at every level), with any back-end of :func:`uvms_qp.hqp.available_solvers`;
* ``"weighted"``: one weighted QP, priorities turned into weights (level ``k`` of ``p`` gets its
  squared violations multiplied by ``priority_ratio ** (p - 1 - k)``), same hard bounds: the
  usual "soft priorities" of weighted differential IK, for comparison. ``solver="daqp"`` is run
  as the plain QP ``"cascade:daqp"`` (in DAQP's hierarchical mode the priority weights would
  become soft weights spanning ``priority_ratio ** (p - 1)``, far more than its soft-row
  regularisation resolves accurately); very large ratios make the QP ill-conditioned (1e2-1e4
  work well);
* ``"nullspace"``: the closed-form recursive null-space scheme
  (``000_7b5f597fe4e36aa4.txt, Eq. (10)`` extended to p levels, in the metric W of Eq. (17)):
  inequality rows are left out (the scheme has no notion of them) and the result is saturated
  into the hard box afterwards (``StepResult.saturated`` tells when that happened); hard rows
  are not enforced (their violation is reported).

``metric`` is the diagonal W of the final regularisation ``min zeta' W zeta`` (e.g.
:func:`uvms_qp.tasks.motion_distribution_weights`, ``003_229789978cc4b235.txt, Eq. (14)``, or
``diag(10, 10, 10, 1, 1, 1)`` of paper 000).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from functools import cached_property
from operator import attrgetter, is_
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ._validation import FloatArray, as_scalar, as_vector
from .constraints.constraint import Constraint
from .errors import BoundsError, InputError, NonFiniteError
from .hqp import HierarchyResult, HierarchySolver, Status
from .hqp.backends.daqp_hierarchical import DaqpHierarchicalBackend
from .hqp.backends.nullspace import nullspace_solve
from .hqp.evaluate import evaluate
from .hqp.inplace import InPlaceDaqp
from .hqp.problem import Block, Problem
from .hqp.result import StackedResult
from .rows import Rows
from .safety.fallback import PRIMARY, ZERO, SafeSolver, default_alternate
from .stack import Stack
from .tasks.task import Task

if TYPE_CHECKING:  # pragma: no cover
    from .model import Model, State

_ROW_WEIGHTS = attrgetter("row_weights")
Scheme = Literal["hqp", "weighted", "nullspace"]
SCHEMES: tuple[str, ...] = ("hqp", "weighted", "nullspace")
#: Rank decision of the ``"nullspace"`` scheme (see :func:`uvms_qp.hqp.backends.nullspace.
#: nullspace_solve`): singular values of a projected level at or below
#: ``max(NULLSPACE_ATOL, NULLSPACE_RCOND * |weighted rows of the level|_F)`` are dropped.
NULLSPACE_RCOND = 1e-10
NULLSPACE_ATOL = 0.0


def _check_arguments(model: Any, solver: Any, options: Any, strict: Any) -> None:
    """Reject constructor arguments of the wrong type, naming the argument.

    Raises:
        InputError: ``model`` is not a :class:`~uvms_qp.model.Model`, ``solver`` not a string,
            ``options`` neither None nor a dict, or ``strict`` not a bool.
    """
    from .model import Model

    if not isinstance(model, Model):
        hint = (f"; load a bundled model with uvms_qp.load_model({model!r})"
                if isinstance(model, str) else "")
        raise InputError(f"model: expected a Model, got {type(model).__name__}{hint}")
    if not isinstance(solver, str):
        raise InputError(f"solver: expected a solver name (str), got {type(solver).__name__}")
    if options is not None and not isinstance(options, dict):
        raise InputError(
            f"options: expected a dict of back-end options or None, got {type(options).__name__}")
    if not isinstance(strict, bool | np.bool_):
        raise InputError(f"strict: expected True or False, got {strict!r}")


def not_a_state(value: Any) -> InputError:
    """The error for a ``step`` called with something other than a model :class:`State`.

    A configuration array is the usual mistake: the message says how to make the state.
    """
    kind = type(value).__module__ + "." + type(value).__qualname__
    if kind.startswith("builtins."):
        kind = type(value).__qualname__
    return InputError(
        f"state: step expects a State, got {kind}; build one from a configuration q with "
        "model.state(q)"
    )


@dataclass(eq=False)
class StepResult:
    """Outcome of one control tick; never None, ``zeta`` always finite.

    Attributes:
        zeta: Commanded ``[vehicle body rates; joint rates]`` (nv,) [m/s, rad/s].
        status: Solver status (:class:`~uvms_qp.hqp.Status`: ``optimal``, ``level_infeasible``,
            ``hard_infeasible``, ``backend_error``).
        hierarchy: The solver's :class:`~uvms_qp.hqp.HierarchyResult` (per-level residuals,
            slacks, active bounds, solve time).
        t: Time of the tick [s].
        step_time: Wall time of the whole step (rows, bounds, solve, residuals) [s].
        scheme: ``"hqp"``, ``"weighted"`` or ``"nullspace"``.
        solver: Back-end name.
        lower: Hard lower bounds on zeta used this tick (nv,).
        upper: Hard upper bounds on zeta used this tick (nv,).
        saturated: True when zeta had to be clipped into the box by more than round-off
            (nullspace scheme, or a fallback stage; see ``clipped``).
        level_names: Task names of each level.
        stage: Stage of the fallback ladder that produced zeta (:mod:`uvms_qp.safety`):
            ``primary`` on the happy path; ``cold_retry``, ``alternate``, ``relaxed`` (verified
            solves), ``decayed_previous``, ``zero``, ``hold_zero`` (degraded commands).
        clipped: Amount the final saturation removed from the solver's zeta [m/s, rad/s].
        deadline_missed: The step took longer than the controller's ``deadline``.
        attempts: Why each earlier stage was rejected (empty on the happy path).
    """

    zeta: FloatArray
    status: Status
    hierarchy: HierarchyResult
    t: float
    step_time: float
    scheme: str
    solver: str
    lower: FloatArray
    upper: FloatArray
    saturated: bool = False
    level_names: tuple[tuple[str, ...], ...] = ()
    stage: str = PRIMARY
    clipped: float = 0.0
    deadline_missed: bool = False
    attempts: tuple[str, ...] = ()
    _task_names: tuple[str, ...] = ()
    _rate_units: tuple[str, ...] = ()
    _error_units: tuple[str, ...] = ()
    _residual_sq: FloatArray = field(default_factory=lambda: np.zeros(0))
    _errors: tuple[FloatArray | None, ...] = ()
    _hard_rows_violation: float = 0.0
    _level_sizes: tuple[int, ...] = ()

    @classmethod
    def from_command(
        cls,
        zeta: FloatArray,
        *,
        t: float,
        step_time: float,
        scheme: str,
        solver: str = "closed-form",
        residuals: dict[str, tuple[float, str]] | None = None,
        lower: FloatArray | None = None,
        upper: FloatArray | None = None,
        status: Status = Status.OPTIMAL,
        message: str = "",
    ) -> StepResult:
        """Public constructor for schemes that compute zeta without a hierarchy solve.

        The embedded :class:`~uvms_qp.hqp.HierarchyResult` carries ``zeta`` with ``status``, no
        level residuals and the step time as solve time; ``task_residuals`` and ``task_errors``
        report ``residuals`` (task name -> (norm, unit)).

        Args:
            zeta: Finite command (nv,) [m/s, rad/s].
            t: Time of the tick [s].
            step_time: Wall time of the step [s].
            scheme: Name of the scheme.
            solver: Name recorded as the solver.
            residuals: Task name -> (error norm, unit).
            lower: Box the command respects (default unbounded).
            upper: Box the command respects (default unbounded).
            status: Status to report.
            message: Detail kept in ``hierarchy.message``.

        Raises:
            NonFiniteError: zeta holds NaN or inf.
        """
        z = np.asarray(zeta, dtype=np.float64)
        if not np.all(np.isfinite(z)):
            raise NonFiniteError(f"{scheme}: non-finite zeta at t = {t}")
        n = z.shape[0]
        res = residuals or {}
        names = tuple(res)
        values = np.asarray([res[k][0] for k in names], dtype=np.float64)
        units = tuple(res[k][1] for k in names)
        hierarchy = HierarchyResult(x=z, status=status, solver=solver, solve_time=step_time,
                                    message=message)
        return cls(
            zeta=z, status=status, hierarchy=hierarchy, t=float(t), step_time=float(step_time),
            scheme=scheme, solver=solver,
            lower=np.full(n, -np.inf) if lower is None else lower,
            upper=np.full(n, np.inf) if upper is None else upper,
            level_names=(names,) if names else (), _task_names=names, _rate_units=units,
            _error_units=units, _residual_sq=np.square(values),
            _errors=tuple(np.array([v]) for v in values.tolist()),
            _level_sizes=(len(names),) if names else ())

    @property
    def ok(self) -> bool:
        """True when zeta is the scheme's optimum (``optimal`` or ``level_infeasible``)."""
        return self.status in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE)

    @property
    def degraded(self) -> bool:
        """True when zeta did not come from the primary back-end (see ``stage``)."""
        return self.stage != PRIMARY

    @cached_property
    def task_residuals(self) -> dict[str, tuple[float, str]]:
        """Task name -> (norm of its row violation at zeta, unit of its rows)."""
        return {name: (math.sqrt(s), unit) for name, s, unit in
                zip(self._task_names, self._residual_sq.tolist(), self._rate_units, strict=True)}

    @cached_property
    def level_violations(self) -> list[float]:
        """Per level: unweighted norm of the row violation at zeta (scheme-independent)."""
        out = []
        i = 0
        sq = self._residual_sq.tolist()
        for size in self._level_sizes:
            out.append(math.sqrt(sum(sq[i:i + size])))
            i += size
        return out

    @cached_property
    def task_errors(self) -> dict[str, tuple[float, str]]:
        """Task name -> (norm of its error or objective value this tick, unit); NaN if none."""
        out = {}
        for name, e, unit in zip(self._task_names, self._errors, self._error_units, strict=True):
            out[name] = (float(np.sqrt(e @ e)) if e is not None else float("nan"), unit)
        return out

    @cached_property
    def bound_violation(self) -> float:
        """Largest violation of the hard box and hard rows at zeta (0 when they hold)."""
        v = max(float(np.max(self.lower - self.zeta, initial=0.0)),
                float(np.max(self.zeta - self.upper, initial=0.0)))
        return max(v, self._hard_rows_violation)

    def summary(self) -> str:
        """A readable report: status, time, per-level and per-task residuals with units."""
        lines = [f"t = {self.t:.3f} s  {self.scheme}/{self.solver}: {self.status.value}  "
                 f"step {self.step_time * 1e6:.0f} us"
                 + ("  (saturated into the box)" if self.saturated else "")
                 + (f"  [fallback: {self.stage}]" if self.stage != PRIMARY else "")]
        res = self.task_residuals
        err = self.task_errors
        for k, names in enumerate(self.level_names):
            lines.append(f"  level {k}: violation {self.level_violations[k]:.3e}")
            for name in names:
                r, ru = res[name]
                e, eu = err[name]
                lines.append(f"    {name:<22} residual {r:.3e} [{ru}]   error {e:.3e} [{eu}]")
        lines.append(f"  zeta = {np.array2string(self.zeta, precision=4, suppress_small=True)}")
        lines.append(f"  hard bound violation {self.bound_violation:.1e}")
        if self.hierarchy.message:
            lines.append(f"  {self.hierarchy.message}")
        lines.extend(f"  rejected: {a}" for a in self.attempts)
        return "\n".join(lines)


class Controller:
    """Solve a :class:`~uvms_qp.stack.Stack` on a model every tick.

    Args:
        model: The UVMS model (the stack is bound to it here).
        stack: Levels of tasks and hard constraints.
        solver: Back-end (``"daqp"``, ``"cascade:<qpsolvers name>"``, ``"nullspace"``).
        dt: Control period [s] (turns position limits into rate bounds).
        metric: Diagonal W (nv,) of the final regularisation ``min zeta' W zeta`` (positive), or
            None for the identity.
        scheme: ``"hqp"``, ``"weighted"`` or ``"nullspace"`` (see the module docstring).
        priority_ratio: Weight ratio between consecutive levels for ``scheme="weighted"``.
        options: Back-end options passed to :class:`~uvms_qp.hqp.HierarchySolver`.
        strict: Raise :class:`~uvms_qp.errors.NoSolutionFound` when no back-end returns a
            verified solution, instead of degrading (relaxed levels, decayed previous command,
            zero; see :mod:`uvms_qp.safety` and ``docs/reliability.md``).
        deadline: Wall-time budget of one step [s] (None: none); back-ends get matching time or
            iteration limits and the fallback ladder skips its solver stages once it has passed.

    Raises:
        InputError: bad dt, metric or scheme; any binding error of the stack (unknown frame,
            joint, axis...), with its location in the stack.
        UnknownSolverError: unknown or uninstalled solver.
    """

    def __init__(
        self,
        model: Model,
        stack: Stack,
        solver: str = "daqp",
        dt: float = 0.05,
        metric: Any = None,
        *,
        scheme: Scheme = "hqp",
        priority_ratio: float = 1e4,
        options: dict[str, Any] | None = None,
        strict: bool = False,
        deadline: float | None = None,
    ) -> None:
        _check_arguments(model, solver, options, strict)
        if not isinstance(stack, Stack):
            raise InputError(f"stack: expected a Stack, got {type(stack).__name__}")
        if scheme not in SCHEMES:
            raise InputError(f"scheme: expected one of {', '.join(SCHEMES)}, got {scheme!r}")
        self.model = model
        self.stack = stack.bind(model)
        self.dt = as_scalar(dt, "dt", positive=True)
        self.scheme = scheme
        self.priority_ratio = as_scalar(priority_ratio, "priority_ratio", positive=True)
        nv = int(model.nv)
        self.nv = nv
        self.metric = (np.ones(nv) if metric is None
                       else as_vector(metric, "metric", nv, positive=True))
        if scheme == "nullspace":
            solver = "nullspace"
        elif scheme == "weighted" and solver == "daqp":
            # as soft weights of one DAQP level the priority weights would span more orders of
            # magnitude than its soft-row regularisation resolves; DAQP as a plain QP is exact
            solver = "cascade:daqp"
        self.strict = bool(strict)  # a bool (or NumPy bool) by _check_arguments
        if scheme == "nullspace":
            self._safe: SafeSolver | None = None
            self._solver = HierarchySolver(solver, weights=self.metric, options=options)
        else:
            alternate = default_alternate(solver, cascade_only=scheme == "weighted")
            self._safe = SafeSolver(solver, self.metric, options, alternate=alternate,
                                    deadline=deadline, strict=self.strict)
            self._solver = self._safe.primary
        self.solver_name = self._solver.name
        self._build_buffers()

    # ------------------------------------------------------------------------------------- set-up
    def _build_buffers(self) -> None:
        nv = self.nv
        levels = self.stack.levels
        tasks: list[Task] = [t for level in levels for t in level]
        total = sum(t.dim for t in tasks)
        row_cons = [c for c in self.stack.constraints if c.rows_dim > 0]
        mh = sum(c.rows_dim for c in row_cons)
        self._inplace = self._make_inplace(mh, [sum(t.dim for t in level) for level in levels])
        if self._inplace is not None:
            # every row and side is written straight into the in-place solver's stacked buffers
            ws, head = self._inplace.ws, self._inplace.ws.head
            self._A = ws.A[head:]
            self._lo, self._hi = self._inplace.lo[head:], self._inplace.hi[head:]
            self._w = self._inplace.w
            self._HA = ws.A[nv:head]
            self._Hlo, self._Hhi = self._inplace.lo[nv:head], self._inplace.hi[nv:head]
            self._lower, self._upper = self._inplace.lo[:nv], self._inplace.hi[:nv]
        else:
            self._A = np.zeros((total, nv))
            self._lo = np.zeros(total)
            self._hi = np.zeros(total)
            self._w = np.ones(total)
            self._HA = np.zeros((mh, nv))
            self._Hlo = np.zeros(mh)
            self._Hhi = np.zeros(mh)
            self._lower = np.zeros(nv)
            self._upper = np.zeros(nv)
        self._slots: list[tuple[Task, FloatArray, FloatArray, FloatArray]] = []
        self._task_slices: list[slice] = []
        self._weight_refs: list[FloatArray | None] = []
        starts = []
        level_ranges = []
        r = 0
        for level in levels:
            r0 = r
            for t in level:
                sl = slice(r, r + t.dim)
                self._slots.append((t, self._A[sl], self._lo[sl], self._hi[sl]))
                self._task_slices.append(sl)
                self._weight_refs.append(None)
                starts.append(r)
                r += t.dim
            level_ranges.append((r0, r))
        self._tasks = tasks
        self._starts = np.asarray(starts, dtype=np.intp)
        self._level_ranges = level_ranges
        self._equality_tasks = np.array([t.equality_rows for t in tasks], dtype=bool)
        self._row_is_equality = np.zeros(total, dtype=bool)  # refreshed every tick
        # hard rows
        box_cons = [c for c in self.stack.constraints if c.has_box]
        self._row_slots: list[tuple[Constraint, FloatArray, FloatArray, FloatArray]] = []
        r = 0
        for c in row_cons:
            sl = slice(r, r + c.rows_dim)
            self._row_slots.append((c, self._HA[sl], self._Hlo[sl], self._Hhi[sl]))
            r += c.rows_dim
        self._box_cons = box_cons
        self._dynamic_box = [c for c in box_cons if not c.is_static]
        self._static_lower = np.full(nv, -np.inf)
        self._static_upper = np.full(nv, np.inf)
        for c in box_cons:
            if c.is_static:
                c.fill_box(None, self.dt, self._static_lower, self._static_upper)  # type: ignore[arg-type]
        self._lower[:] = self._static_lower
        self._upper[:] = self._static_upper
        if (self._lower > self._upper).any():
            self._raise_empty_box(None)
        self._hard_eq = np.zeros(mh, dtype=bool)
        self._hard_block = Block(self._HA, self._Hlo, self._Hhi, np.ones(mh), self._hard_eq,
                                 tuple(c.name for c in row_cons))
        self._problem = self._make_problem()
        self.level_names = tuple(level.names for level in levels)
        self._level_sizes = tuple(len(level) for level in levels)
        self._task_names = tuple(t.name for t in tasks)
        self._rate_units = tuple(t.rate_unit for t in tasks)
        self._error_units = tuple(t.error_unit for t in tasks)

    def _make_inplace(self, hard_rows: int, sizes: list[int]) -> InPlaceDaqp | None:
        """The in-place DAQP solver of the primary stage, for ``scheme="hqp"`` with ``"daqp"``.

        Uses the primary back-end's settings and tolerances (deadline limits included); None
        for every other scheme and solver (their steps take the general path). The path is
        the primary back-end's own: it is used only while that back-end is in place (a
        wrapped or replaced back-end, e.g. :func:`uvms_qp.testing.faults.inject`, is called
        through the general path).
        """
        backend = getattr(self._solver, "_backend", None)
        self._inplace_backend = backend
        if self.scheme != "hqp" or not isinstance(backend, DaqpHierarchicalBackend) or (
                not backend.lean):
            return None
        return InPlaceDaqp(self.nv, hard_rows, sizes, self.metric, backend.daqp_settings,
                           level_tol=self._solver.level_tol, hard_tol=self._solver.hard_tol,
                           rho_ladder=backend.rho_ladder, name=self.solver_name)

    def _make_problem(self) -> Problem:
        """Problem whose blocks are views of the row buffers (filled in place every tick)."""
        nv = self.nv
        blocks: list[Block] = []
        if self.scheme == "weighted":
            self._level_eq = [self._row_is_equality]
            self._w_level = np.ones(self._A.shape[0])
            blocks.append(Block(self._A, self._lo, self._hi, self._w_level, self._level_eq[0],
                                self._task_names_flat()))
        elif self.scheme == "nullspace":
            self._level_eq = []
            self._ns_index: list[np.ndarray] = []
            k = 0
            for level in self.stack.levels:
                keep: list[int] = []
                for _task in level:
                    sl = self._task_slices[k]
                    if self._equality_tasks[k]:
                        keep.extend(range(sl.start, sl.stop))
                    k += 1
                idx = np.asarray(keep, dtype=np.intp)
                self._ns_index.append(idx)
                eq = np.ones(idx.size, dtype=bool)
                self._level_eq.append(eq)
                blocks.append(Block(np.zeros((idx.size, nv)), np.zeros(idx.size),
                                    np.zeros(idx.size), np.ones(idx.size), eq, ()))
        else:
            self._level_eq = []
            for (r0, r1), level in zip(self._level_ranges, self.stack.levels, strict=True):
                eq = self._row_is_equality[r0:r1]
                self._level_eq.append(eq)
                blocks.append(Block(self._A[r0:r1], self._lo[r0:r1], self._hi[r0:r1],
                                    self._w[r0:r1], eq, level.names))
        if self.scheme == "nullspace":
            lower, upper = np.full(nv, -np.inf), np.full(nv, np.inf)
        else:
            lower, upper = self._lower, self._upper
        self._blocks = tuple(blocks)
        self._problem_box = (lower, upper)
        self._stacked = (Block(self._A, self._lo, self._hi, self._w, self._row_is_equality,
                               self._task_names_flat())
                         if self.scheme == "hqp" and len(blocks) > 1 else None)
        self._offsets = np.asarray([a for a, _ in self._level_ranges], dtype=np.intp)
        return self._new_problem()

    def _new_problem(self) -> Problem:
        """A fresh Problem over the (in-place filled) buffers.

        A new object every tick: the solver layer may cache values derived from a problem
        (stacked rows, scales), which must not survive a change of the buffers. The stacked
        rows of all levels are exactly the controller's contiguous row buffer, so that view is
        handed over instead of a copy.
        """
        lower, upper = self._problem_box
        problem = Problem(self.nv, self._blocks, self._hard_block, lower, upper, self.metric)
        if self._stacked is not None and isinstance(
                getattr(Problem, "stacked", None), cached_property):
            problem.__dict__["stacked"] = self._stacked
            if isinstance(getattr(Problem, "offsets", None), cached_property):
                problem.__dict__["offsets"] = self._offsets  # structural: rows per level
        return problem

    def _task_names_flat(self) -> tuple[str, ...]:
        return tuple(t.name for t in self._tasks)

    # -------------------------------------------------------------------------------------- API
    @property
    def tasks(self) -> tuple[Task, ...]:
        """All tasks, highest priority first."""
        return tuple(self._tasks)

    @property
    def safe(self) -> SafeSolver | None:
        """The verifying, falling-back solver (None for the closed-form nullspace scheme)."""
        return self._safe

    def reset(self) -> None:
        """Reset the run-time memory of every task and of the fallback ladder."""
        self.stack.reset()
        if self._safe is not None:
            self._safe.reset()
        if self._inplace is not None:
            self._inplace.reset()

    def level_rows(self, state: State, t: float = 0.0) -> list[Rows]:
        """Rows of every level at ``(state, t)`` (fresh copies; for inspection and tests)."""
        self._fill(state, float(t))
        return [Rows(self._A[a:b].copy(), self._lo[a:b].copy(), self._hi[a:b].copy(),
                     self._w[a:b].copy(), f"level {k}")
                for k, (a, b) in enumerate(self._level_ranges)]

    def bounds(self, state: State) -> tuple[FloatArray, FloatArray]:
        """Merged hard box ``(lower, upper)`` on zeta at ``state`` (copies)."""
        self._fill_box(state)
        return self._lower.copy(), self._upper.copy()

    # ---------------------------------------------------------------------------------- hot path
    def _fill(self, state: State, t: float) -> None:
        for task, A, lo, hi in self._slots:
            task.fill(state, t, A, lo, hi)
        if all(map(is_, map(_ROW_WEIGHTS, self._tasks), self._weight_refs)):
            return  # no weight changed since the last tick (one C-level pass)
        w = self._w
        for k, task in enumerate(self._tasks):
            rw = task.row_weights
            if rw is not self._weight_refs[k]:
                w[self._task_slices[k]] = rw
                self._weight_refs[k] = rw
                if self.scheme == "weighted":
                    self._refresh_weighted()

    def _refresh_weighted(self) -> None:
        p = len(self._level_ranges)
        for k, (a, b) in enumerate(self._level_ranges):
            self._w_level[a:b] = self._w[a:b] * self.priority_ratio ** (p - 1 - k)

    def _fill_box(self, state: State) -> None:
        lower, upper = self._lower, self._upper
        lower[:] = self._static_lower
        upper[:] = self._static_upper
        dt = self.dt
        for c in self._dynamic_box:
            c.fill_box(state, dt, lower, upper)
        if (lower > upper).any():
            self._raise_empty_box(state)

    def _raise_empty_box(self, state: State | None) -> None:
        i = int(np.flatnonzero(self._lower > self._upper)[0])
        parts = []
        for c in self._box_cons:
            if state is None and not c.is_static:
                continue
            lo, hi = c.box(state, self.dt)  # type: ignore[arg-type]
            if np.isfinite(lo[i]) or np.isfinite(hi[i]):
                parts.append(f"{c.name} gives [{lo[i]:.4g}, {hi[i]:.4g}]")
        name = self.model.zeta_names[i]
        raise BoundsError(f"hard box on zeta[{i}] ({name}) is empty: " + "; ".join(parts))

    def step(self, state: State, t: float = 0.0) -> StepResult:
        """Compute zeta for ``state`` at time ``t`` [s].

        Every command is verified and saturated into the hard box (``docs/reliability.md``):
        when the back-end fails, the fallback ladder runs and ``StepResult.stage`` names the
        stage that produced zeta.

        Raises:
            InputError: a task whose target was never set, a state of another model, or
                something other than a State (e.g. a configuration array; use ``model.state(q)``).
            NonFiniteError: a task produced NaN/inf rows (the message names the task); bad input
                never reaches a back-end.
            BoundsError: the hard box is empty (the message names the constraints involved): no
                command can satisfy it.
            NoSolutionFound: strict mode, and no back-end returned a verified solution.
        """
        start = time.perf_counter()
        try:  # a try block costs nothing on the happy path
            if state.model is not self.model:
                raise InputError("state: belongs to another model than the controller's")
        except AttributeError:
            raise not_a_state(state) from None
        self._fill(state, t)
        self._fill_box(state)
        for c, HA, Hlo, Hhi in self._row_slots:
            c.fill_rows(state, self.dt, HA, Hlo, Hhi)
        if self._inplace is not None and self._solver._backend is self._inplace_backend:
            # the happy path of scheme "hqp" with DAQP, verified in place; a NaN or inf in any
            # row or side makes it refuse the answer (its slacks are not finite), so bad rows
            # always reach the check below, which names the task
            inplace = self._inplace.solve()
            if inplace is not None:
                return self._inplace_result(inplace, t, start)
        A, lo, hi = self._A, self._lo, self._hi
        # legitimate lower sides hold finite values and -inf only, upper sides finite values and
        # +inf only: a NaN, a +inf lower side or a -inf upper side (e.g. a gain times an error
        # that overflowed) makes the sum NaN, +inf (lower) or -inf (upper); O(1) NumPy calls
        s_a, s_lo, s_hi = A.sum(), lo.sum(), hi.sum()
        if not math.isfinite(s_a) or s_lo != s_lo or s_lo == math.inf or (
                s_hi != s_hi or s_hi == -math.inf):
            self._raise_non_finite()  # returns when only the sum overflowed (finite entries)
        if self._row_slots:
            np.equal(self._Hlo, self._Hhi, out=self._hard_eq)
        np.equal(lo, hi, out=self._row_is_equality)
        problem = self._new_problem()
        if self.scheme == "nullspace":
            for block, idx in zip(problem.levels, self._ns_index, strict=True):
                np.take(A, idx, axis=0, out=block.A)
                np.take(lo, idx, out=block.lo)
                np.take(hi, idx, out=block.hi)
                np.take(self._w, idx, out=block.w)
        saturated = False
        stage, clipped, missed = PRIMARY, 0.0, False
        attempts: tuple[str, ...] = ()
        if self.scheme == "nullspace":
            t0 = time.perf_counter()
            raw = nullspace_solve(problem, NULLSPACE_RCOND, NULLSPACE_ATOL)
            zeta = np.minimum(np.maximum(raw, self._lower), self._upper)
            status, message = Status.OPTIMAL, ""
            if not np.isfinite(zeta).all():
                # finite rows whose closed-form solution overflows: never command it
                zeta, stage, status = self._zero_command(), ZERO, Status.BACKEND_ERROR
                message = "zero: the closed-form solution is not finite"
                attempts = ("primary: the closed-form solution is not finite",)
            saturated = bool(np.any(zeta != raw))
            if saturated and not message:
                message = "saturated into the hard box"
            result = evaluate(problem, zeta, "nullspace", status, message,
                              level_tol=self._solver.level_tol, hard_tol=self._solver.hard_tol,
                              solve_time=time.perf_counter() - t0)
        else:
            safe = self._safe.solve(problem, start)  # type: ignore[union-attr]
            result, zeta, stage = safe.result, safe.x, safe.stage
            clipped, missed, attempts = safe.clipped, safe.deadline_missed, safe.attempts
            saturated = safe.clip_flagged
            if not np.isfinite(zeta).all():  # pragma: no cover - the ladder verifies finiteness
                raise NonFiniteError(f"{self.solver_name}: the fallback ladder returned a "
                                     "non-finite zeta")
        y = A @ zeta
        viol = np.maximum(lo - y, 0.0)
        viol += np.maximum(y - hi, 0.0)
        viol *= viol
        sq = np.add.reduceat(viol, self._starts) if viol.size else np.zeros(0)
        hard_v = 0.0
        if self._HA.shape[0]:
            yh = self._HA @ zeta
            hard_v = float(max(np.max(self._Hlo - yh), np.max(yh - self._Hhi), 0.0))
        return StepResult(
            zeta=zeta, status=result.status, hierarchy=result, t=t,
            step_time=time.perf_counter() - start, scheme=self.scheme, solver=self.solver_name,
            lower=self._lower.copy(), upper=self._upper.copy(), saturated=saturated,
            level_names=self.level_names, stage=stage, clipped=clipped, deadline_missed=missed,
            attempts=attempts, _task_names=self._task_names,
            _rate_units=self._rate_units, _error_units=self._error_units, _residual_sq=sq,
            _errors=tuple(task.last_error for task in self._tasks), _hard_rows_violation=hard_v,
            _level_sizes=self._level_sizes)

    def _inplace_result(self, result: StackedResult, t: float, start: float) -> StepResult:
        """The step result of an answer accepted by the in-place solver.

        ``result.x`` is already inside the box and its slacks were measured at it, so the
        per-task residuals come from those slacks (no second product with the rows).
        """
        zeta = result.x
        safe = self._safe
        safe.record_primary(zeta)  # type: ignore[union-attr]
        s = result.stacked_slacks
        sq = np.add.reduceat(s * s, self._starts) if s.size else np.zeros(0)
        elapsed = time.perf_counter() - start
        deadline = safe.deadline  # type: ignore[union-attr]
        lower, upper = result.box
        return StepResult(
            zeta=zeta, status=result.status, hierarchy=result, t=t, step_time=elapsed,
            scheme=self.scheme, solver=self.solver_name, lower=lower, upper=upper,
            saturated=False, level_names=self.level_names,
            stage=PRIMARY, clipped=self._inplace.clipped,  # type: ignore[union-attr]
            deadline_missed=deadline is not None and elapsed > deadline,
            _task_names=self._task_names, _rate_units=self._rate_units,
            _error_units=self._error_units, _residual_sq=sq,
            _errors=tuple(task.last_error for task in self._tasks),
            _hard_rows_violation=result.hard_violation, _level_sizes=self._level_sizes)

    def _zero_command(self) -> FloatArray:
        """The zero command saturated into this tick's hard box (finite: the box is not empty)."""
        return np.minimum(np.maximum(np.zeros(self.nv), self._lower), self._upper)

    def _raise_non_finite(self) -> None:
        """Raise NonFiniteError naming the first task with a non-finite entry.

        Non-finite: NaN or inf in its rows ``A``, NaN or ``+inf`` in a lower side, NaN or
        ``-inf`` in an upper side. Returns normally when every entry is legitimate (the sums
        that triggered the check overflowed on large finite values).
        """
        A, lo, hi = self._A, self._lo, self._hi
        for task, sl in zip(self._tasks, self._task_slices, strict=True):
            if not np.isfinite(A[sl]).all():
                raise NonFiniteError(f"task {task.name!r} produced non-finite rows")
            if np.isnan(lo[sl]).any() or np.isposinf(lo[sl]).any() or np.isnan(hi[sl]).any() or (
                    np.isneginf(hi[sl]).any()):
                raise NonFiniteError(
                    f"task {task.name!r} produced a non-finite target side (NaN, a +inf lower "
                    "or a -inf upper side; e.g. a gain times an error that overflowed)")

    def __repr__(self) -> str:
        return (f"Controller({self.model.name!r}, {len(self.stack.levels)} levels, "
                f"scheme={self.scheme!r}, solver={self.solver_name!r}, dt={self.dt:g})")
