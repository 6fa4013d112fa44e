"""Vectorised validation of user-facing levels straight into a stacked workspace.

:func:`load_levels` accepts the common form of a problem (a list of levels, each a non-empty
list of ``Rows`` objects, ``(A, b)`` pairs or ``(A, lo, hi)`` triples of float arrays; optional
hard rows of the same forms; optional bounds of length n), copies the rows into the buffers of a
:class:`~uvms_qp.hqp.workspace.Workspace` and checks the whole stack with a few reductions:

* every matrix entry is finite (one ``isfinite`` over the stacked rows);
* no side is NaN, no lower side is ``+inf``, no upper side is ``-inf`` (this includes an
  infinite equality target): ``sum(lo)`` is finite or ``-inf`` and ``sum(hi)`` is finite or
  ``+inf`` (NaN propagates and ``+inf + -inf`` is NaN; a finite sum that overflows only sends
  the problem to the detailed path);
* ``lo <= hi`` everywhere: ``min(hi - lo) >= 0``;
* ``Rows`` objects hold float arrays of consistent shapes, and their weights are finite and
  positive.

Anything it does not accept (another form, a shape mismatch, an empty level, a failed check)
returns None, and the caller runs :func:`~uvms_qp.hqp.problem.normalize_problem`, which raises
the detailed error naming the culprit (or, for a false alarm such as an overflowing sum, solves
the problem on the reference path).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..rows import Rows, pair_or_triple_arrays
from .workspace import Workspace

_Item = tuple[FloatArray, FloatArray, FloatArray, FloatArray | None]
_NINF: dict[int, FloatArray] = {}
_PINF: dict[int, FloatArray] = {}


def _item(item: Any) -> _Item | None:
    """``(A, lo, hi, weights)`` of one level item, or None if it is not in the common form."""
    if isinstance(item, Rows):
        A, lo, hi, w = item.A, item.lower, item.upper, item.weights
        if type(A) is not np.ndarray or type(lo) is not np.ndarray or type(hi) is not np.ndarray:
            return None
        if A.dtype.kind != "f" or (w is not None and (
                type(w) is not np.ndarray or w.shape != lo.shape or w.dtype.kind != "f")):
            return None
    elif isinstance(item, tuple | list) and len(item) in (2, 3):
        arrays = pair_or_triple_arrays(item)
        if arrays is None:
            return None
        A, lo, hi = arrays
        w = None
    else:
        return None
    if A.ndim != 2 or lo.shape != (A.shape[0],) or hi.shape != lo.shape:
        return None
    return A, lo, hi, w


def _items(level: Any, out: list[_Item]) -> int | None:
    """Append the items of one level (or of the hard rows); return its row count or None."""
    if not isinstance(level, list | tuple) or not level:
        return None
    m = 0
    for element in level:
        got = _item(element)
        if got is None:
            return None
        out.append(got)
        m += got[0].shape[0]
    return m


def _side(value: Any, n: int, cache: dict[int, FloatArray], fill: float) -> FloatArray | None:
    if value is None:
        side = cache.get(n)
        if side is None:
            side = cache[n] = np.full(n, fill)
        return side
    try:
        side = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    return side if side.shape == (n,) else None


def load_levels(
    workspace: Callable[[int, int, tuple[int, ...]], Workspace],
    levels: Sequence[Any],
    lower: Any,
    upper: Any,
    hard: Sequence[Any] | None,
) -> tuple[Workspace, FloatArray, FloatArray, FloatArray] | None:
    """Validate and load a problem in the common form; None sends it to the detailed path.

    Args:
        workspace: Returns the workspace of a structure ``(n, hard rows, level sizes)``.
        levels: Levels, highest priority first (see :func:`~uvms_qp.hqp.solve_hierarchy`).
        lower: Hard lower bounds on x or None.
        upper: Hard upper bounds on x or None.
        hard: Hard rows or None.

    Returns:
        ``(workspace, lo, hi, w)``: the rows are in ``workspace.A``; ``lo``/``hi`` are the fresh
        stacked sides ``[lower; lo_H; lo_1; ...]`` (DAQP's clamped copies written too) and
        ``w`` the level row weights.
    """
    if not isinstance(levels, list | tuple) or not levels:
        return None
    items: list[_Item] = []
    mh = 0
    if hard is not None and len(hard):
        got = _items(list(hard), items)
        if got is None:
            return None
        mh = got
    n_hard = len(items)
    sizes = []
    for level in levels:
        m = _items(level, items)
        if m is None:
            return None
        sizes.append(m)
    n = items[0][0].shape[1]
    if n == 0:
        return None
    for A, _, _, _ in items:
        if A.shape[1] != n:
            return None
    lo_box = _side(lower, n, _NINF, -np.inf)
    hi_box = _side(upper, n, _PINF, np.inf)
    if lo_box is None or hi_box is None:
        return None
    ws = workspace(n, mh, tuple(sizes))
    rows = ws.A
    r = n
    for A, _, _, _ in items:
        m = A.shape[0]
        rows[r: r + m] = A
        r += m
    sides = np.concatenate([lo_box, *[it[1] for it in items], hi_box, *[it[2] for it in items]])
    lo, hi = sides[: ws.M], sides[ws.M:]
    if not np.isfinite(rows[n:]).all():
        return None
    s_lo, s_hi = sum(lo.tolist()), sum(hi.tolist())  # Python floats: no warnings
    if not (math.isfinite(s_lo) or s_lo == -math.inf) or not (
            math.isfinite(s_hi) or s_hi == math.inf):
        return None
    if min((hi - lo).tolist()) < 0.0:
        return None
    level_items = items[n_hard:]
    if all(it[3] is None for it in level_items):
        w = ws.ones
    else:
        w = np.concatenate([it[3] if it[3] is not None else np.ones(it[0].shape[0])
                            for it in level_items])
        if not (np.isfinite(w).all() and w.min() > 0.0):
            return None
    ws.clamp(lo, hi)
    return ws, lo, hi, w
