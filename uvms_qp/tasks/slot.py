"""The run-time memory of one task in one controller (:class:`TaskSlot`).

A task is a description: its parameters, its binding to a model and the rows they give. What
changes from tick to tick (the activation and its ramp, a held target, the last error, the
previous value of a rate estimate, the Jacobian already written into the problem) lives in a
slot, one per task and per controller, made by :meth:`~uvms_qp.tasks.Task.new_slot` and owned
by the controller's stack assembler. Two controllers on one stack each keep their own slots,
as Pinocchio keeps a ``Data`` per use of one ``Model``.

A task class with memory of its own subclasses :class:`TaskSlot` (adding ``__slots__`` and
extending :meth:`TaskSlot.clear`) and names it in ``Task.Slot``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import FloatArray


class TaskSlot:
    """Run-time memory of one task in one controller.

    Attributes:
        activation: The task's activation in [0, 1] at the last tick (1: in the stack, 0: out;
            set by the assembler from the stack's requests, see
            :meth:`~uvms_qp.stack.Stack.set_activation`).
        ramp: The activation ramp under way, ``(from, to, start time [s])``, or None.
        seen: The stack's activation request the slot last followed (a serial number).
        error: The error (error tasks) or objective value at the last evaluation
            [error_unit], as set (a sequence of floats becomes an array when read through
            :attr:`last_error`); None before the first evaluation.
        written: ``(buffer, J)`` of the latest fill (``J`` is not copied again into the same
            buffer when a task returns the same read-only array).
        row_weights: Per-row weights of a task whose weights change with the state (the
            joint-limit damping task), else None (the task's own ``row_weights``).
        peers: The slots of the other tasks of the controller by task (a task linked to
            another, :meth:`~uvms_qp.tasks.Task.link`, reads its values there), or None.
    """

    __slots__ = ("activation", "error", "peers", "ramp", "row_weights", "seen", "written")

    def __init__(self) -> None:
        self.activation = 1.0
        self.ramp: tuple[float, float, float] | None = None
        self.seen = -1
        self.peers: dict[Any, TaskSlot] | None = None
        self.row_weights: FloatArray | None = None
        self.error: Any = None
        self.written: tuple[Any, Any] = (None, None)
        self.clear()

    def clear(self) -> None:
        """Forget the task's memory (held targets, previous values, the last error).

        Called when the controller is reset and when the task enters the stack (its activation
        ramps up from 0). Subclasses extend it for the memory they add.
        """
        self.error = None

    @property
    def last_error(self) -> FloatArray | None:
        """The error or objective value at the last evaluation [error_unit] (None before)."""
        e = self.error
        if e is not None and type(e) is not np.ndarray:
            e = self.error = np.array(e, dtype=np.float64)
        return e
