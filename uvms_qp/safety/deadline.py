"""A per-step deadline: the back-ends' own limits derived from the step's budget.

Behaviour (also in ``docs/reliability.md``):

1. The step's clock starts when the step begins (the controller's ``step``; the safe solver's
   ``solve`` when called alone) and reads :func:`time.perf_counter` (or a clock given for tests).
   Its end is handed to every part of the solve: the back-end (``Backend.end``), the
   certificate, the repair and the damping screen each stop there.
2. Each back-end also receives a time or iteration limit derived from the budget
   (:func:`backend_limits`): DAQP ``time_limit`` [s] (hierarchical mode and cascade), HiGHS,
   OSQP and Clarabel ``time_limit`` [s] (a cascade hands each QP the time left), ProxQP and
   PIQP an iteration cap; quadprog has none. A cascade starts no QP after the end.
3. A back-end call cannot be pre-empted (it runs native code synchronously). When it returns
   after the deadline, its answer is still verified and, if verified, used (it is safe, and the
   freshest command available); the step is marked ``deadline_missed``.
4. Once the deadline has passed, the fallback ladder skips every remaining solver stage (cold
   retry, alternate back-end, relaxed levels, damping) and goes straight to the cheap stages
   (decayed previous command, zero).
"""

from __future__ import annotations

import math
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
