"""A per-step deadline: wall time around back-end calls and the back-ends' own limits.

Behaviour (also in ``docs/reliability.md``):

1. The step's clock starts when the step begins (the controller's ``step``; the safe solver's
   ``solve`` when called alone) and reads :func:`time.perf_counter` (or a clock given for tests).
2. Each back-end receives a time or iteration limit derived from the budget
   (:func:`backend_limits`): DAQP ``time_limit`` [s] (hierarchical mode and cascade), HiGHS,
   OSQP and Clarabel ``time_limit`` [s], ProxQP and PIQP an iteration cap; quadprog has none.
   A cascade solves several QPs per step: :class:`CascadeGuard` refuses to start a QP once the
   deadline has passed (the QP counts as failed, the cascade reports ``backend_error`` at once),
   so a cascade step overruns by at most one QP.
3. A back-end call cannot be pre-empted (it runs native code synchronously). When it returns
   after the deadline, its answer is still verified and, if verified, used (it is safe, and the
   freshest command available); the step is marked ``deadline_missed``.
4. Once the deadline has passed, the fallback ladder skips every remaining solver stage (cold
   retry, alternate back-end, relaxed levels) and goes straight to the cheap stages (decayed
   previous command, zero), so a miss costs at most one more back-end call's worth of time.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

#: Solver name -> options that cap its run time, as a function of the budget [s].
_TIME_LIMITS: dict[str, str] = {
    "daqp": "time_limit",
    "cascade:daqp": "time_limit",
    "cascade:highs": "time_limit",
    "cascade:osqp": "time_limit",
    "cascade:clarabel": "time_limit",
}
_ITERATION_LIMITS: dict[str, tuple[str, int]] = {
    "cascade:proxqp": ("max_iter", 50),
    "cascade:piqp": ("max_iter", 250),
}


class CascadeGuard:
    """Stand-in for the ``qpsolvers`` module inside a cascade back-end: no QP after the deadline.

    A :class:`~uvms_qp.hqp.backends.cascade.CascadeBackend` calls
    ``qpsolvers.solve_problem`` once per QP through its ``_qpsolvers`` attribute;
    :func:`guard_cascade` replaces that attribute by this guard. Every other attribute is the
    module's. ``end`` is the ``time.perf_counter()`` instant after which ``solve_problem`` raises
    :class:`TimeoutError` (which the cascade treats as a failed QP); None disables the guard.
    """

    def __init__(self, module: Any, clock: Callable[[], float] = time.perf_counter) -> None:
        self._module = module
        self.clock = clock
        self.end: float | None = None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._module, name)

    def solve_problem(self, *args: Any, **kwargs: Any) -> Any:
        """``qpsolvers.solve_problem``, unless the deadline has passed."""
        if self.end is not None and self.clock() > self.end:
            raise TimeoutError("step deadline passed: QP not started")
        return self._module.solve_problem(*args, **kwargs)


def guard_cascade(backend: Any, clock: Callable[[], float] = time.perf_counter
                  ) -> CascadeGuard | None:
    """Install a :class:`CascadeGuard` in a cascade back-end; None for other back-ends."""
    module = getattr(backend, "_qpsolvers", None)
    if module is None:
        return None
    if isinstance(module, CascadeGuard):
        module.clock = clock
        return module
    guard = CascadeGuard(module, clock)
    backend._qpsolvers = guard
    return guard


def backend_limits(solver: str, budget: float | None) -> dict[str, Any]:
    """Back-end options that cap the time of one back-end call.

    Args:
        solver: Solver name (``"daqp"``, ``"cascade:<name>"``, ...).
        budget: Step budget [s], or None / ``inf`` for no limit.

    Returns:
        Options for :class:`~uvms_qp.hqp.HierarchySolver` (empty when there is nothing to set).
    """
    if budget is None or not math.isfinite(budget):
        return {}
    out: dict[str, Any] = {}
    key = _TIME_LIMITS.get(solver)
    if key is not None:
        out[key] = float(budget)
    it = _ITERATION_LIMITS.get(solver)
    if it is not None:
        out[it[0]] = it[1]
    return out
