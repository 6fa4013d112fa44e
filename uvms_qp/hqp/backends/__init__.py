"""Back-ends of the lexicographic solver: one file per family, one protocol.

A back-end turns a :class:`~uvms_qp.hqp.problem.Problem` into an :class:`Answer` (the raw ``x``
and what the back-end says about it); everything after it is shared: the measurement and status
of :mod:`uvms_qp.hqp.measure`, the fallback ladder of :mod:`uvms_qp.safety`.

=================  ==========================================================================
family             module
=================  ==========================================================================
``daqp``           :mod:`.daqp`: DAQP's hierarchical mode, all levels in one call (C binding in
                   :mod:`.daqp_binding`)
``cascade``        :mod:`.cascade`: one QP per level through qpsolvers
``nullspace``      :mod:`.nullspace`: the closed-form recursive null-space solution
=================  ==========================================================================
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

from ..._validation import FloatArray
from ..measure import Measured
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status


@dataclass(slots=True)
class Answer:
    """What a back-end hands on to :func:`uvms_qp.hqp.measure.evaluate`.

    Attributes:
        x: Solution, or None on failure (never trusted: measured afterwards).
        status: The back-end's verdict (``optimal`` means "claims success": the measurement
            and the certificate decide).
        message: Detail for the user.
        info: Back-end extras (exit flags, DAQP's own timing...).
        measured: :func:`~uvms_qp.hqp.measure.measure` of ``x``, when the back-end measured it
            already (its own acceptance test), so that it is not measured twice.
    """

    x: FloatArray | None
    status: Status = Status.OPTIMAL
    message: str = ""
    info: dict[str, object] = field(default_factory=dict)
    measured: Measured | None = None


class Backend(Protocol):
    """A back-end of the lexicographic problem.

    Attributes:
        spec: Its registry entry.
        end: Reading of ``clock`` [s] by which the current solve ends (set by the solver before
            each solve; ``inf``: none). A back-end whose solves can run long stops there and
            reports ``backend_error``.
        clock: The clock of ``end`` [s] (the solver's; a safe solver's may be a test's).
        factorises: (optional) Its solve calls BLAS or LAPACK routines that may run threads (an SVD,
            least squares, a QP library on BLAS): its solves always run inside
            :data:`~uvms_qp.hqp.linalg.one_blas_thread`. False for a back-end whose own work
            is native code without BLAS (DAQP), whose small problems then skip the limit
            (:func:`~uvms_qp.hqp.linalg.single_threaded`); a solver reads a back-end without
            this attribute as True.
    """

    spec: SolverSpec
    end: float
    clock: Callable[[], float]

    def solve(self, problem: Problem) -> Answer:
        """Solve ``problem`` (trusted: validated upstream)."""

    def reset(self) -> None:
        """Forget any warm start: the next solve starts cold."""

    def reduce(self, problem: Problem) -> bool:
        """Leave the level rows that are constants of their level out of the next solves.

        Constants over the higher levels' optimum (after an answer the certificate could not
        prove, or a failed solve).

        Returns:
            True when the next solve of ``problem`` differs (rows newly left out), False when
            the back-end has nothing to reduce (it handles such rows by design).
        """
