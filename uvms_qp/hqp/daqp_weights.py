"""Per-row soft weights that make DAQP's hierarchy minimise each level's weighted violation.

DAQP softens every row of a level after scaling it to unit norm in the metric of the QP (the
rows ``m_i = a_i W^(-1/2)`` of its least-distance form), so with one uniform soft weight it
minimises ``sum_i (s_i / |m_i|)^2`` on a level that cannot be met, whatever the row weights. DAQP
(0.11) also takes one reciprocal quadratic weight ``rho_i`` per row, in the scale of the original
problem: the penalty of row ``i`` is ``s_i^2 / (2 rho_i)``. With

    rho_i = rho_soft * max_{j in level} (w_j |m_j|^2) / w_i

the penalties of a level are proportional to ``w_i s_i^2``, the weighted least-squares violation
every other back-end minimises, and the normalised weights DAQP works with,
``rho_i / |m_i|^2 = rho_soft * max_j (w_j |m_j|^2) / (w_i |m_i|^2)``, are never below
``rho_soft``: the most weighted row of a level keeps the regularisation DAQP is tuned for, the
others are softened in proportion. A level whose rows are all zero keeps the default (0 selects
``rho_soft``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validation import FloatArray


class SoftWeights:
    """The per-row ``rho_i`` of one structure, recomputed from the rows every solve.

    Args:
        head: Number of simple bounds and hard rows before the level rows (their entries stay
            0: DAQP's default, irrelevant for hard rows).
        sizes: Rows per level.
        W: Diagonal metric (n,) of the QP (``H = diag(W)``).

    Attributes:
        rho: Full-length weights ``(head + sum(sizes),)`` handed to DAQP (a reused buffer).
    """

    def __init__(self, head: int, sizes: Sequence[int], W: FloatArray) -> None:
        self.head = int(head)
        self.rho = np.zeros(self.head + int(sum(sizes)))
        self._levels = self.rho[self.head:]
        self._squares = np.zeros((int(sum(sizes)), len(W)))
        sizes = [int(m) for m in sizes]
        bounds = np.cumsum((0, *sizes))
        filled = [k for k, m in enumerate(sizes) if m]  # reduceat needs non-empty segments
        self._starts = bounds[filled].astype(np.intp)
        self._row_level = np.repeat(np.arange(len(filled)), [sizes[k] for k in filled])
        self._inv_W = 1.0 / np.asarray(W, dtype=np.float64)

    def compute(self, rows: FloatArray, w: FloatArray, rho_soft: float) -> FloatArray:
        """Write and return :attr:`rho` for level rows ``rows`` (sum(sizes), n), weights ``w``.

        Args:
            rows: The level rows ``a_i`` (original scale).
            w: Positive row weights.
            rho_soft: DAQP's uniform soft weight (in its normalised form).
        """
        self.compute_levels(rows, w, rho_soft, self._levels)
        return self.rho

    def compute_levels(self, rows: FloatArray, w: FloatArray, rho_soft: float,
                       out: FloatArray) -> None:
        """:meth:`compute` for the level entries only, written into ``out`` (sum(sizes),)."""
        q = np.square(rows, out=self._squares).dot(self._inv_W)  # |a_i W^(-1/2)|^2
        q *= w
        top = np.maximum.reduceat(q, self._starts)
        top *= rho_soft
        np.divide(top.take(self._row_level), w, out=out)


def soft_weights_supported(model: Any) -> bool:
    """True when a set-up ``model`` (``daqp.Model`` or ``NativeDaqp``) takes per-row weights.

    The binding must offer ``soft_weights`` and the C library must have been built with them
    (a call without arrays changes nothing and is refused otherwise). Check once per set-up.
    """
    setter = getattr(model, "soft_weights", None)
    if setter is None:
        return False
    try:
        setter()
    except RuntimeError:
        return False
    return True
