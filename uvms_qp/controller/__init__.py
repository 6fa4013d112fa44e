"""The controller: a stack assembled into one problem every tick, solved by a scheme.

* :mod:`.assembler`: binds the stack, owns the problem's buffers, writes rows, box and hard rows;
* :mod:`.schemes`: the :class:`Scheme` protocol and the controller's ``hqp``, ``weighted`` and
  ``nullspace`` schemes, each running its solves through the fallback ladder;
* :mod:`.result`: :class:`StepResult`, the outcome of one step for every scheme;
* :mod:`.controller`: :class:`Controller`, the public facade.
"""

from __future__ import annotations

from .assembler import StackAssembler, not_a_state
from .controller import Controller
from .result import StepResult, TaskLayout
from .schemes import SCHEMES, HqpScheme, NullspaceScheme, Scheme, WeightedScheme

__all__ = [
    "SCHEMES",
    "Controller",
    "HqpScheme",
    "NullspaceScheme",
    "Scheme",
    "StackAssembler",
    "StepResult",
    "TaskLayout",
    "WeightedScheme",
    "not_a_state",
]
