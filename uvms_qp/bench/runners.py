"""Solvers and schemes under benchmark, each able to run every kind of problem it applies to.

A :class:`Runner` turns one :class:`~uvms_qp.bench.sets.BenchProblem` into one
:class:`~uvms_qp.bench.record.Record`. Runners:

* ``daqp``, ``cascade:<name>`` (every installed qpsolvers back-end): the lexicographic QP
  (:class:`~uvms_qp.controller.Controller` on UVMS problems, :class:`~uvms_qp.hqp.HierarchySolver`
  on raw ones);
* ``nullspace``: the closed-form recursive null-space scheme
  (Soylu et al. (2007), Eq. (10)), on problems whose levels are all equalities, its answer
  saturated into the hard box as the controller's ``scheme="nullspace"`` does (a closed form cannot
  enforce the box: a clipped answer is ``unproven`` unless the certificate proves it);
* ``weighted``: the same stack as ONE weighted QP (level ``k`` of ``p`` weighted by
  ``1e4 ** (p - 1 - k)``), solved by ``cascade:daqp`` (a plain QP: as soft weights of one DAQP
  level, the priority weights would span more orders than its soft-row regularisation resolves);
* ``scheme:<name>``: the papers' closed-form schemes (:data:`uvms_qp.schemes.SCHEME_TYPES`) on the
  scenarios that name them;
* ``pink``: Pink differential IK (optional) on the problems it can express
  (:mod:`uvms_qp.bench.pink_adapter`): the one-level random problems as they are; on a scenario,
  its own smaller problem (the tracked frame and a posture cost, one weighted level), so its
  scenario rows carry the note :data:`~uvms_qp.bench.record.OWN_PROBLEM`.

Timing: a UVMS trial is a full control step, state update included (``model.state(q)`` then
``step``; Pink: ``Configuration`` then ``solve_ik``); a raw trial is one
``HierarchySolver.solve`` call (validation included). Set-up and one warm-up call are not timed:
on a random or raw problem an extra first call, in a closed-loop scenario the first control step
(verified and counted as a trial like every step, its time kept in ``info["first_step_us"]``).

Verification (whatever the back-end claims): a trial succeeds when the answer is finite, the
status is one of :data:`OK_STATUSES`, and every hard row (box and inequalities,
recomputed from the constraints) holds to :data:`~uvms_qp.bench.record.HARD_TOL`. Any exception
is caught, counted as a failure of every trial it prevented, and attributed by its type.

:data:`EXTRA_RUNNERS` is a registry hook: name -> factory of additional runners (used by tests to
inject a failing back-end).
"""

from __future__ import annotations

import contextlib
import fnmatch
import math
import os
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..controller import Controller
from ..errors import InputError
from ..hqp import HierarchySolver, available_solvers, hard_violation
from ..rows import Rows
from ..schemes import SCHEME_TYPES, build_scheme
from ..sim.runner import simulate
from ..sim.scenario import load_scenario
from .pink_adapter import PinkController, pink_available, pink_supported, position_gain, rate_box
from .record import HARD_TOL, OWN_PROBLEM, SATURATED, Record
from .sets import BenchProblem

#: Weight ratio between consecutive levels of the ``weighted`` runner.
PRIORITY_RATIO = 1e4
#: Back-end of the ``weighted`` runner (one plain QP).
WEIGHTED_BACKEND = "cascade:daqp"

#: Statuses of a verified answer: the lexicographic optimum, or the controller's damped or blended
#: one (the optimum of the stack with damping rows near a singularity; tasks ramping).
OK_STATUSES = ("optimal", "damped", "blended")


# ------------------------------------------------------------------------------- verification


def constraint_violation(constraints: Any, state: Any, dt: float, zeta: FloatArray) -> float:
    """Largest violation of the hard box and hard rows of ``constraints`` at ``zeta``.

    Recomputed from the constraint objects (independent of the controller's buffers) with
    :func:`uvms_qp.hqp.hard_violation`; the box of several constraints is their intersection.
    """
    n = zeta.size
    lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    rows = []
    for c in constraints:
        if getattr(c, "has_box", False):
            lo, hi = c.box(state, dt)
            np.maximum(lower, lo, out=lower)
            np.minimum(upper, hi, out=upper)
        if getattr(c, "rows_dim", 0):
            rows.append(c.rows(state, dt))
    if not rows:
        return hard_violation(zeta, lower, upper)
    return hard_violation(zeta, lower, upper, np.vstack([r.A for r in rows]),
                          np.concatenate([r.lower for r in rows]),
                          np.concatenate([r.upper for r in rows]))


def level_norms(rows: list[Any], zeta: FloatArray) -> list[float]:
    """Weighted violation norm ``sqrt(sum_i w_i s_i^2)`` of every level's rows at ``zeta``."""
    out = []
    for r in rows:
        s = r.violation(zeta)
        w = np.ones(r.m) if r.weights is None else r.weights
        out.append(float(np.sqrt(w @ (s * s))))
    return out


def _judge(record: Record, x: FloatArray, status: str, violation: float,
           message: str = "") -> bool:
    """Count one trial into ``record``; returns True on a verified success."""
    record.trials += 1
    finite = bool(np.all(np.isfinite(x)))
    if not finite:
        record.nan_count += 1
        record.fail("nan")
        return False
    record.hard_violation = max(record.hard_violation, violation)
    if status in OK_STATUSES:
        record.claimed_violation = max(record.claimed_violation, violation)
        if violation > HARD_TOL:
            record.fail("hard_violation")
            return False
        record.successes += 1
        return True
    record.fail(str(status))
    if message and not record.note:
        record.note = message[:200]
    return False


@contextlib.contextmanager
def quiet_stdout() -> Iterator[None]:
    """Silence the C-level standard output (back-end banners) for the duration of a run."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # captured or replaced stdout
        yield
        return
    sys.stdout.flush()
    saved = os.dup(fd)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), fd)
            yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, fd)
        os.close(saved)


# ------------------------------------------------------------------------------------ runners


class Runner:
    """Base class: dispatch on the problem kind, catch and attribute every exception.

    Subclasses implement ``_uvms``/``_raw``/``_scenario_controller`` for the kinds they support
    and :meth:`applies` for finer rules.
    """

    name = "runner"
    kinds: tuple[str, ...] = ("scenario", "uvms", "raw")

    def applies(self, problem: BenchProblem) -> str | None:
        """None when the runner applies to ``problem``, else the reason it does not."""
        if problem.kind not in self.kinds:
            return f"{self.name} does not run {problem.kind} problems"
        return None

    def run(self, problem: BenchProblem, repetitions: int) -> Record:
        """Run ``problem``; returns its record (never raises for a solver failure)."""
        record = Record(problem.set, problem.name, self.name, info=dict(problem.info))
        reason = self.applies(problem)
        if reason is not None:
            record.note = f"n/a: {reason}"
            return record
        planned = repetitions if problem.kind != "scenario" else int(problem.max_steps or 0)
        try:
            if problem.kind == "scenario":
                self._run_scenario(problem, record)
            elif problem.kind == "uvms":
                self._run_uvms(problem, record, repetitions)
            else:
                self._run_raw(problem, record, repetitions)
        except Exception as exc:  # attributed, never dropped
            missing = max(planned - record.trials, 1)
            record.trials += missing
            record.fail(f"exception:{type(exc).__name__}", missing)
            record.note = f"{type(exc).__name__}: {exc}"[:300]
        return record

    # -- scenarios -------------------------------------------------------------------------
    def _scenario_controller(self, scenario: Any, stack: Any) -> Any:
        raise NotImplementedError

    def _run_scenario(self, problem: BenchProblem, record: Record) -> None:
        scenario = load_scenario(str(problem.scenario))
        stack = scenario.build_stack()
        controller = self._scenario_controller(scenario, stack)
        timed = _TimedStep(controller, scenario.model)
        steps = min(scenario.steps, int(problem.max_steps or scenario.steps))
        result = simulate(scenario, timed, stack=stack, scheme_name=self.name,
                          duration=steps * scenario.dt)
        record.info.update({"model": scenario.model.name, "steps": result.steps,
                            "dt": scenario.dt})
        if timed.times:  # the first step is the warm-up: verified below, not timed
            record.info["first_step_us"] = timed.times[0] * 1e6
        record.times_us = [t * 1e6 for t in timed.times[1:]]
        if len(timed.backend) > 1:
            record.backend_us = float(np.median(timed.backend[1:]))
        record.trials = result.steps
        record.nan_count = int(result.nan_steps)
        record.fail("nan", result.nan_steps)
        viol = np.asarray(result.bound_violation, dtype=float)
        record.hard_violation = float(viol.max(initial=0.0))
        ok = np.array([s in OK_STATUSES for s in result.status], dtype=bool)
        if ok.any():
            record.claimed_violation = float(viol[ok].max())
        good = ok & (viol <= HARD_TOL)
        for s in sorted(set(result.status) - set(OK_STATUSES)):
            record.fail(s, sum(1 for x in result.status if x == s))
        record.fail("hard_violation", int((ok & (viol > HARD_TOL)).sum()))
        record.successes = max(0, int(good.sum()) - result.nan_steps)
        extra = record.successes + record.failed - record.trials
        if extra > 0:  # a NaN step is also counted by its status: keep trials consistent
            record.failures["nan"] -= extra

    # -- UVMS control steps ----------------------------------------------------------------
    def _uvms_controller(self, draw: Any) -> Any:
        raise NotImplementedError

    def _run_uvms(self, problem: BenchProblem, record: Record, repetitions: int) -> None:
        assert problem.build is not None
        draw = problem.build()
        reference = _reference_rows(problem)
        controller = self._uvms_controller(draw)
        model, q = draw.model, draw.q
        controller.step(model.state(q), 0.0)  # warm-up (workspace, activation poses)
        result = None
        backend: list[float] = []
        for _ in range(repetitions):
            start = time.perf_counter()
            state = model.state(q)
            result = controller.step(state, 0.0)
            record.times_us.append((time.perf_counter() - start) * 1e6)
            _backend_time(result, backend)
            zeta = np.asarray(result.zeta, dtype=float)
            violation = (constraint_violation(draw.stack.constraints, state, draw.dt, zeta)
                         if np.all(np.isfinite(zeta)) else math.inf)
            _judge(record, zeta, str(result.status), violation,
                   getattr(getattr(result, "hierarchy", None), "message", "") or
                   getattr(result, "message", ""))
        if backend:
            record.backend_us = float(np.median(backend))
        if getattr(result, "saturated", False):
            _mark_saturated(record)
        if result is not None and np.all(np.isfinite(result.zeta)):
            record.levels = level_norms(reference, np.asarray(result.zeta, dtype=float))

    # -- raw lexicographic problems --------------------------------------------------------
    def _raw_solver(self, problem: BenchProblem) -> Any:
        raise NotImplementedError

    def _raw_inputs(self, problem: BenchProblem) -> tuple[list[Any], Any, Any]:
        return problem.levels or [], problem.lower, problem.upper

    def _run_raw(self, problem: BenchProblem, record: Record, repetitions: int) -> None:
        solver = self._raw_solver(problem)
        levels, lower, upper = self._raw_inputs(problem)
        solver.solve(levels, lower, upper)  # warm-up
        backend = []
        result = None
        for _ in range(repetitions):
            start = time.perf_counter()
            result = solver.solve(levels, lower, upper)
            record.times_us.append((time.perf_counter() - start) * 1e6)
            x = np.asarray(result.x, dtype=float)
            violation = (_box_violation(problem, x) if np.all(np.isfinite(x)) else math.inf)
            _judge(record, x, str(result.status), violation, result.message)
            c_time = result.info.get("daqp_solve_time") if result.info else None
            if isinstance(c_time, float):
                backend.append(c_time * 1e6)
        if backend:
            record.backend_us = float(np.median(backend))
        if result is not None and (result.info or {}).get("clipped"):
            _mark_saturated(record)
        if result is not None and np.all(np.isfinite(result.x)):
            record.levels = level_norms(_raw_reference_rows(problem), np.asarray(result.x))


def _mark_saturated(record: Record) -> None:
    """Note that the row's answer was clipped into the box (keeping the status message)."""
    if not record.note.startswith(SATURATED):
        record.note = f"{SATURATED}; {record.note}" if record.note else SATURATED


class _TimedStep:
    """Wrap a controller: each step rebuilds the state from ``q`` and times state + step."""

    def __init__(self, controller: Any, model: Any) -> None:
        self.controller = controller
        self.model = model
        self.solver_name = getattr(controller, "solver_name", None)
        self.times: list[float] = []
        self.backend: list[float] = []

    def reset(self) -> None:
        reset = getattr(self.controller, "reset", None)
        if callable(reset):
            reset()
        self.times = []
        self.backend = []

    def step(self, state: Any, t: float) -> Any:
        start = time.perf_counter()
        result = self.controller.step(self.model.state(state.q), t)
        self.times.append(time.perf_counter() - start)
        _backend_time(result, self.backend)
        return result


def _backend_time(result: Any, out: list[float]) -> None:
    """Append the back-end's own solve time [us] of a step result, when it reports one."""
    info = getattr(getattr(result, "hierarchy", None), "info", None)
    value = info.get("daqp_solve_time") if info else None
    if isinstance(value, float):
        out.append(value * 1e6)


def _box_violation(problem: BenchProblem, x: FloatArray) -> float:
    lo = problem.lower if problem.lower is not None else np.full(x.size, -np.inf)
    hi = problem.upper if problem.upper is not None else np.full(x.size, np.inf)
    return hard_violation(x, lo, hi)


def _raw_reference_rows(problem: BenchProblem) -> list[Any]:
    out = []
    for level in problem.levels or []:
        A = np.vstack([t[0] for t in level])
        lo = np.concatenate([t[1] for t in level])
        hi = np.concatenate([t[2] for t in level])
        out.append(Rows(A, lo, hi))
    return out


def _reference_rows(problem: BenchProblem) -> list[Any]:
    """Rows of every level of a UVMS problem, from an independent build of its stack."""
    assert problem.build is not None
    draw = problem.build()
    ref = Controller(draw.model, draw.stack, solver="daqp", dt=draw.dt, deadline=None)
    return ref.level_rows(draw.model.state(draw.q), 0.0)


def _all_equality_rows(rows: list[Any]) -> bool:
    return all(bool(np.array_equal(r.lower, r.upper)) for r in rows)


class HqpRunner(Runner):
    """The lexicographic QP with back-end ``solver`` (``"daqp"`` or ``"cascade:<name>"``)."""

    def __init__(self, solver: str) -> None:
        self.name = solver
        self.solver = solver

    def _scenario_controller(self, scenario: Any, stack: Any) -> Any:
        return scenario.make_controller(self.solver, stack=stack)

    def _uvms_controller(self, draw: Any) -> Any:
        return Controller(draw.model, draw.stack, solver=self.solver, dt=draw.dt, deadline=None)

    def _raw_solver(self, problem: BenchProblem) -> Any:
        return HierarchySolver(self.solver)


class NullspaceRunner(Runner):
    """The closed-form recursive null-space scheme, on equality-only problems."""

    name = "nullspace"

    def applies(self, problem: BenchProblem) -> str | None:
        """See :meth:`Runner.applies`."""
        reason = super().applies(problem)
        if reason is not None:
            return reason
        if problem.kind == "raw":
            return None if problem.all_equality else "inequality levels"
        if problem.kind == "uvms":
            return None if _all_equality_rows(_reference_rows(problem)) else "inequality tasks"
        scenario = load_scenario(str(problem.scenario))
        ctl = scenario.make_controller()
        rows = ctl.level_rows(scenario.model.state(scenario.q0), 0.0)
        return None if _all_equality_rows(rows) else "inequality tasks"

    def _scenario_controller(self, scenario: Any, stack: Any) -> Any:
        return Controller(scenario.model, stack, dt=scenario.dt, deadline=None,
                          metric=scenario.metric, scheme="nullspace")

    def _uvms_controller(self, draw: Any) -> Any:
        return Controller(draw.model, draw.stack, dt=draw.dt, deadline=None, scheme="nullspace")

    def _raw_solver(self, problem: BenchProblem) -> Any:
        solver = HierarchySolver("nullspace")
        solver.saturate = True  # as the controller's scheme: the command is the clipped answer
        return solver


class WeightedRunner(Runner):
    """One weighted QP on the same stack (soft priorities), same hard bounds."""

    name = "weighted"

    def _scenario_controller(self, scenario: Any, stack: Any) -> Any:
        return Controller(scenario.model, stack, solver=WEIGHTED_BACKEND,
                          dt=scenario.dt, deadline=None, metric=scenario.metric,
                          scheme="weighted", priority_ratio=PRIORITY_RATIO)

    def _uvms_controller(self, draw: Any) -> Any:
        return Controller(draw.model, draw.stack, solver=WEIGHTED_BACKEND, dt=draw.dt,
                          deadline=None, scheme="weighted", priority_ratio=PRIORITY_RATIO)

    def _raw_solver(self, problem: BenchProblem) -> Any:
        return HierarchySolver(WEIGHTED_BACKEND)

    def _raw_inputs(self, problem: BenchProblem) -> tuple[list[Any], Any, Any]:
        rows = _raw_reference_rows(problem)
        p = len(rows)
        merged = Rows(np.vstack([r.A for r in rows]),
                      np.concatenate([r.lower for r in rows]),
                      np.concatenate([r.upper for r in rows]),
                      np.concatenate([np.full(r.m, PRIORITY_RATIO ** (p - 1 - k))
                                      for k, r in enumerate(rows)]))
        return [[merged]], problem.lower, problem.upper


class SchemeRunner(Runner):
    """A closed-form paper scheme on the scenarios that name it."""

    kinds = ("scenario",)

    def __init__(self, scheme: str) -> None:
        self.scheme = scheme
        self.name = f"scheme:{scheme}"

    def applies(self, problem: BenchProblem) -> str | None:
        """See :meth:`Runner.applies`."""
        reason = super().applies(problem)
        if reason is not None:
            return reason
        scenario = load_scenario(str(problem.scenario))
        if self.scheme not in scenario.schemes:
            return f"scenario does not name {self.scheme}"
        return None

    def _scenario_controller(self, scenario: Any, stack: Any) -> Any:
        return build_scheme(self.scheme, scenario, stack=stack)


class PinkRunner(Runner):
    """Pink on the problems it can express (one weighted level on a fully actuated model)."""

    name = "pink"
    kinds = ("scenario", "uvms")

    def __init__(self, qp_solver: str = "daqp") -> None:
        self.qp_solver = qp_solver

    def applies(self, problem: BenchProblem) -> str | None:
        """See :meth:`Runner.applies`."""
        reason = super().applies(problem)
        if reason is not None:
            return reason
        if problem.kind == "uvms":
            return None if problem.info.get("pink") else "stack has strict priorities"
        scenario = load_scenario(str(problem.scenario))
        task, trajectory = _tracking(scenario, scenario.build_stack())
        if task is None or trajectory is None:
            return "no tracked frame with a trajectory"
        return pink_supported(scenario.model, task.frame)

    def run(self, problem: BenchProblem, repetitions: int) -> Record:
        """See :meth:`Runner.run`; a scenario row is noted as Pink's own, smaller problem."""
        record = super().run(problem, repetitions)
        if problem.kind == "scenario" and record.applicable:
            record.note = f"{OWN_PROBLEM}; {record.note}" if record.note else OWN_PROBLEM
        return record

    def _scenario_controller(self, scenario: Any, stack: Any) -> Any:
        task, trajectory = _tracking(scenario, stack)
        state = scenario.model.state(scenario.q0)
        lo, hi = rate_box(stack.constraints, state, scenario.dt, scenario.model.nv)
        gain = getattr(task, "gain", 1.0)
        gain = float(np.max(gain)) if np.ndim(gain) else float(gain)
        return PinkController(scenario.model, scenario.dt, frame=task.frame,
                              trajectory=trajectory, gain=gain,
                              position_gain=position_gain(stack.constraints),
                              rate_lower=lo, rate_upper=hi, qp_solver=self.qp_solver)

    def _uvms_controller(self, draw: Any) -> Any:
        spec = draw.pink
        draw.stack.bind(draw.model)  # the rate bounds are read from the bound constraints
        state = draw.model.state(draw.q)
        lo, hi = rate_box(draw.stack.constraints, state, draw.dt, draw.model.nv)
        return PinkController(draw.model, draw.dt, position=spec["position"],
                              rotation=spec["rotation"], gain=spec["gain"],
                              posture_cost=spec["posture_weight"],
                              position_gain=position_gain(draw.stack.constraints),
                              rate_lower=lo, rate_upper=hi, qp_solver=self.qp_solver)


def _tracking(scenario: Any, stack: Any) -> tuple[Any, Any]:
    """The scenario's tracking task in ``stack`` and its trajectory (None when missing)."""
    if scenario.tracking is None:
        return None, None
    return stack.task(scenario.tracking), scenario.tracking_trajectory


# ------------------------------------------------------------------------------------ registry

#: Additional runners by name (a hook for plug-ins and tests): name -> factory.
EXTRA_RUNNERS: dict[str, Callable[[], Runner]] = {}


def runner_names() -> tuple[list[str], list[str]]:
    """Every runner available here, in table order, and notes on the missing ones."""
    solvers = available_solvers()
    names = [s for s in solvers if s != "nullspace"]
    names += ["nullspace", "weighted"] if "nullspace" in solvers else ["weighted"]
    names += [f"scheme:{s}" for s in SCHEME_TYPES]
    notes = []
    if pink_available():
        names.append("pink")
    else:
        notes.append("pink: not installed, skipped (pip install 'uvms-qp[pink]')")
    names += list(EXTRA_RUNNERS)
    return names, notes


def make_runner(name: str) -> Runner:
    """Build the runner called ``name``."""
    if name in EXTRA_RUNNERS:
        return EXTRA_RUNNERS[name]()
    if name == "nullspace":
        return NullspaceRunner()
    if name == "weighted":
        return WeightedRunner()
    if name == "pink":
        return PinkRunner()
    if name.startswith("scheme:"):
        return SchemeRunner(name.split(":", 1)[1])
    return HqpRunner(name)


def select_runners(patterns: list[str] | None) -> tuple[list[Runner], list[str]]:
    """Runners whose names match any of ``patterns`` (shell globs, e.g. ``cascade:*``).

    Returns:
        The runners in table order and notes (missing optional ones).

    Raises:
        InputError: a pattern that matches no available runner (the available ones are listed).
    """
    names, notes = runner_names()
    if not patterns:
        chosen = names
    else:
        chosen = []
        for pattern in patterns:
            hits = [n for n in names if fnmatch.fnmatchcase(n, pattern)]
            if not hits:
                if pattern == "pink" and not pink_available():
                    continue
                raise InputError(f"--solvers: {pattern!r} matches nothing; available: "
                                 f"{', '.join(names)}")
            chosen.extend(h for h in hits if h not in chosen)
        chosen = [n for n in names if n in chosen]
    return [make_runner(n) for n in chosen], notes
