"""Reliability layer: validate before solving, verify after, fall back safely.

* :mod:`~uvms_qp.safety.verify`: is a back-end's answer finite, inside the hard set, truthful?
* :mod:`~uvms_qp.safety.fallback`: the ladder (cold retry, alternate back-end, relaxed levels,
  decayed previous command, zero, hold zero) in :class:`SafeSolver`;
* :mod:`~uvms_qp.safety.saturation`: the final clip to the hard box, with the amount reported;
* :mod:`~uvms_qp.safety.deadline`: the per-step wall-clock budget and back-end limits;

See ``docs/reliability.md`` for the contract of a control step.
"""

from __future__ import annotations

from .deadline import Deadline, backend_limits
from .fallback import (
    DEGRADED_STAGES,
    SOLVED_STAGES,
    STAGES,
    SafeSolve,
    SafeSolver,
    default_alternate,
    fallback_summary,
    reset_warm_start,
)
from .saturation import Saturation, saturate
from .verify import Verdict, hard_violation_of, verify_point, verify_solution

__all__ = [
    "DEGRADED_STAGES",
    "SOLVED_STAGES",
    "STAGES",
    "Deadline",
    "SafeSolve",
    "SafeSolver",
    "Saturation",
    "Verdict",
    "backend_limits",
    "default_alternate",
    "fallback_summary",
    "hard_violation_of",
    "reset_warm_start",
    "saturate",
    "verify_point",
    "verify_solution",
]
