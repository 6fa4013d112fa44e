"""Reliability layer: every control step ends with a finite command inside the hard box.

* :mod:`~uvms_qp.safety.fallback`: the ladder (cold retry, alternate back-end, relaxed levels,
  decayed previous command, zero, hold zero) in :class:`SafeSolver`, which runs every solve of
  every scheme; an answer is verified by its measurement (:mod:`uvms_qp.hqp.measure`);
* :mod:`~uvms_qp.safety.deadline`: the back-ends' own limits derived from the step's budget;
* :mod:`~uvms_qp.safety.realtime`: preparing the host process for wall-clock deadlines
  (a real-time priority, a frozen garbage collector), on the user's call.

See ``docs/reliability.md`` for the contract of a control step.
"""

from __future__ import annotations

from .deadline import backend_limits
from .fallback import (
    CLIP_FLAG_TOL,
    DEGRADED_STAGES,
    SOLVED_STAGES,
    STAGES,
    SafeSolve,
    SafeSolver,
    default_alternate,
    fallback_summary,
)
from .realtime import RealtimePermissionError, RealtimeSettings, prepare_realtime

__all__ = [
    "CLIP_FLAG_TOL",
    "DEGRADED_STAGES",
    "SOLVED_STAGES",
    "STAGES",
    "RealtimePermissionError",
    "RealtimeSettings",
    "SafeSolve",
    "SafeSolver",
    "backend_limits",
    "default_alternate",
    "fallback_summary",
    "prepare_realtime",
]
