r"""Singular-value damping of a lexicographic problem that keeps the hierarchy exact elsewhere.

A level whose rows are nearly singular in the freedom the higher levels leave (a stretched arm, a
station-keeping level that conflicts with the tool task) has an undamped least-squares optimum
that asks ``b_i / sigma_i`` along the weak direction: rates far beyond any bound for a tiny gain
in the level's residual. The box clips it to a vertex, one period of motion crosses the
singularity, and the optimum jumps to the opposite vertex: the command bangs between its bounds.

The damping here is the variable, per-direction damping of Nakamura and Hanafusa (1986) and
Maciejewski and Klein (1988), applied per level inside the hierarchy as in the damped HQP of
Escande, Mansard and Wieber (2014). For level ``k``, with ``Z`` an orthonormal basis of the
freedom left by the higher levels' active rows (in the metric ``W`` of the final regularisation,
``y = W^(1/2) x``), the level's weighted rows are scaled to unit norm (``D``, so that units and
scale drop out: a singular value is then a pure measure of how nearly the rows depend on each
other and on the higher levels) and ``D A_k W^(-1/2) Z = U S V'``. Every direction with
``sigma_i < epsilon_i`` gets one damping row appended to the level,

    lambda_i (Z v_i)' W^(1/2) x = 0,   lambda_i = c_i sqrt(epsilon_i^2 - sigma_i^2),

with ``c_i = |D^(-1) u_i|`` the rows' own scale along that direction. In the normalised units
the level then answers ``sigma_i b_i / epsilon_i^2`` along ``v_i`` instead of
``b_i / sigma_i``: bounded by ``|b_i| / epsilon_i``, continuous through the singularity, equal to
the undamped value at ``sigma_i = epsilon_i``; every other direction is untouched. Directions with
``sigma_i >= epsilon_i`` get no row: away from singularities no row is added at all and the
answer is the undamped lexicographic optimum, bit for bit.

The threshold is ``epsilon_i = max(epsilon, sqrt(dt |b_i|))``, ``b_i`` the level's demand along
the direction (normalised units, from the undamped answer). In closed loop the damped answer
moves the singular value by ``dt g sigma_i b_i / epsilon_i^2`` per period (``g``, the change of
``sigma`` per unit of motion, is of order 1 per radian in normalised units), so
``sigma_(k+1) = (1 - dt g |b_i| / epsilon_i^2) sigma_k`` near the singularity: monotone, without
the overshoot that is the chatter, when ``epsilon_i^2 >= dt g |b_i|``. The demand term keeps that
condition at large demands and long periods; ``epsilon`` is the floor.

Damping does not consume the null space: ``v_i`` lies in the row space of the level's rows in
``Z`` (``sigma_i > 0``), so any direction the level's own rows leave free to the lower levels is
orthogonal to ``v_i`` and satisfies the damping rows whatever it is. The lower levels keep
exactly the freedom ``null(A_k)`` they have without damping. Directions with ``sigma_i = 0`` (to
round-off) are not damped: the level's rows do not see them.

The active rows come from an undamped answer ``x``: every equality row, and the inequality rows
at or beyond a side (a row the level cannot satisfy counts as active). They restrict ``Z`` for
the levels below. The rows a level damps are its equality rows and the active inequality rows
that demand motion (a side that excludes zero, ``lo > 0`` or ``hi < 0``: a floor already
crossed): an inequality row that zero motion satisfies asks for no rate, and a damping row on it
would pin a direction the row leaves free once it is no longer active. Hard rows active at ``x``
restrict ``Z`` from the start; the box does not (it is what the damping keeps the rates away
from, not a kinematic constraint of the level). The active set is the undamped answer's, so an
inequality row of a higher level that a lower level pushes onto its side enters that level's
freedom: near a singularity, such a lower level can change how a higher one is damped.

Cost: a screen first tests all the levels at once against lower bounds on their singular values
(one or two Cholesky factorisations of Gram matrices of the stacked unit active rows, see
:func:`_screen`). Away from singularities it proves that no direction is weak and nothing else is
computed; otherwise the levels are examined one by one as above. What does not change between
calls (views of the level rows and sides, ``W^(1/2)``, the thresholds, and per set of active rows
the indices of the rows stacked, the buffers of the Gram matrices and, for a set whose rows
overflow the freedom, the unit rows that last passed both factorisations with their least
singular values) is kept per problem. Rows move little from one control period to the next:
while the unit rows stay within the margin of those kept (Weyl's inequality), the two
factorisations would pass and are not run (:func:`_near`). A call that the screen settles is
then about twenty numpy calls and one Python pass over the rows picked: on the demo stack (4
levels, 33 rows, 10 variables) about 150 k instructions, a third of them deciding the active rows.
A problem the screen cannot settle (rows that depend on the rows above, a level near its
threshold) costs one or two SVDs per level on top, with the bookkeeping on Python lists of the few
rows involved (the bundled demo scenario, whose ten active rows in ten variables include one that
depends on the others, takes that way on two steps in three; figures in ``docs/developer.md``).

A damped level's answer is the lexicographic optimum of the problem with the damping rows, not
of the user's problem: a certificate of the user's problem does not apply to it (see
:class:`Damping`).
"""

from __future__ import annotations

import math
import operator
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from time import perf_counter

import numpy as np

from .._validation import FloatArray
from .linalg import absolute as _absolute
from .linalg import add as _add
from .linalg import divide as _divide
from .linalg import gesdd as _GESDD
from .linalg import greater_equal as _greater_equal
from .linalg import less_equal as _less_equal
from .linalg import logical_or as _logical_or
from .linalg import max_of as _max
from .linalg import maximum as _maximum
from .linalg import minimum as _minimum
from .linalg import multiply as _multiply
from .linalg import one_blas_thread
from .linalg import potrf as _POTRF
from .linalg import sqrt as _sqrt
from .linalg import subtract as _subtract
from .problem import Problem
from .tolerances import ACTIVE_TOL, RANK_ATOL, RANK_RTOL

#: ``row is not None``, for a C-level loop over a level's rows.
_IS_SOMETHING = partial(operator.is_not, None)

#: Sets of active rows whose screen structure a problem keeps (the last few).
_KEEP = 8

#: The margin, in squared singular values of unit rows, by which a reference must clear the
#: screen's thresholds to stand for its tests (:func:`_near`).
_MARGIN = 1e-8
#: Calls that run the screen's tests after a reference is dropped, before a new one is taken.
_WAIT = 8

#: The library's damping threshold ``epsilon`` of every level (``Controller(damping=...)``): the
#: singular value of a level's unit-norm rows, in the freedom the levels above leave, below which
#: its directions are damped (dimensionless; a row at about 3 degrees from the span of the others).
DEFAULT_THRESHOLD = 0.05
#: The screen's floor on a block's smallest singular value (unit rows): below it, the block may
#: be rank deficient and the levels are examined one by one.
SCREEN_RANK = 1e-6


@dataclass(frozen=True, slots=True)
class Damping:
    """The damping rows of each level of a problem, and what they are for.

    Attributes:
        rows: Per level, the damping rows ``D_k`` (r_k, n) (targets 0, weight 1), or None for a
            level without damping (threshold 0 or no singular value below it).
        sigma_min: Per level, the smallest nonzero singular value of its unit-norm rows that
            ask for motion, in the freedom the higher levels leave (``inf`` for a level without
            such rows or without freedom; NaN below the last level with a threshold, whose
            singular values are not computed).
    """

    rows: tuple[FloatArray | None, ...]
    sigma_min: tuple[float, ...]

    @property
    def acted(self) -> bool:
        """True when at least one level got damping rows."""
        return any(map(_IS_SOMETHING, self.rows))

    @property
    def damped_levels(self) -> tuple[int, ...]:
        """Indices of the levels that got damping rows."""
        return tuple(k for k, r in enumerate(self.rows) if r is not None)


#: Per problem (while it lives), what :func:`level_damping` keeps between calls.
_SETUPS: weakref.WeakKeyDictionary[Problem, _Setup] = weakref.WeakKeyDictionary()


def _svd(M: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``U`` (m, m), singular values (descending) and ``V'`` (c, c) of ``M`` (m, c)."""
    u, s, vt, info = _GESDD(M, compute_uv=1, full_matrices=1)
    if info != 0:  # pragma: no cover - LAPACK's divide and conquer failed; the slow, sure path
        u, s, vt = np.linalg.svd(M, full_matrices=True)
    return u, s, vt


def level_damping(problem: Problem, x: FloatArray, thresholds: Sequence[float],
                  dt: float = 0.0, *, end: float = math.inf,
                  clock: Callable[[], float] = perf_counter) -> Damping | None:
    """The damping rows of every level of ``problem`` at its undamped answer ``x``.

    See the module docstring. The problem's metric ``W``, row weights, hard rows and sides are
    read from its buffers. A screen first bounds every level's singular values from below by
    those of the stacked active rows (:func:`_screen`); only when that cannot prove that no
    direction is weak are the levels examined one by one. What does not change between calls
    (the level rows' views, ``W^(1/2)``, the thresholds, and per set of active rows the indices
    and buffers of the screen) is kept for the problem while it lives.

    Args:
        problem: The problem (its box is not used).
        x: The undamped answer (n,), which fixes the active inequality rows and the demands.
        thresholds: Per level ``epsilon`` (>= 0; 0: no damping), dimensionless.
        dt: Control period [s] of the closed loop (0: no demand term in the threshold).
        end: Reading of ``clock`` [s] after which the levels are not examined one by one.
        clock: The clock of ``end``.

    Returns:
        The damping rows and the smallest singular value of each level (a lower bound on it
        when the screen proves that no level needs damping), or None when ``end`` passed
        before the levels the screen could not settle were examined.
    """
    setup = _SETUPS.get(problem)
    if (setup is None or setup.W is not problem.W or setup.dt != dt
            or (setup.thresholds is not thresholds
                and setup.thresholds != tuple(thresholds))):
        setup = _SETUPS[problem] = _Setup(problem, thresholds, dt)
    if setup.last < 0:
        return setup.undamped
    z = setup.A.dot(x, out=setup.z)
    _subtract(z, setup.sides, out=setup.B)  # [z - lo; z - hi]
    # ACTIVE_TOL max(1, max |z|): |z|^2 < 0.99 proves max |z| < 1 with a dot product (the
    # round-off of the sum is far below the gap), cheaper than the reduction
    if float(z.dot(z)) < 0.99:
        tol = ACTIVE_TOL
    else:
        largest = float(_max(_absolute(z, out=z)))
        tol = ACTIVE_TOL * largest if largest > 1.0 else ACTIVE_TOL
    setup.tol[()], setup.tol_neg[()] = tol, -tol
    # active: at or beyond a side (an equality row always; an infinite side never)
    active = _less_equal(setup.below, setup.tol, out=setup.active)
    _logical_or(active, _greater_equal(setup.above, setup.tol_neg, out=setup.scratch),
                out=active)
    root = setup.root
    hard = _active_hard(problem, x, root) if problem.mh else None
    mh = 0 if hard is None else hard.shape[0]
    key = active.tobytes()
    shape = setup.shapes.get(key if not mh else (key, mh))
    if shape is None:
        shape = setup.shape(active, mh)
    y_norm = math.sqrt(float(x.dot(x) if setup.unit_metric else x.dot(setup.W * x)))
    bounds = _screen(setup, shape, hard, y_norm)
    if bounds is not None:
        return Damping(setup.nones, tuple(bounds))
    # what each row misses, z - clip(z, lo, hi): z - lo below lo, z - hi above hi
    slack = _add(_minimum(setup.below, 0.0), _maximum(setup.above, 0.0))
    if clock() > end:
        return None
    with one_blas_thread:
        return _examine(problem, setup, x, active, slack, hard, y_norm, end, clock)


def _examine(problem: Problem, setup: _Setup, x: FloatArray, active: np.ndarray,
             slack: FloatArray, hard: FloatArray | None, y_norm: float, end: float,
             clock: Callable[[], float]) -> Damping | None:
    """The levels examined one by one (the screen could not prove that none needs damping).

    None when ``end`` passes before every level was examined.
    """
    p, last, eps, dt, root = len(problem.spans), setup.last, setup.eps, setup.dt, setup.root
    A, lo, hi = setup.A, setup.sides[0], setup.sides[1]
    # the rows that ask for motion: active, with a side that excludes zero
    demanding = (active & ((lo == hi) | (lo > 0.0) | (hi < 0.0))).tolist()
    actives = active.tolist()
    y, scaled = (x, A) if setup.unit_metric else (x * root, A / root)  # rows over y = W^(1/2) x
    norms = np.sqrt(np.einsum("ij,ij->i", scaled, scaled))
    norms[norms == 0.0] = 1.0
    unit = scaled / norms[:, None]  # unit rows: the row weights and units drop out
    slack = slack / norms  # what each row misses (normalised)
    weighted = norms * np.sqrt(problem.w[:setup.end - setup.head])  # the rows' own scale
    Z = None if hard is None else _null(hard)  # None: all the freedom
    rows: list[FloatArray | None] = [None] * p
    sigmas = [math.nan] * p
    for k, (a, b) in enumerate(setup.spans):
        if k and clock() > end:
            return None
        act = [i for i in range(a, b) if actives[i]]
        if not act or (Z is not None and Z.shape[1] == 0):
            sigmas[k] = math.inf
            continue
        M = unit.take(act, 0)
        if Z is not None:
            M = M @ Z
        d = [i for i in act if demanding[i]]  # the rows that ask for motion
        svd = None
        if d:
            same = len(d) == len(act)
            D = M if same else M[[demanding[i] for i in act]]
            yz = y if Z is None else Z.T @ y
            if same and k < last:  # the vectors are needed for the freedom below anyway
                svd = _svd(M)
                sv = svd[1]
            else:  # singular values first: the vectors only when a direction may be weak
                sv = _GESDD(D, compute_uv=0)[1]
            values = sv.tolist()
            r = _rank(values)
            sigmas[k] = values[r - 1] if r else math.inf
            slack_d = slack.take(d)
            if r and _may_be_weak(values[:r], eps[k], dt, math.sqrt(float(yz.dot(yz))),
                                  math.sqrt(float(slack_d.dot(slack_d)))):
                u, sv, vt = svd if svd is not None else _svd(D)
                rows[k] = _damping_rows(eps[k], dt, u, sv, vt, r, weighted.take(d), Z, root,
                                        slack_d, yz)
        else:
            sigmas[k] = math.inf
        if k < last:
            if svd is None:
                svd = _svd(M)
            null = svd[2][_rank(svd[1].tolist()):].T
            Z = null if Z is None else Z @ null
    return Damping(tuple(rows), tuple(sigmas))


def _may_be_weak(s: list[float], eps: float, dt: float, y_norm: float, slack_norm: float) -> bool:
    """Whether a singular value may be below its threshold, from bounds on the demands.

    The demand along direction ``i`` is ``s_i v_i' Z' y - u_i' slack`` (see
    :func:`_damping_rows`), at most ``s_i |Z' y| + |slack|`` in size; a direction with
    ``s_i^2 >= max(eps^2, dt (s_i |Z' y| + |slack|))`` is not weak whatever its vectors.
    """
    if eps <= 0.0:
        return False
    floor = eps * eps
    return any(v * v < max(floor, dt * (v * y_norm + slack_norm)) for v in s)


def _needed(eps: float, dt: float, y_norm: float, slack_norm: float) -> float:
    """The least singular value that is not weak whatever the direction's vectors.

    ``max(eps, s*)`` with ``s*`` the positive root of ``s^2 = dt (s |y| + |slack|)``: above
    both, ``s^2 >= max(eps^2, dt (s |Z' y| + |slack|))`` (:func:`_may_be_weak`).
    """
    t = dt * y_norm
    return max(eps, 0.5 * (t + math.sqrt(t * t + 4.0 * dt * slack_norm)))


def _unit(rows: FloatArray, root: FloatArray) -> FloatArray:
    """``rows`` over ``y = W^(1/2) x`` scaled to unit norm (zero rows stay zero)."""
    scaled = rows / root
    norms = np.sqrt(np.einsum("ij,ij->i", scaled, scaled))
    norms[norms == 0.0] = 1.0
    return np.asarray(scaled / norms[:, None], dtype=np.float64)


def _above(G: FloatArray, floor2: FloatArray | float, diag: FloatArray | None = None) -> bool:
    """Whether ``G - diag(floor2)`` is positive definite (``G`` is overwritten).

    With ``G`` the Gram matrix of a block of rows ``R`` (``R R'`` for a wide block, with
    ``floor2 = floor^2 D^2``, ``D`` its row norms; ``R' D^-2 R`` for a tall one, with
    ``floor2 = floor^2``): every singular value of the unit rows ``D^-1 R`` (the ``min(m, n)``
    of them) exceeds ``floor``. A Cholesky factorisation succeeds exactly when the matrix is
    positive definite. ``diag``: a view of ``G``'s diagonal the caller keeps (default: made
    here, ``G`` contiguous).
    """
    if diag is None:
        diag = G.reshape(-1)[::G.shape[0] + 1]
    _subtract(diag, floor2, out=diag)
    return bool(_POTRF(G, 0, 0, 1)[1] == 0)


class _Setup:
    """What :func:`level_damping` reads of one problem for given thresholds.

    Views of the level rows and sides down to the last level with a threshold, ``W^(1/2)``,
    the thresholds as floats, buffers, and the screen's structure per set of active rows
    (:class:`_Active`, the last few).
    """

    __slots__ = ("A", "B", "W", "above", "active", "below", "dt", "end", "eps", "head", "last",
                 "n", "nones", "root", "scratch", "shapes", "sides", "spans", "tail",
                 "thresholds", "tol", "tol_neg", "undamped", "unit_metric", "z")

    def __init__(self, problem: Problem, thresholds: Sequence[float], dt: float) -> None:
        p = len(problem.spans)
        self.W, self.dt, self.n = problem.W, dt, problem.n
        self.thresholds = tuple(thresholds)
        self.last = last = max((k for k, e in enumerate(self.thresholds) if e > 0.0),
                               default=-1)
        self.nones = (None,) * p
        self.undamped = Damping(self.nones, (math.nan,) * p)
        self.tail = (math.nan,) * (p - last - 1)
        self.head = head = problem.head
        self.end = end = problem.spans[last][1] if last >= 0 else head
        self.A = problem.A[head:end]
        self.sides = problem.sides[:, head:end]
        self.root = np.sqrt(problem.W)
        self.unit_metric = bool((problem.W == 1.0).all())  # y = x: nothing to scale
        self.eps = [float(e) for e in self.thresholds[:last + 1]]
        self.spans = [(a - head, b - head) for a, b in problem.spans[:last + 1]]
        self.z = np.empty(end - head)
        self.tol, self.tol_neg = np.empty(()), np.empty(())  # of the active rows, and -tol
        self.B = np.empty((2, end - head))
        self.below, self.above = self.B  # z - lo, z - hi
        self.active = np.empty(end - head, dtype=bool)
        self.scratch = np.empty(end - head, dtype=bool)
        self.shapes: dict[object, _Active] = {}

    def shape(self, active: np.ndarray, mh: int) -> _Active:
        """The screen's structure for the active rows ``active`` and ``mh`` active hard rows."""
        if len(self.shapes) >= _KEEP:
            self.shapes.clear()
        key = active.tobytes()
        shape = self.shapes[key if not mh else (key, mh)] = _Active(self, active, mh)
        return shape


class _Active:
    """The screen's structure for one set of active rows (see :func:`_screen`).

    Which rows it stacks, which levels each test covers, its buffers, and the unit rows that
    last passed both tests with their least singular values (:func:`_near`).
    """

    __slots__ = ("both", "column", "delta", "delta_flat", "diag", "fit", "fit_active", "fit_sides",
                 "fit_span", "floored", "gram", "idx", "lead", "lead_diag", "levels", "mh",
                 "mine", "need2", "norms", "plan", "plan_eps", "reference", "rows", "shift",
                 "tall", "tall_diag", "template", "unit", "used", "wait")

    def __init__(self, setup: _Setup, active: np.ndarray, mh: int) -> None:
        n, spans, eps = setup.n, setup.spans, setup.eps
        p = len(spans)
        act = active.tolist()
        self.mh = mh
        counts = [sum(act[a:b]) for a, b in spans]  # active rows per level
        fit, used = 0, mh  # the levels whose active rows, with those above, fit in n rows
        while fit < p and used + counts[fit] <= n:
            used += counts[fit]
            fit += 1
        self.fit, self.used = fit, used
        # down to the level that overflows, if one does
        self.idx = np.flatnonzero(active[:spans[min(fit, p - 1)][1]])
        self.both = np.concatenate((self.idx, self.idx + active.size))  # in [z - lo; z - hi]
        k = mh + self.idx.size
        self.rows = np.empty((k, n))  # the active hard rows, then the level rows picked
        self.mine = self.rows[mh:]
        self.gram = np.empty((k, k))
        self.diag = self.gram.reshape(-1)[::k + 1]
        self.lead = self.gram[:used, :used]
        self.lead_diag = self.diag[:used]
        self.norms = np.empty(k)
        self.column = self.norms[:, None]
        self.unit = np.empty((k, n))
        self.tall = np.empty((n, n))
        self.tall_diag = self.tall.reshape(-1)[::n + 1]
        levels, start = [], mh  # (level, first row in the stack, active rows)
        for j in range(min(fit + 1, p)):
            levels.append((j, start, counts[j]))
            start += counts[j]
        self.levels = levels
        self.floored = [j for j in range(fit) if counts[j] and eps[j] > 0.0]
        self.shift = np.empty(used)  # floor^2 times the squared norms of the leading rows
        self.need2 = np.empty(())
        # the unit rows that last passed both tests and their least singular values (leading
        # rows, stack), for the calls after (:func:`_near`)
        self.reference: tuple[FloatArray, float, float] | None = None
        self.wait = 0
        self.delta = np.empty((k, n))
        self.delta_flat = self.delta.reshape(-1)
        # the levels that fit, each with a threshold and active rows, by their rows in the
        # level rows picked; the largest threshold among them; the rows of the level after
        self.plan = [(start - mh, start - mh + c) for j, start, c in levels[:fit]
                     if c and eps[j] > 0.0]
        self.plan_eps = max((eps[j] for j in self.floored), default=0.0)
        if fit < p:
            _, start, c = levels[fit]
            self.fit_span = (start - mh, start - mh + c)
        self.template = [math.inf] * p + [math.nan] * len(setup.tail)  # the bounds
        if fit < p:
            a, b = spans[fit]
            self.fit_sides = (setup.sides[0, a:b], setup.sides[1, a:b])
            self.fit_active = act[a:b]


def _screen(setup: _Setup, shape: _Active, hard: FloatArray | None, y_norm: float
            ) -> list[float] | None:
    """Lower bounds on each level's singular values when they prove that no level needs damping.

    The singular values of a level's rows in the freedom ``Z`` the rows above it leave are
    bounded from below by those of all the rows down to it stacked: with ``H`` the rows above,
    ``min_u_H |H' u_H + A_k' u| = |Z Z' A_k' u|``, so ``sigma_min([H; A_k]) <= sigma_min(A_k Z)``
    (for a stack of more than ``n`` rows, its ``n``-th value bounds the ``dim Z``-th of
    ``A_k Z``), and a stack of at most ``n`` rows only loses in its smallest value when rows are
    added (interlacing), as the rows that ask for motion gain against all the active rows. So
    one test of the unit active rows (the active hard rows first) of the levels that fit in
    ``n`` rows bounds all of them; the level whose rows overflow the freedom left is tested with
    the rows above it (its rows that ask for motion too, when they are fewer), and when those
    rows have rank ``n`` the levels below have no freedom. Each test is a Cholesky
    factorisation of a Gram matrix (:func:`_above`) at the least value that rules out a weak
    direction of every level it covers (:func:`_needed`, with the largest threshold and slack of
    the levels it covers: ``_needed`` grows with both, so that is the largest of their values).
    When the rows overflow and stay near the unit rows that last passed both tests, the kept
    singular values prove the two tests (:func:`_near`) and they are not run.

    Args:
        setup: The problem's views, thresholds and buffers.
        shape: The structure of this set of active rows (``setup.active``); ``setup.below``
            and ``setup.above`` hold ``z - lo`` and ``z - hi`` of the level rows.
        hard: The active hard rows (unit, over ``y``), or None.
        y_norm: ``|W^(1/2) x|``.

    Returns:
        Per level of the problem a proven lower bound on its smallest singular value (``inf``
        for a level without active rows in the freedom left, NaN below the last level with a
        threshold), or None when the tests cannot prove that no level needs damping.
    """
    n, p, mh = setup.n, len(setup.spans), shape.mh
    rows, gram = shape.rows, shape.gram
    if mh:
        rows[:mh] = hard
    setup.A.take(shape.idx, 0, out=shape.mine)
    if not setup.unit_metric:
        _divide(shape.mine, setup.root, out=shape.mine)  # rows over y
    if gram.size:
        rows.dot(rows.T, out=gram)
    squares = shape.diag.tolist()  # squared row norms
    if not all(squares):
        return None  # a zero active row
    values = setup.B.take(shape.both).tolist()  # z - lo, then z - hi, of the level rows picked
    k = shape.idx.size
    # what each of them misses (z - lo below lo, z - hi above hi) over its norm, squared: the
    # sum over a level's rows is the square of its slack in unit rows
    terms = [(v * v if v < 0.0 else w * w if w > 0.0 else 0.0) / q for v, w, q in
             zip(values[:k], values[k:], squares[mh:], strict=True)]
    floor = need = SCREEN_RANK  # the least value the directions may have (see _needed)
    eps, dt = setup.eps, setup.dt
    if shape.plan:  # the levels that fit: the largest threshold and slack of them
        own = max([sum(terms[a:b]) for a, b in shape.plan])
        floor = max(SCREEN_RANK, _needed(shape.plan_eps, dt, y_norm, math.sqrt(own)))
    fit, used = shape.fit, shape.used
    overflow = fit < p and used < n  # a level overflows the freedom the ones above leave
    if overflow:  # its test takes the unit rows, before the leading block is shifted
        if eps[fit] > 0.0:
            a, b = shape.fit_span
            need = max(SCREEN_RANK, _needed(eps[fit], dt, y_norm, math.sqrt(sum(terms[a:b]))))
        _sqrt(shape.diag, out=shape.norms)
        unit = _divide(rows, shape.column, out=shape.unit)
        reference = shape.reference
        proven = reference is not None and _near(shape, reference, unit, floor, need)
    else:
        proven = False
    if used and not proven:  # the leading block minus floor^2 times its row norms squared
        lead = shape.lead_diag
        if not _above(shape.lead, _multiply(lead, floor * floor, out=shape.shift), lead):
            return None
    bounds = shape.template.copy()
    for k in shape.floored:
        bounds[k] = floor
    if not overflow:  # every level fits, or no freedom below
        return bounds
    if not proven:
        tall = unit.T.dot(unit, out=shape.tall)
        need2 = shape.need2
        need2[()] = need * need
        if not _above(tall.T, need2, shape.tall_diag):  # rank n: no freedom below
            return None
        _refer(shape, unit)
    if eps[fit] > 0.0:
        low, high = shape.fit_sides
        if low.tobytes() != high.tobytes():  # not every row an equality: which ask for motion
            asks = [lo == hi or lo > 0.0 or hi < 0.0 for lo, hi, on in
                    zip(low.tolist(), high.tolist(), shape.fit_active, strict=True) if on]
            if not all(asks):  # fewer rows ask for motion: test them with the rows above
                if not any(asks):
                    need = math.inf
                else:
                    picked = unit[np.flatnonzero([True] * used + asks)]
                    G = (picked.dot(picked.T) if picked.shape[0] <= n
                         else picked.T.dot(picked))
                    if not _above(G, need * need):
                        return None
        bounds[fit] = need
    return bounds


def _near(shape: _Active, reference: tuple[FloatArray, float, float], unit: FloatArray,
          floor: float, need: float) -> bool:
    """Whether the unit rows are close enough to the shape's reference to pass both tests.

    The singular values of the unit rows move by at most ``e = |U - U_ref|_F`` from those of
    the reference (Weyl), so the leading rows' smallest is above ``s_lead - e`` and the stack's
    ``n``-th above ``s_tall - e``. When those clear ``floor`` and ``need`` by ``_MARGIN`` (in
    squares: far above the round-off of a Cholesky factorisation of unit rows), the two tests
    of :func:`_screen` pass, and they are not run. Otherwise the reference is dropped.
    """
    rows, lead, tall = reference
    _subtract(unit, rows, out=shape.delta)
    delta = shape.delta_flat
    e = math.sqrt(float(delta.dot(delta)))
    low, high = lead - e, tall - e
    if high > 0.0 and high * high > need * need + _MARGIN and (
            not shape.used or (low > 0.0 and low * low > floor * floor + _MARGIN)):
        return True
    shape.reference = None
    return False


def _refer(shape: _Active, unit: FloatArray) -> None:
    """Keep the unit rows that passed both tests and their least singular values (:func:`_near`).

    Not on every call: after a reference is dropped, the next ``_WAIT`` calls that pass run the
    tests without taking a new one (a reference that does not stand costs two SVDs).
    """
    if shape.reference is not None:
        return
    if shape.wait:
        shape.wait -= 1
        return
    shape.wait = _WAIT
    n, used = unit.shape[1], shape.used
    _, values, _, info = _GESDD(unit, compute_uv=0)
    lead = math.inf  # (no leading rows: not read)
    if used and not info:
        _, lead_values, _, info = _GESDD(unit[:used], compute_uv=0)
        lead = float(lead_values[used - 1])
    if not info:
        shape.reference = (unit.copy(), lead, float(values[n - 1]))


def _active_hard(problem: Problem, x: FloatArray, root: FloatArray) -> FloatArray:
    """The hard rows active at ``x``, scaled to unit norm over ``y = W^(1/2) x``."""
    n, head = problem.n, problem.head
    H, lo, hi = problem.A[n:head], problem.lo[n:head], problem.hi[n:head]
    z = H @ x
    tol = ACTIVE_TOL * problem.hard_scale
    rows = _unit(H[(lo == hi) | (z - lo <= tol) | (hi - z <= tol)], root)
    return np.asarray(rows[np.einsum("ij,ij->i", rows, rows) > 0.0], dtype=np.float64)


def _null(rows: FloatArray) -> FloatArray | None:
    """Orthonormal basis of the freedom ``rows`` leave (None: all of it, no rows)."""
    if rows.shape[0] == 0:
        return None
    _, s, vt = _svd(rows)
    return np.asarray(vt[_rank(s.tolist()):].T, dtype=np.float64)


def _damping_rows(eps: float, dt: float, u: FloatArray, s: FloatArray, vt: FloatArray, r: int,
                  weighted: FloatArray, Z: FloatArray | None, root: FloatArray,
                  slack: FloatArray, yz: FloatArray) -> FloatArray | None:
    """The damping rows of one level (None when no direction is below its threshold).

    ``u, s, vt``: SVD of the level's unit rows that ask for motion, in the freedom ``Z`` (rank
    ``r``); ``weighted`` the norms of those rows weighted (over ``y``), ``slack`` what they miss
    at the undamped answer (normalised) and ``yz = Z' W^(1/2) x`` the undamped answer in ``Z``.
    """
    # the demand along each direction, from the undamped answer (normalised units): what the
    # level's rows achieve there plus what they miss
    demand = s[:r] * (vt[:r] @ yz) - u[:, :r].T @ slack
    limit = np.maximum(eps * eps, dt * np.abs(demand))
    weak = np.flatnonzero(s[:r] * s[:r] < limit)
    if weak.size == 0:
        return None
    scale = np.linalg.norm(u[:, weak] * weighted[:, None], axis=0)  # the rows' own units
    lam = scale * np.sqrt(limit[weak] - s[weak] * s[weak])
    directions = vt[weak] if Z is None else vt[weak] @ Z.T  # (r_w, n) in y
    return np.asarray(lam[:, None] * directions * root, dtype=np.float64)


def _rank(values: list[float]) -> int:
    """Number of singular values (descending) above the rank tolerance."""
    if not values:
        return 0
    tol = max(RANK_ATOL, RANK_RTOL * values[0])
    return sum(v > tol for v in values)
