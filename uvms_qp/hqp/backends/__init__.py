"""Back-ends of the lexicographic solver; each exposes ``solve(problem) -> BackendOutput``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..._validation import FloatArray
from ..result import Status


@dataclass
class BackendOutput:
    """What a back-end hands to :func:`uvms_qp.hqp.evaluate.evaluate`.

    Attributes:
        x: Solution or None on failure.
        status: The back-end's verdict (OPTIMAL means "claims success"; the evaluation decides
            between optimal and level_infeasible).
        message: Detail for the user.
        info: Back-end extras (exit flags, DAQP's own timing...).
        measured: Set by back-ends with a stacked workspace when ``x`` was already measured:
            ``(workspace, slacks, lo, hi, w, box/hard violation)`` for
            :func:`uvms_qp.hqp.evaluate.evaluate_stacked`; None otherwise.
    """

    x: FloatArray | None
    status: Status = Status.OPTIMAL
    message: str = ""
    info: dict[str, object] = field(default_factory=dict)
    measured: tuple[Any, ...] | None = None
