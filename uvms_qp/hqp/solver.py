"""The entry points: a reusable :class:`HierarchySolver` and the one-shot :func:`solve_hierarchy`.

One path for every call: :class:`~uvms_qp.hqp.validate.Validator` (user input only) ->
back-end (:mod:`uvms_qp.hqp.backends`) -> :func:`~uvms_qp.hqp.measure.evaluate` (the measurement
and the optimality certificate of every unmet level) -> for an answer the certificate cannot
prove: the back-end once more on the problem without its degenerate rows when it reduces them
(DAQP), else :func:`~uvms_qp.hqp.certificate.repair` (an exact active-set pass from the answer),
each certified again; what is still not proven is reported ``unproven``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from time import perf_counter
from time import perf_counter as _wall
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from .backends import Backend
from .backends.cascade import CascadeBackend
from .backends.daqp import DaqpBackend
from .backends.daqp_binding import open_daqp
from .backends.nullspace import NullspaceBackend
from .certificate import Certifier, repair
from .linalg import one_blas_thread
from .measure import Certify, clip_to_box, evaluate
from .problem import Problem
from .registry import SolverSpec, available_solvers, get_spec
from .result import OK_STATUSES, HierarchyResult, Status
from .validate import Validator, check_magnitude


def make_backend(spec: SolverSpec, options: dict[str, Any]) -> Backend:
    """The back-end of a registry entry, configured with ``options`` (checked by it)."""
    if spec.kind == "daqp":
        return DaqpBackend(spec, options)
    if spec.kind == "cascade":
        return CascadeBackend(spec, options)
    return NullspaceBackend(spec, **options)


class HierarchySolver:
    """A reusable lexicographic solver: keeps the problem buffers and the back-end's warm start.

    Args:
        solver: One of :func:`available_solvers` (``"daqp"``, ``"nullspace"``,
            ``"cascade:<qpsolvers name>"``).
        weights: Diagonal of the metric W of the final regularisation ``min x' W x``, shape (n,),
            positive; None for the identity (e.g. ``[10, 10, 10, 1, 1, 1]`` moves the arm rather
            than the vehicle, Soylu et al. (2007), Eq. (17)).
        options: Back-end options. Common keys: ``level_tol`` (relative tolerance deciding that a
            level is met, default from the registry), ``hard_tol``; DAQP settings (``rho_soft``,
            ``primal_tol``, ``time_limit``...) and ``rho_ladder``; cascade ``rank_tol``, ``reg``
            and qpsolvers settings; nullspace ``rcond``, ``atol`` and ``damping``.
        deadline: Budget of one solve [s] on :attr:`clock` (None: none). Every part of a
            solve takes its time from what is left: a cascade starts no QP after it, the
            certificate leaves the levels it has not reached ``unproven``, the repair stops
            with the best point it has; a solve past it reports what it has, truthfully.

    Attributes:
        backend: The back-end object (:class:`~uvms_qp.hqp.backends.Backend`).
        certify: The optimality certificate asked about every answer with an unmet level (a
            :class:`~uvms_qp.hqp.certificate.Certifier` at the solver's tolerances by default,
            or a stand-in :data:`~uvms_qp.hqp.measure.Certify`); None: unmet levels are not
            questioned (the status then claims what it has not proven).
        repair: An answer the certificate cannot prove is solved again without its degenerate
            rows (a back-end that reduces them) or goes through
            :func:`~uvms_qp.hqp.certificate.repair` before it is reported ``unproven``
            (default: for back-ends that enforce the hard set; a closed form's answer is
            reported as it is). A safe solver asks for it as a stage of its ladder instead.
        deadline: Budget of one solve [s] (``inf``: none).
        saturate: Clip every claimed answer into the box before measuring it, the amount in
            ``info["clipped"]`` (for a closed form that cannot enforce the box, whose command is
            its saturated answer); False by default.

    Raises:
        UnknownSolverError: unknown or uninstalled solver (lists installed ones, says what to
            install).
        InputError: options that are not a dict of known keys, or a bad value.
    """

    def __init__(self, solver: str = "daqp", weights: Any = None,
                 options: dict[str, Any] | None = None, *, deadline: float | None = None
                 ) -> None:
        self.spec = get_spec(solver)
        if options is None:
            options = {}
        if not isinstance(options, dict) or not all(isinstance(k, str) for k in options):
            raise InputError(f"options: expected a dict with string keys, got {options!r}")
        opts = dict(options)
        self.level_tol = as_scalar(opts.pop("level_tol", self.spec.level_tol),
                                   "options['level_tol']", positive=True)
        self.hard_tol = as_scalar(opts.pop("hard_tol", self.spec.hard_tol),
                                  "options['hard_tol']", positive=True)
        self.backend: Backend = make_backend(self.spec, opts)
        self.deadline = math.inf if deadline is None else as_scalar(
            deadline, "deadline", positive=True, allow_inf=True)
        self._name = self.spec.name
        self.certifier = Certifier(open_daqp, level_tol=self.level_tol, hard_tol=self.hard_tol)
        self.certify: Certify | None = self.certifier
        self.repair = self.spec.bounds
        self._clock: Callable[[], float] = perf_counter
        self.clock = perf_counter
        self.saturate = False
        self.weights = weights
        self._validate = Validator()

    @property
    def name(self) -> str:
        """Name of the solver."""
        return self.spec.name

    @property
    def clock(self) -> Callable[[], float]:
        """The clock [s] of :attr:`deadline`; the back-end and the certificate read it too.

        :func:`time.perf_counter` by default; a safe solver sets its own (a test may fake it).
        """
        return self._clock

    @clock.setter
    def clock(self, clock: Callable[[], float]) -> None:
        self._clock = clock
        self.backend.clock = clock
        self.certifier.clock = clock

    @property
    def weights(self) -> Any:
        """Diagonal of the metric W as given (None for the identity)."""
        return self._weights

    @weights.setter
    def weights(self, value: Any) -> None:
        if value is getattr(self, "_weights", ...) and value is None:
            return
        self._weights = value
        self._metric: FloatArray | None = None
        self._metric_src = b""

    def _metric_for(self, n: int) -> FloatArray | None:
        """The validated metric for n variables (None for the identity).

        Validated once and reused while the given weights keep their values (an array changed
        in place is noticed through its bytes and validated again).
        """
        raw = self._weights
        if raw is None:
            return None
        try:
            src = np.asarray(raw, dtype=np.float64).tobytes()
        except (TypeError, ValueError):
            src = b"?"
        W = self._metric
        if W is None or W.shape[0] != n or src != self._metric_src:
            W = as_vector(raw, "weights", n, positive=True).copy()  # never the caller's array
            check_magnitude(W, "weights", weights=True)
            self._metric, self._metric_src = W, src
        return W

    def reset(self) -> None:
        """Forget the back-end's warm start: the next solve starts cold."""
        self.backend.reset()
        self.certifier.reset()

    def solve(self, levels: Sequence[Any], lower: Any = None, upper: Any = None,
              hard: Sequence[Any] | None = None) -> HierarchyResult:
        """Validate and solve one lexicographic problem.

        Args:
            levels: Levels, highest priority first; each a list of ``Rows``, ``(A, b)`` pairs or
                ``(A, lo, hi)`` triples over x (shape (m, n)), or one of them alone.
            lower: Hard lower bounds on x (length n, ``-inf`` allowed), e.g. [m/s], [rad/s].
            upper: Hard upper bounds on x (length n, ``+inf`` allowed).
            hard: Hard general rows (never relaxed), same forms as a level.

        Returns:
            The result (never None; ``x`` always finite; see :class:`~uvms_qp.hqp.Status`).

        Raises:
            InputError: malformed input (shape, NaN/inf, lower > upper, inequality level given to
                ``"nullspace"``), with a message naming the culprit.
        """
        problem = self._validate(levels, lower, upper, hard)
        if self._weights is not None:
            problem.W = self._metric_for(problem.n)  # type: ignore[assignment]
        return self.solve_problem(problem)

    def solve_problem(self, problem: Problem, end: float | None = None, *,
                      repair: bool | None = None) -> HierarchyResult:
        """Solve a :class:`~uvms_qp.hqp.problem.Problem` (trusted: no validation).

        The problem's own metric ``problem.W`` is used; ``x`` is measured like any answer.

        Args:
            problem: The problem.
            end: Reading of :attr:`clock` [s] by which the solve ends (default: now plus
                :attr:`deadline`).
            repair: Repair an unproven answer (:meth:`repaired`); default :attr:`repair`.
        """
        if end is None:
            end = self._clock() + self.deadline
        if self.single_threaded(problem):
            return self._solve_problem(problem, end, repair)
        with one_blas_thread:
            return self._solve_problem(problem, end, repair)

    def single_threaded(self, problem: Problem) -> bool:
        """True when no product of this solver's solve of ``problem`` can run a second thread.

        That is :attr:`Problem.single_threaded` with a back-end that calls no factorisation of
        its own: the solve needs no BLAS thread limit (a part that factorises enters it itself).
        """
        return problem.single_threaded and not getattr(self.backend, "factorises", True)

    def _solve_problem(self, problem: Problem, end: float, repair: bool | None
                       ) -> HierarchyResult:
        """:meth:`solve_problem` on its end (inside the BLAS thread limit or not).

        Without the limit when no product of the solve can thread
        (:attr:`Problem.single_threaded`, a back-end that calls no factorisation of its own).
        """
        start = _wall()
        self.backend.end = end
        self.certifier.end = end
        answer = self.backend.solve(problem)
        x, message, info = answer.x, answer.message, answer.info
        if self.saturate and answer.status in OK_STATUSES and answer.measured is None:
            x, message, info = _saturated(problem, x, message, info)
        result = evaluate(problem, x, answer.status, self._name, message, info,
                          self.level_tol, self.hard_tol, _wall() - start, answer.measured,
                          self.certify)
        if result.status is Status.UNPROVEN and (self.repair if repair is None else repair):
            result = self.repaired(problem, result, end, start)
        return result

    def repaired(self, problem: Problem, result: HierarchyResult, end: float,
                 start: float | None = None) -> HierarchyResult:
        """An unproven answer made proven, or as it was with what was tried in its message.

        First the back-end again on the problem without its degenerate rows (when it reduces
        them: DAQP), then :func:`~uvms_qp.hqp.certificate.repair` from the better of the two
        answers, both by ``end`` (a reading of :attr:`clock`). An ill-posed level is left as it
        is: its exact optimum is the answer already.
        """
        if start is None:
            start = _wall()
        cert = result.certificate
        if cert is None or cert.ok or cert.ill_posed:
            return result
        with one_blas_thread:
            self.backend.end = self.certifier.end = end
            if self.backend.reduce(problem):
                answer = self.backend.solve(problem)
                again = evaluate(problem, answer.x, answer.status, self._name, answer.message,
                                 {**answer.info, "reduced": True}, self.level_tol,
                                 self.hard_tol, _wall() - start, answer.measured, self.certify)
                if again.status is not Status.UNPROVEN:
                    if again.ok:
                        return again
                    return _noted(result, "degenerate rows reduced: " + again.status.value,
                                  start)
                result = again
                cert = again.certificate
                if cert is None or cert.ill_posed:
                    return result
            fixed = repair(problem, result.x, cert, certifier=self.certifier, deadline=end,
                           clock=self._clock)
            if not fixed.repaired and fixed.x is result.x:
                return _noted(result, f"repair: {fixed.message}", start)
            info = {**result.info, "repaired_from_level": cert.first_failure}
            message = "; ".join(m for m in (result.message, fixed.message) if m)
            return evaluate(problem, fixed.x, Status.OPTIMAL, self._name, message, info,
                            self.level_tol, self.hard_tol, _wall() - start, None, self.certify)


def _noted(result: HierarchyResult, note: str, start: float) -> HierarchyResult:
    """``result`` with ``note`` added to its message and the time so far."""
    result.message = f"{result.message}; {note}" if result.message else note
    result.solve_time = _wall() - start
    return result


def _saturated(problem: Problem, x: Any, message: str, info: dict[str, object]
               ) -> tuple[Any, str, dict[str, object]]:
    """A finite answer of the right length clipped into the box (anything else unchanged)."""
    if not (isinstance(x, np.ndarray) and x.shape == (problem.n,) and np.isfinite(x).all()):
        return x, message, info
    clipped, amount = clip_to_box(x, problem.lower, problem.upper)
    if not amount:
        return x, message, info
    return clipped, message or "saturated into the hard box", {**info, "clipped": amount}


def solve_hierarchy(
    levels: Sequence[Any],
    lower: Any = None,
    upper: Any = None,
    solver: str = "daqp",
    weights: Any = None,
    *,
    hard: Sequence[Any] | None = None,
    options: dict[str, Any] | None = None,
    deadline: float | None = None,
) -> HierarchyResult:
    """Solve a lexicographic problem once (see :class:`HierarchySolver` for the arguments).

    Repeated calls with the same ``solver`` and no ``options`` reuse one cached
    :class:`HierarchySolver` (its buffers and warm start), so a loop of calls stays cheap.
    ``deadline`` [s] bounds this call (None: none).
    """
    if not isinstance(solver, str):
        raise InputError(f"solver: expected a solver name (one of {available_solvers()}), "
                         f"got {type(solver).__name__}")
    if options is None:
        cached = _CACHE.get(solver)
        if cached is None:
            cached = _CACHE[solver] = HierarchySolver(solver)
        if weights is not None or cached._weights is not None:
            cached.weights = weights
        cached.deadline = math.inf if deadline is None else as_scalar(
            deadline, "deadline", positive=True, allow_inf=True)
        return cached.solve(levels, lower, upper, hard)
    return HierarchySolver(solver, weights, options, deadline=deadline).solve(
        levels, lower, upper, hard)


_CACHE: dict[str, HierarchySolver] = {}
