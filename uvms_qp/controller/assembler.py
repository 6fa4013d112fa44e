"""The stack assembler: a bound stack written straight into one problem's buffers every tick."""

from __future__ import annotations

from functools import partial
from operator import attrgetter, is_
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from ..errors import BoundsError, InputError, NonFiniteError
from ..hqp import Problem, Status
from ..hqp.damping import DEFAULT_THRESHOLD, Damping
from ..hqp.measure import measure
from ..hqp.validate import finite_ok
from ..rows import Rows
from ..safety import SafeSolve
from ..stack import Stack
from ..tasks import Task, TaskSlot
from .history import CommandHistory, box_bounds
from .result import Reversals, StepResult, TaskErrors, TaskLayout, TaskResiduals

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_ROW_WEIGHTS = attrgetter("row_weights")
_LAST_ERROR = attrgetter("error")  # as set: made an array by the lazy report
_ACTIVATION = attrgetter("activation")


class _Slacks:
    """The slacks of the stack's own problem at a command measured on another problem."""

    __slots__ = ("slacks",)

    def __init__(self, slacks: FloatArray) -> None:
        self.slacks = slacks


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


class StackAssembler:
    """Binds a stack to a model and fills one :class:`~uvms_qp.hqp.Problem` with it every tick.

    Each task writes its rows straight into its slice of ``problem.A`` / ``lo`` / ``hi``; box
    constraints intersect their box into the first n rows (static boxes merged once); row
    constraints write the hard rows. Row weights are re-read only when a task hands out a new
    ``row_weights`` array (after every ``update``: the task is then checked against the period
    again). Nothing is allocated per tick.

    The assembler owns the run-time memory of the stack in this controller: one
    :class:`~uvms_qp.tasks.TaskSlot` per task (activation and its ramp, held targets, the last
    error; :meth:`slot`) and one memory per constraint that keeps one (the previous command of
    a command-rate bound). The stack itself stays a description that other controllers may
    share.

    Args:
        model: The UVMS model.
        stack: Levels of tasks and hard constraints (bound to ``model`` here).
        dt: Control period [s] (turns position limits into rate bounds).
        metric: Diagonal W (nv,) of the final regularisation (validated).
        damping: Damping threshold of the levels that set none (``Level(damping=...)``), >= 0
            (0: no damping; :mod:`uvms_qp.hqp.damping`).

    Attributes:
        problem: The problem the stack is written into.
        tasks: All tasks, highest priority first.
        slots: The run-time memory of each task in this controller (same order).
        layout: Where each task's rows sit (for the per-task reports).
        level_names: Task names of each level.
        weights_version: Incremented whenever a row weight changed.
        damping: Damping threshold of each level (None when every one is 0).
        no_rows: ``(None,) * levels``: no rows to add to any level.
        history: The commands of the last second (:class:`CommandHistory`).

    Raises:
        InputError: any binding error of the stack, with its location; a task whose rows would
            not settle at this period (:meth:`Stack.check_period`).
        BoundsError: the static boxes of the constraints do not intersect.
    """

    def __init__(self, model: Model, stack: Stack, dt: float, metric: FloatArray,
                 damping: float = DEFAULT_THRESHOLD) -> None:
        self.model = model
        self.stack = stack.bind(model)
        self.stack.check_period(dt)
        self.dt = dt
        nv = int(model.nv)
        self.nv = nv
        levels = self.stack.levels
        self.tasks: tuple[Task, ...] = tuple(t for level in levels for t in level)
        self.slots: tuple[TaskSlot, ...] = tuple(task.new_slot() for task in self.tasks)
        self._by_name = dict(zip((t.name for t in self.tasks), self.slots, strict=True))
        peers = dict(zip(self.tasks, self.slots, strict=True))
        self._entries = tuple(stack.entries[t.name] for t in self.tasks)
        for slot, entry in zip(self.slots, self._entries, strict=True):
            slot.peers = peers
            slot.activation, slot.seen = entry.activation, entry.serial
        self._requests = stack.requests
        self._ramping: list[int] = []  # tasks whose activation ramps
        self._weight_sources = tuple(slot if task.weights_per_tick else task
                                     for task, slot in zip(self.tasks, self.slots, strict=True))
        row_cons = [c for c in self.stack.constraints if c.rows_dim > 0]
        mh = sum(c.rows_dim for c in row_cons)
        self.problem = problem = Problem(nv, mh, [sum(t.dim for t in lv) for lv in levels], metric)
        A, lo, hi, sides = problem.A, problem.lo, problem.hi, problem.sides
        spans, r = [], problem.head
        for task in self.tasks:
            spans.append((r, r + task.dim))
            r += task.dim
        self._slots = [(task, A[a:b], sides[:, a:b], slot) for task, (a, b), slot in zip(
            self.tasks, spans, self.slots, strict=True)]
        self._row_slots = []
        r = nv
        for c in row_cons:
            self._row_slots.append((c, A[r:r + c.rows_dim], lo[r:r + c.rows_dim],
                                    hi[r:r + c.rows_dim]))
            r += c.rows_dim
        self._box_cons = [c for c in self.stack.constraints if c.has_box]
        memory = {c: c.memory() for c in self.stack.constraints}
        self._memories = [(c, m) for c, m in memory.items() if m is not None]
        # a box that yields (command-rate bounds) is filled last, clipped into the others
        self._dynamic_box = [
            c.fill_box if memory[c] is None
            else partial(c.fill_box, memory=memory[c])  # type: ignore[call-arg]
            for c in sorted((c for c in self._box_cons if not c.is_static),
                            key=lambda c: c.yields)]
        self._box = problem.sides[:, :nv]
        self._lower, self._upper = self._box  # views
        self._static_box = np.empty((2, nv))
        self._static_box[0], self._static_box[1] = -np.inf, np.inf
        for c in self._box_cons:
            if c.is_static:
                c.fill_box(None, dt, self._static_box[0], self._static_box[1])  # type: ignore[arg-type]
        self._box[...] = self._static_box
        if (self._static_box[0] > self._static_box[1]).any():
            self._raise_empty_box(None)
        self._weight_refs: list[FloatArray | None] = [None] * len(self.tasks)
        self.weights_version = 0
        head = problem.head
        self._weight_rows = [slice(a - head, b - head) for a, b in spans]
        self.level_names = tuple(level.names for level in levels)
        self._task_level = tuple(k for k, level in enumerate(levels) for _ in level)
        self._derived: dict[tuple[Any, ...], tuple[Problem, Any, Any, Any]] = {}
        thresholds = tuple(damping if level.damping is None else level.damping
                           for level in levels)
        self.damping = thresholds if any(thresholds) else None
        self.no_rows: tuple[None, ...] = (None,) * len(levels)
        self.history = CommandHistory(nv, dt, box_bounds(*self._static_box))
        self.layout = TaskLayout(tuple(t.name for t in self.tasks), tuple(spans),
                                 tuple(t.rate_unit for t in self.tasks),
                                 tuple(t.error_unit for t in self.tasks))

    # ---------------------------------------------------------------------------- per tick
    def fill(self, state: State, t: float) -> Problem:
        """Write the rows, weights, box and hard rows at ``(state, t)`` into :attr:`problem`.

        Raises:
            InputError: ``state`` is not a State of this model (e.g. a configuration array), or
                a task updated since the last tick whose rows would not settle at this period.
            NonFiniteError: a task or constraint produced NaN/inf rows (the message names it).
        """
        try:  # a try block costs nothing on the happy path
            if state.model is not self.model:
                raise InputError("state: belongs to another model than the controller's")
        except AttributeError:
            raise not_a_state(state) from None
        if self.stack.requests != self._requests:
            self._follow_requests()
        if self._ramping:
            self._advance(t)
        for task, A, sides, slot in self._slots:
            task.fill(state, t, A, sides, slot)
        if not all(map(is_, map(_ROW_WEIGHTS, self._weight_sources), self._weight_refs)):
            self._refresh_weights()
        self._box[...] = self._static_box
        if self._dynamic_box:
            lower, upper, dt = self._lower, self._upper, self.dt
            for fill_box in self._dynamic_box:
                fill_box(state, dt, lower, upper)
        for c, HA, Hlo, Hhi in self._row_slots:
            c.fill_rows(state, self.dt, HA, Hlo, Hhi)
        problem = self.problem
        if not finite_ok(problem):
            self._diagnose(state)
        return problem

    def _follow_requests(self) -> None:
        """Start a ramp toward each activation the stack was asked for since the last tick."""
        self._requests = self.stack.requests
        for i, (slot, entry) in enumerate(zip(self.slots, self._entries, strict=True)):
            if slot.seen != entry.serial:
                slot.seen = entry.serial
                slot.ramp = (slot.activation, entry.activation, -1.0)  # starts at this tick
                if i not in self._ramping:
                    self._ramping.append(i)

    def _advance(self, t: float) -> None:
        """Move the ramping activations to time ``t`` [s] (a pending ramp starts now).

        ``a(t) = a_0 + (a_1 - a_0) (3 s^2 - 2 s^3)``, ``s = (t - t_0) / (ramp |a_1 - a_0|)``
        clipped to [0, 1]. A ramp up from 0 first clears the task's slot: a task entering the
        stack takes its held target then, not at the start of the run.
        """
        for i in tuple(self._ramping):
            slot = self.slots[i]
            a0, a1, start = slot.ramp  # type: ignore[misc]
            if start < 0.0:
                start = t
                slot.ramp = (a0, a1, t)
                if a0 == 0.0:
                    slot.clear()
            span = self._entries[i].ramp * abs(a1 - a0)
            s = 1.0 if span <= 0.0 else min(max((t - start) / span, 0.0), 1.0)
            slot.activation = a0 + (a1 - a0) * s * s * (3.0 - 2.0 * s)
            if s >= 1.0:
                slot.activation = a1
                slot.ramp = None
                self._ramping.remove(i)

    def slot(self, name: str) -> TaskSlot:
        """The run-time memory of task ``name`` in this controller (:class:`~.TaskSlot`).

        Its last error, its activation, a held target: what reports read of a task.

        Raises:
            InputError: an unknown task (the known ones are listed).
        """
        slot = self._by_name.get(name)
        if slot is None:
            self.stack.task(name)  # raises, listing the known tasks
        return slot  # type: ignore[return-value]

    def activation(self) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """``(out, ramping)``: indices of the tasks at activation 0 and strictly between 0 and 1.

        Read after :meth:`fill` (which advances the tasks' ramps to this tick).
        """
        values = list(map(_ACTIVATION, self.slots))
        if min(values) == 1.0:
            return (), ()
        return (tuple(i for i, a in enumerate(values) if a == 0.0),
                tuple(i for i, a in enumerate(values) if 0.0 < a < 1.0))

    def reset(self) -> None:
        """Forget this controller's run-time memory of the stack, and the command history.

        Every slot is cleared and takes the activation the stack requests now (no ramp); every
        constraint memory returns to its initial value.
        """
        for slot, entry in zip(self.slots, self._entries, strict=True):
            slot.clear()
            slot.activation, slot.ramp, slot.seen = entry.activation, None, entry.serial
        self._ramping.clear()
        self._requests = self.stack.requests
        for c, memory in self._memories:
            c.reset(memory)
        self.history.reset()

    def derived(self, excluded: tuple[int, ...], extra: tuple[FloatArray | None, ...]
                ) -> Problem:
        """This tick's problem without the rows of some tasks and with rows added to levels.

        Args:
            excluded: Indices (into :attr:`tasks`) of the tasks whose rows are left out (tasks
                out of the stack, activation 0).
            extra: Per level, rows ``D`` (r, n) appended with target 0 and weight 1 (damping
                rows), or None.

        Returns:
            A problem with the same box, hard rows and levels, filled from :attr:`problem`
            (buffers kept per shape, so a back-end keeps its set-up for it).
        """
        base = self.problem
        key = (excluded, tuple(0 if d is None else d.shape[0] for d in extra))
        entry = self._derived.get(key)
        if entry is None:
            entry = self._derived[key] = self._derived_layout(*key)
        problem, source, target, blocks = entry
        problem.A[target] = base.A[source]
        problem.sides[:, target] = base.sides[:, source]
        head = base.head
        w = problem.w
        w.fill(1.0)
        w[target[head:] - head] = base.w[source[head:] - head]
        for start, D in zip(blocks, extra, strict=True):
            if D is not None:
                r = D.shape[0]
                problem.A[start:start + r] = D
                problem.sides[:, start:start + r] = 0.0
        problem.set_weights(w)
        return problem

    def _derived_layout(self, excluded: tuple[int, ...], counts: tuple[int, ...]
                        ) -> tuple[Problem, Any, Any, tuple[int, ...]]:
        """The buffers of :meth:`derived` for one shape: problem, row maps, extra-row starts."""
        base = self.problem
        head = base.head
        source, target = list(range(head)), list(range(head))
        sizes, blocks = [], []
        out = head
        for k in range(len(base.sizes)):
            kept = [i for j, (a, b) in enumerate(self.layout.spans)
                    if self._task_level[j] == k and j not in excluded for i in range(a, b)]
            source.extend(kept)
            target.extend(range(out, out + len(kept)))
            out += len(kept)
            blocks.append(out)
            out += counts[k]
            sizes.append(len(kept) + counts[k])
        problem = Problem(base.n, base.mh, sizes, base.W)
        return problem, np.asarray(source), np.asarray(target), tuple(blocks)

    def check_box(self, state: State) -> None:
        """Raise BoundsError naming the constraints when this tick's box is empty.

        Asked after a step whose hard set was found empty (an empty box is no bad number: the
        back-ends see it and report it, and this names the culprits).
        """
        lower, upper = self._box
        if (lower > upper).any():
            self._raise_empty_box(state)

    def _refresh_weights(self) -> None:
        """Take the new row weights, checking an updated task against the control period.

        A task hands out new weights after every update (:meth:`~.Task.check_period`).
        """
        problem = self.problem
        for k, source in enumerate(self._weight_sources):
            rw = source.row_weights
            if rw is not self._weight_refs[k]:
                task = self.tasks[k]
                if source is task:
                    try:
                        task.check_period(self.dt)
                    except InputError as exc:
                        exc.args = (f"task {task.name!r} updated: {exc}", *exc.args[1:])
                        raise
                problem.set_weights(rw, self._weight_rows[k])
                self._weight_refs[k] = rw
        self.weights_version += 1

    def step_result(self, out: SafeSolve, t: float, step_time: float, scheme: str,
                    solver: str, status: Status | None = None, solved: Problem | None = None,
                    damping: Damping | None = None, excluded: tuple[int, ...] = (),
                    ramping: tuple[int, ...] = ()) -> StepResult:
        """The step result of a ladder outcome (reports read lazily from its slacks).

        Hands the command to the constraints (:meth:`Constraint.command_sent`) and to the
        history. ``solved`` is the problem the answer was measured on when it is not this
        stack's own (tasks left out, damping rows): the task reports are then measured on the
        stack's problem.
        """
        x = out.x
        for c, memory in self._memories:
            c.command_sent(x, memory)
        ring, count = self.history.record(x)
        result = out.result
        box = result.box
        source: Any = result
        if solved is not None and solved is not self.problem:
            source = _Slacks(measure(self.problem, x)[0])
        tasks, slots = self.tasks, self.slots
        return StepResult(
            x, result.status if status is None else status, result, t, step_time, scheme,
            solver, box[0], box[1], out.clip_flagged, self.level_names, out.stage, out.clipped,
            out.deadline_missed, out.attempts, TaskResiduals(self.layout, source),
            TaskErrors(self.layout, tuple(map(_LAST_ERROR, slots))),
            damping=damping,
            inactive=tuple(tasks[i].name for i in excluded) if excluded else (),
            ramping={tasks[i].name: slots[i].activation for i in ramping} if ramping else None,
            reversals=Reversals(self.history, ring.copy(), count, self.model.zeta_names))

    # ------------------------------------------------------------------------- inspection
    def level_rows(self, state: State, t: float = 0.0) -> list[Rows]:
        """Rows of every level at ``(state, t)`` (fresh copies)."""
        problem = self.fill(state, float(t))
        out = []
        for k in range(len(problem.sizes)):
            rows = problem.level(k)
            out.append(Rows(rows.A.copy(), rows.lower.copy(), rows.upper.copy(),
                            None if rows.weights is None else rows.weights.copy(), f"level {k}"))
        return out

    def bounds(self, state: State) -> tuple[FloatArray, FloatArray]:
        """Merged hard box ``(lower, upper)`` on zeta at ``state`` (copies)."""
        self._box[...] = self._static_box
        lower, upper = self._box
        for fill_box in self._dynamic_box:
            fill_box(state, self.dt, lower, upper)
        if (lower > upper).any():
            self._raise_empty_box(state)
        return lower.copy(), upper.copy()

    # ---------------------------------------------------------------------------- errors
    def _diagnose(self, state: State) -> None:
        """Raise the error naming the task or constraint whose output is bad.

        Returns normally when every entry is legitimate (the reductions of
        :func:`~uvms_qp.hqp.validate.finite_ok` overflowed on large finite values).
        """
        named: list[tuple[str, FloatArray, FloatArray, FloatArray]] = [
            *[(f"task {task.name!r}", A, lo, hi) for task, A, (lo, hi), _ in self._slots],
            *[(f"constraint {c.name!r}", A, lo, hi) for c, A, lo, hi in self._row_slots]]
        for who, A, lo, hi in named:
            if not np.isfinite(A).all():
                raise NonFiniteError(f"{who} produced non-finite rows")
            if np.isnan(lo).any() or np.isposinf(lo).any() or np.isnan(hi).any() or (
                    np.isneginf(hi).any()):
                raise NonFiniteError(
                    f"{who} produced a non-finite target side (NaN, a +inf lower or a -inf upper "
                    "side; e.g. a gain times an error that overflowed)")
            if (lo > hi).any():
                i = int(np.flatnonzero(lo > hi)[0])
                raise BoundsError(f"{who} produced row {i} with lower side {lo[i]:.6g} > upper "
                                  f"side {hi[i]:.6g}")

    def _raise_empty_box(self, state: State | None) -> None:
        lower, upper = self._box if state is not None else self._static_box
        i = int(np.flatnonzero(lower > upper)[0])
        parts = []
        for c in self._box_cons:
            if state is None and not c.is_static:
                continue
            lo, hi = c.box(state, self.dt)  # type: ignore[arg-type]
            if np.isfinite(lo[i]) or np.isfinite(hi[i]):
                parts.append(f"{c.name} gives [{lo[i]:.4g}, {hi[i]:.4g}]")
        name = self.model.zeta_names[i]
        raise BoundsError(f"hard box on zeta[{i}] ({name}) is empty: " + "; ".join(parts))
