"""The command as a signal: reversals, counted the one way the library counts them.

A reversal of an entry of zeta is a change of sign from one command to the next with both
commands above :data:`REVERSAL_THRESHOLD` of the entry's bound: noise around zero is not a
reversal, nor is a smooth change of direction (it passes through the small values), while a
command that bangs between its bounds reverses every step (1 / dt per second).
:func:`command_reversals` counts them on a recorded series (the run metrics of
:mod:`uvms_qp.sim.metrics`); :class:`CommandHistory` keeps the controller's own recent commands so
that every :class:`~uvms_qp.controller.StepResult` can tell how the command behaved over the last
second, also in a loop that records nothing.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray

#: Fraction of an entry's bound a command must exceed, on both sides of a sign change, for the
#: change to count as a reversal.
REVERSAL_THRESHOLD = 0.01
#: Time [s] over which the controller counts its own reversals.
HISTORY_WINDOW = 1.0


def command_reversals(zeta: FloatArray, bounds: FloatArray,
                      threshold: float = REVERSAL_THRESHOLD) -> NDArray[np.int64]:
    """Number of reversals of each entry of the command (nv,).

    A reversal: two consecutive commands of opposite signs, both above ``threshold * bounds``
    in magnitude.

    Args:
        zeta: Commands (N, nv), oldest first.
        bounds: Bound of each entry (nv,) [m/s, rad/s].
        threshold: Fraction of the bound a command must exceed on both sides.
    """
    if zeta.shape[0] < 2:
        return np.zeros(zeta.shape[1], dtype=np.int64)
    large = np.abs(zeta) > threshold * bounds
    flips = (np.sign(zeta[1:]) * np.sign(zeta[:-1]) < 0) & large[1:] & large[:-1]
    return np.asarray(flips.sum(axis=0), dtype=np.int64)


def box_bounds(lower: FloatArray, upper: FloatArray) -> FloatArray:
    """Bound of each entry from a box (nv,): the larger finite side, inf where neither is."""
    low, high = np.abs(lower), np.abs(upper)
    low = np.where(np.isfinite(low), low, -np.inf)
    high = np.where(np.isfinite(high), high, -np.inf)
    widest = np.maximum(low, high)
    return np.asarray(np.where(widest >= 0.0, widest, np.inf), dtype=np.float64)


class CommandHistory:
    """The controller's last commands, for the reversal figure of each step.

    Recording costs one row copy per step; the count runs only when a step result is asked for
    it. The bound of each entry is the controller's static box (its rate bounds), or, for an
    entry without one, the largest command of the window.

    Args:
        nv: Size of zeta.
        dt: Control period [s] (the window holds ``HISTORY_WINDOW / dt + 1`` commands).
        bounds: Bound of each entry (nv,) [m/s, rad/s] (inf where none).
    """

    __slots__ = ("bounds", "count", "dt", "ring")

    def __init__(self, nv: int, dt: float, bounds: FloatArray) -> None:
        size = max(2, math.ceil(HISTORY_WINDOW / dt - 1e-9) + 1)
        self.ring = np.zeros((size, nv))
        self.count = 0
        self.dt = dt
        self.bounds = bounds

    def record(self, zeta: FloatArray) -> tuple[FloatArray, int]:
        """Keep ``zeta``; return ``(ring, count)``, what :func:`reversals_per_s` needs later."""
        self.ring[self.count % self.ring.shape[0]] = zeta
        self.count += 1
        return self.ring, self.count

    def reset(self) -> None:
        """Forget every command."""
        self.count = 0


def reversals_per_s(history: CommandHistory, ring: FloatArray, count: int) -> float:
    """Worst entry's reversals per second over the window that ended at command ``count``.

    Args:
        history: The history the commands came from (bounds, period).
        ring: A copy of its ring taken at that command (or the ring itself if no command came
            since).
        count: The number of commands recorded up to and including that one.
    """
    size = ring.shape[0]
    n = min(count, size)
    if n < 2:
        return 0.0
    end = count % size
    ordered = np.roll(ring, -end, axis=0)[size - n:]
    bounds = history.bounds
    unbounded = ~np.isfinite(bounds)
    if unbounded.any():
        bounds = bounds.copy()
        bounds[unbounded] = np.abs(ordered[:, unbounded]).max(axis=0)
    flips = command_reversals(ordered, bounds)
    return float(flips.max(initial=0)) / ((n - 1) * history.dt)
