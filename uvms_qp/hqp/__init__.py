"""The lexicographic (hierarchical) least-squares solver on plain matrices.

Levels ``L_0 > ... > L_(p-1)`` of rows ``lo_k <= A_k x <= hi_k`` are solved in priority order, each
level minimising its weighted violation ``sum_i w_i s_i^2`` subject to the hard box and rows and to
every higher level keeping the violation it reached; a final regularisation picks the minimum of
``x' W x`` (``W`` diagonal). With equality levels only, full-rank levels and no active bound the
answer is the recursive null-space solution of Soylu et al. (2007), Eq. (10), in the
metric ``W`` (weighted pseudoinverse, Soylu et al. (2007), Eq. (17)).

The parts, each written once: :mod:`.problem` (the one stacked layout), :mod:`.validate` (user
input into it), :mod:`.backends` (one file per back-end family), :mod:`.measure` (slacks,
residuals, the hard violation, the status), :mod:`.result`, :mod:`.registry`, :mod:`.hard_set`
and :mod:`.kkt` (helpers of the back-ends).

Example:
    >>> import numpy as np
    >>> from uvms_qp.hqp import solve_hierarchy
    >>> A1 = np.array([[1.0, 1.0, 0.0]])
    >>> result = solve_hierarchy([[(A1, [1.0])]], lower=[-1, -1, -1], upper=[1, 1, 1])
    >>> result.status.value, np.round(result.x, 6).tolist()
    ('optimal', [0.5, 0.5, 0.0])
"""

from __future__ import annotations

from ..rows import Rows
from .measure import hard_violation
from .problem import Problem
from .registry import SOLVERS, SolverSpec, available_solvers
from .result import HierarchyResult, Status
from .solver import HierarchySolver, solve_hierarchy
from .validate import normalize_problem

__all__ = [
    "SOLVERS",
    "HierarchyResult",
    "HierarchySolver",
    "Problem",
    "Rows",
    "SolverSpec",
    "Status",
    "available_solvers",
    "hard_violation",
    "normalize_problem",
    "solve_hierarchy",
]
