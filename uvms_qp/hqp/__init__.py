"""The lexicographic (hierarchical) least-squares solver on plain matrices.

Levels ``L_1 > ... > L_p`` of rows ``lo_k <= A_k x <= hi_k`` are solved in priority order, each
level minimising its weighted violation ``sum_i w_i s_i^2`` subject to the hard box and rows and to
every higher level keeping the violation it reached; a final regularisation picks the minimum of
``x' W x`` (``W`` diagonal). With equality levels only, full-rank levels and no active bound the
answer is the recursive null-space solution of ``000_7b5f597fe4e36aa4.txt, Eq. (10)`` in the
metric ``W`` (weighted pseudoinverse, ``000_7b5f597fe4e36aa4.txt, Eq. (17)``).

Example:
    >>> import numpy as np
    >>> from uvms_qp.hqp import solve_hierarchy
    >>> A1 = np.array([[1.0, 1.0, 0.0]])
    >>> result = solve_hierarchy([[(A1, [1.0])]], lower=[-1, -1, -1], upper=[1, 1, 1])
    >>> result.status.value, np.round(result.x, 6).tolist()
    ('optimal', [0.5, 0.5, 0.0])
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from ..rows import Rows
from .backends import BackendOutput
from .evaluate import evaluate, evaluate_stacked
from .inplace import check_settings
from .loading import load_levels
from .problem import Problem, normalize_problem
from .registry import SOLVERS, SolverSpec, available_solvers, get_spec
from .result import HierarchyResult, Status

__all__ = [
    "SOLVERS",
    "HierarchyResult",
    "HierarchySolver",
    "Problem",
    "Rows",
    "SolverSpec",
    "Status",
    "available_solvers",
    "normalize_problem",
    "solve_hierarchy",
]


_NULLSPACE_OPTIONS = frozenset(("rcond", "atol"))
_COMMON_OPTIONS = frozenset(("level_tol", "hard_tol"))


def _check_options(spec: SolverSpec, options: Any) -> dict[str, Any]:
    """A copy of the back-end options after checking that they are a dict of known keys.

    ``"daqp"`` takes DAQP settings and ``rho_ladder``, ``"nullspace"`` takes ``rcond`` and
    ``atol``; a cascade passes unknown keys on to its qpsolvers back-end, so only their type
    is checked. Every solver takes ``level_tol`` and ``hard_tol``.

    Raises:
        InputError: ``options`` is not a dict, or a key is unknown for the solver (the message
            lists the known ones).
    """
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise InputError(f"options: expected a dict, got {type(options).__name__}")
    for key in options:
        if not isinstance(key, str):
            raise InputError(f"options: expected string keys, got {key!r}")
    if spec.kind == "daqp":
        return check_settings(options, "options", _COMMON_OPTIONS | {"rho_ladder"})
    if spec.kind == "nullspace":
        known = _COMMON_OPTIONS | _NULLSPACE_OPTIONS
        for key, value in options.items():
            if key not in known:
                raise InputError(f"options: unknown option {key!r} for solver {spec.name!r} "
                                 f"(known: {', '.join(sorted(known))})")
            if key in _NULLSPACE_OPTIONS:
                as_scalar(value, f"options[{key!r}]", nonnegative=True)
    return dict(options)


def _make_backend(spec: SolverSpec, options: dict[str, Any] | None, lean: bool) -> Any:
    if spec.kind == "daqp":
        from .backends.daqp_hierarchical import DaqpHierarchicalBackend

        return DaqpHierarchicalBackend(spec, options, lean=lean)
    if spec.kind == "cascade":
        from .backends.cascade import CascadeBackend

        return CascadeBackend(spec, options)
    from .backends.nullspace import NullspaceBackend

    return NullspaceBackend(spec, **(options or {}))


class HierarchySolver:
    """A reusable lexicographic solver: keeps the back-end workspace between calls.

    Args:
        solver: One of :func:`available_solvers` (``"daqp"``, ``"nullspace"``,
            ``"cascade:<qpsolvers name>"``).
        weights: Diagonal of the metric W of the final regularisation ``min x' W x``, shape (n,),
            positive; None for the identity (e.g. ``[10, 10, 10, 1, 1, 1]`` moves the arm rather
            than the vehicle, ``000_7b5f597fe4e36aa4.txt, Eq. (17)``).
        options: Back-end options. Common keys: ``level_tol`` (relative tolerance deciding that a
            level is met, default from the registry), ``hard_tol``; DAQP settings (``rho_soft``,
            ``primal_tol``...); cascade ``rank_tol``, ``reg`` and qpsolvers settings; nullspace
            ``rcond``.
        lean: Use the fast path where the back-end has one (``"daqp"``: preallocated stacked
            buffers, vectorised validation and evaluation, lazy diagnostics). False runs the
            reference path (full normalisation, :func:`~uvms_qp.hqp.evaluate.evaluate`); both
            give the same ``x``, status and residuals (tested).

    Raises:
        UnknownSolverError: unknown or uninstalled solver (lists installed ones, says what to
            install).
    """

    def __init__(self, solver: str = "daqp", weights: Any = None,
                 options: dict[str, Any] | None = None, *, lean: bool = True) -> None:
        self.spec = get_spec(solver)
        self.weights = weights
        opts = _check_options(self.spec, options)
        self.level_tol = as_scalar(opts.pop("level_tol", self.spec.level_tol),
                                   "options['level_tol']", positive=True)
        self.hard_tol = as_scalar(opts.pop("hard_tol", self.spec.hard_tol),
                                  "options['hard_tol']", positive=True)
        self.lean = bool(lean)
        self._backend = _make_backend(self.spec, opts, self.lean)
        self._loads = self.lean and self.spec.kind == "daqp"

    @property
    def weights(self) -> Any:
        """Diagonal of the metric W as given (None for the identity)."""
        return self._weights

    @weights.setter
    def weights(self, value: Any) -> None:
        self._weights = value
        self._metric: FloatArray | None = None
        self._metric_src = b""

    def _metric_for(self, n: int) -> FloatArray:
        """The validated metric for n variables.

        Validated once and reused while the given weights keep their values (an array changed
        in place is noticed through its bytes and validated again).
        """
        raw = self._weights
        src = b""
        if raw is not None:
            try:
                src = np.asarray(raw, dtype=np.float64).tobytes()
            except (TypeError, ValueError):
                src = b"?"
        W = self._metric
        if W is None or W.shape[0] != n or src != self._metric_src:
            W = np.ones(n) if raw is None else as_vector(raw, "weights", n, positive=True)
            self._metric, self._metric_src = W, src
        return W

    @property
    def name(self) -> str:
        """Name of the solver."""
        return self.spec.name

    def solve(self, levels: Sequence[Any], lower: Any = None, upper: Any = None,
              hard: Sequence[Any] | None = None) -> HierarchyResult:
        """Validate and solve one lexicographic problem.

        Args:
            levels: Levels, highest priority first; each a list of ``Rows``, ``(A, b)`` pairs or
                ``(A, lo, hi)`` triples over x (shape (m, n)).
            lower: Hard lower bounds on x (length n, ``-inf`` allowed), e.g. [m/s], [rad/s].
            upper: Hard upper bounds on x (length n, ``+inf`` allowed).
            hard: Hard general rows (never relaxed), same forms as a level.

        Returns:
            The result (never None; ``x`` always finite; see :class:`Status`).

        Raises:
            InputError: malformed input (shape, NaN/inf, lower > upper, inequality level given to
                ``"nullspace"``), with a message naming the culprit.
        """
        if self._loads:
            loaded = load_levels(self._backend.workspace, levels, lower, upper, hard)
            if loaded is not None:
                ws, lo, hi, w = loaded
                W = self._metric_for(ws.n)
                memo: list[Problem] = []

                def get_problem() -> Problem:
                    if not memo:
                        memo.append(normalize_problem(levels, lower, upper, W, hard))
                    return memo[0]

                start = time.perf_counter()
                out = self._backend.solve_loaded(ws, lo, hi, w, W, get_problem)
                return self._result(out, get_problem, time.perf_counter() - start)
        problem = normalize_problem(levels, lower, upper, self.weights, hard)
        return self.solve_problem(problem)

    def solve_problem(self, problem: Problem) -> HierarchyResult:
        """Solve an already normalised :class:`Problem` (skips validation).

        The fast entry for internal callers: the arrays of ``problem`` are trusted (float64,
        consistent shapes, no NaN); finiteness of ``x`` and the hard rows are still verified.
        A problem that carries its stacked level rows (``problem.__dict__["stacked"]``, e.g. a
        view of a controller's row buffer) is loaded with one copy.
        """
        start = time.perf_counter()
        out: BackendOutput = self._backend.solve(problem)
        return self._result(out, lambda: problem, time.perf_counter() - start)

    def _result(self, out: BackendOutput, get_problem: Any, elapsed: float) -> HierarchyResult:
        if out.measured is not None and out.x is not None and self.lean:
            ws, s, lo, hi, w, hv = out.measured
            return evaluate_stacked(ws, out.x, s, lo, hi, w, hv, self.spec.name, out.status,
                                    out.message, level_tol=self.level_tol,
                                    hard_tol=self.hard_tol, solve_time=elapsed, info=out.info)
        return evaluate(get_problem(), out.x, self.spec.name, out.status, out.message,
                        level_tol=self.level_tol, hard_tol=self.hard_tol, solve_time=elapsed,
                        info=out.info)


def solve_hierarchy(
    levels: Sequence[Any],
    lower: Any = None,
    upper: Any = None,
    solver: str = "daqp",
    weights: Any = None,
    *,
    hard: Sequence[Any] | None = None,
    options: dict[str, Any] | None = None,
) -> HierarchyResult:
    """Solve a lexicographic problem once (see :class:`HierarchySolver` for the arguments).

    Repeated calls with the same ``solver`` and no ``weights``/``options`` reuse one cached
    :class:`HierarchySolver` (its back-end workspace), so a loop of calls stays cheap.
    """
    if not isinstance(solver, str):
        raise InputError(f"solver: expected a solver name (one of {available_solvers()}), "
                         f"got {type(solver).__name__}")
    if weights is None and options is None:
        cached = _CACHE.get(solver)
        if cached is None:
            cached = _CACHE[solver] = HierarchySolver(solver)
        return cached.solve(levels, lower, upper, hard)
    return HierarchySolver(solver, weights, options).solve(levels, lower, upper, hard)


_CACHE: dict[str, HierarchySolver] = {}
