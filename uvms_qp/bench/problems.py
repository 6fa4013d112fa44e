"""Seeded families of degenerate lexicographic problems, as plain matrices.

Each family isolates one way a problem can be hard for a back-end, on top of a well-conditioned
random base (``n`` in 6..30; 2-4 levels of unit-norm rows mixing equality and inequality rows;
a box that is ``wide`` (targets reachable inside it), ``tight`` (width 0.02..0.3, so bounds are
active) or ``saturated`` (targets far outside, every level pushed against the box)):

* ``well``: the base itself.
* ``repeated``: a row of a higher level repeated in a lower level, with the same target
  (``same``) or a conflicting one (``conflict``), possibly scaled.
* ``zero_row``: a zero row, or a row of norm 1e-12..1e-8, with a nonzero target in a level.
* ``near_singular``: a level of condition 1e6..1e10 (``cond``), or two rows 1e-7 rad apart with
  different targets (``angle``).
* ``ill_conditioned``: a 2 x 2 level of condition about 2e4 (``cond``), or row norms spread over
  1e-3..1e3 (``spread``).
* ``no_box_repeat``: a lower level repeating a row of a higher one with no box on some or all
  variables (the canonical case: level 0 ``x1 + 2 x2 = 10``, level 1 the same row ``= 1``).
* ``scaled_rows`` (:data:`SCALE_FAMILIES`): every row of one level and its sides multiplied by
  1e4..2e5 (targets near 1e5, ``large``), or a row of norm 1e-15..1e-13 with a target of order 1
  added to level 0 (``tiny``): the answer must not depend on the units of a level's rows.
* ``shared_yaw``, ``shared_joint``, ``singular``: controller problems on random BlueROV2 Heavy +
  Reach Alpha 5 states (:func:`controller_family`): station keeping with yaw above current
  alignment; a joint-limit margin above a posture task; the demo stack at a singular arm with
  the vehicle pitched 89.99 deg.

A :class:`FamilyProblem` carries its levels as ``(A, lo, hi, w)`` blocks, the box and the hard
rows; :meth:`FamilyProblem.stacked` gives the stacked layout ``(A, lo, hi, n, mh, sizes, w)`` of
``docs/developer.md`` and :meth:`FamilyProblem.levels_rows` the input of
:func:`uvms_qp.hqp.solve_hierarchy`. The tests and the benchmark share these generators.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from ..controller import Controller
from ..model import load_model
from ..rows import Rows
from ..stack import Level, Stack
from ..tasks import (
    CurrentAlignmentTask,
    EndEffectorTask,
    JointLimitMarginTask,
    PostureTask,
    StationKeepingTask,
    VehicleMotionTask,
)
from .sets import _singular_configuration
from .stacks import demo_stack

#: Plain-matrix families, in the order of the issue's table.
MATRIX_FAMILIES: tuple[str, ...] = ("well", "repeated", "zero_row", "near_singular",
                                    "ill_conditioned", "no_box_repeat")
#: Plain-matrix families of rows in other units (not in the certified-families table).
SCALE_FAMILIES: tuple[str, ...] = ("scaled_rows",)
#: Controller families (BlueROV2 Heavy + Reach Alpha 5).
CONTROLLER_FAMILIES: tuple[str, ...] = ("shared_yaw", "shared_joint", "singular")
BOX_KINDS: tuple[str, ...] = ("wide", "tight", "saturated")

Block = tuple[FloatArray, FloatArray, FloatArray, FloatArray]


@dataclass
class FamilyProblem:
    """One problem of a family.

    Attributes:
        family: Family name.
        variant: Variant within the family (e.g. ``"conflict"``), or the box kind.
        seed: Seed of the draw.
        n: Number of variables.
        levels: One ``(A, lo, hi, w)`` block per level, highest priority first.
        lower: Box lower bounds (``-inf`` allowed).
        upper: Box upper bounds (``+inf`` allowed).
        hard: Hard rows ``(A, lo, hi)`` (zero rows allowed).
        box: Box kind (``"wide"``, ``"tight"``, ``"saturated"``, ``"none"``, ``"partial"``).
    """

    family: str
    variant: str
    seed: int
    n: int
    levels: list[Block]
    lower: FloatArray
    upper: FloatArray
    hard: tuple[FloatArray, FloatArray, FloatArray] = field(default=None)  # type: ignore
    box: str = "wide"

    def __post_init__(self) -> None:
        if self.hard is None:
            self.hard = (np.zeros((0, self.n)), np.zeros(0), np.zeros(0))

    @property
    def name(self) -> str:
        """``family/variant/box/seed``."""
        return f"{self.family}/{self.variant}/{self.box}/{self.seed}"

    def levels_rows(self) -> list[list[Rows]]:
        """Levels as :class:`~uvms_qp.rows.Rows` (weights kept) for ``solve_hierarchy``."""
        return [[Rows(A, lo, hi, w, f"level {k}")] for k, (A, lo, hi, w) in
                enumerate(self.levels)]

    def hard_rows(self) -> list[Rows] | None:
        """Hard rows as a list for ``solve_hierarchy`` (None when there are none)."""
        A, lo, hi = self.hard
        return [Rows(A, lo, hi, None, "hard")] if A.shape[0] else None

    def stacked(self) -> tuple[FloatArray, FloatArray, FloatArray, int, int, tuple[int, ...],
                               FloatArray]:
        """The stacked layout ``(A, lo, hi, n, mh, sizes, w)``."""
        n = self.n
        HA, Hlo, Hhi = self.hard
        A = np.vstack([np.eye(n), HA, *[b[0] for b in self.levels]])
        lo = np.concatenate([self.lower, Hlo, *[b[1] for b in self.levels]])
        hi = np.concatenate([self.upper, Hhi, *[b[2] for b in self.levels]])
        w = np.concatenate([b[3] for b in self.levels])
        return A, lo, hi, n, HA.shape[0], tuple(b[0].shape[0] for b in self.levels), w


# ------------------------------------------------------------------------------- the base
def _unit_rows(rng: np.random.Generator, m: int, n: int) -> FloatArray:
    A = rng.standard_normal((m, n))
    return A / np.linalg.norm(A, axis=1, keepdims=True)


def _box(rng: np.random.Generator, n: int, kind: str) -> tuple[FloatArray, FloatArray,
                                                              FloatArray]:
    """Box bounds and a centre point ``x0`` inside them."""
    x0 = rng.uniform(-1.0, 1.0, n)
    if kind == "tight":
        half = rng.uniform(0.01, 0.15, n)
    elif kind == "saturated":
        half = rng.uniform(0.05, 0.3, n)
    else:
        half = rng.uniform(2.0, 5.0, n)
    return x0 - half, x0 + half, x0


def _level(rng: np.random.Generator, A: FloatArray, x_t: FloatArray, ineq_share: float
           ) -> Block:
    """Sides for rows ``A`` around the target point ``x_t``: equality or one/two-sided rows."""
    m = A.shape[0]
    y = A @ x_t + rng.normal(scale=0.05, size=m)
    lo, hi = y.copy(), y.copy()
    for i in range(m):
        if rng.uniform() < ineq_share:
            kind = rng.integers(3)
            width = rng.uniform(0.0, 0.5)
            if kind == 0:
                lo[i] = -np.inf
            elif kind == 1:
                hi[i] = np.inf
            else:
                lo[i], hi[i] = y[i] - width, y[i] + width
    return A, lo, hi, np.ones(m)


def base_problem(rng: np.random.Generator, n: int, box: str, n_levels: int | None = None,
                 ineq_share: float = 0.3) -> tuple[list[Block], FloatArray, FloatArray]:
    """A well-conditioned random problem: unit rows, level sizes summing to about ``1.5 n``."""
    lower, upper, x0 = _box(rng, n, box)
    p = int(n_levels or rng.integers(2, 5))
    total = max(p, int(rng.integers(n // 2, 2 * n)))
    cuts: Any = (np.sort(rng.choice(np.arange(1, total), size=p - 1, replace=False))
                 if p > 1 else [])
    sizes = np.diff(np.concatenate(([0], cuts, [total]))).astype(int)
    spread = {"wide": 1.0, "tight": 0.5, "saturated": 4.0}[box]
    levels = []
    for m in sizes:
        x_t = x0 + rng.normal(scale=spread, size=n)  # each level its own target point
        levels.append(_level(rng, _unit_rows(rng, int(m), n), x_t, ineq_share))
    return levels, lower, upper


def _with_row(block: Block, a: FloatArray, lo: float, hi: float, rng: np.random.Generator,
              w: float = 1.0) -> Block:
    A, L, U, W = block
    i = int(rng.integers(A.shape[0] + 1))
    return (np.insert(A, i, a, axis=0), np.insert(L, i, lo), np.insert(U, i, hi),
            np.insert(W, i, w))


# ------------------------------------------------------------------------------- families
def _repeated(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    levels, lower, upper = base_problem(rng, n, box)
    j = int(rng.integers(len(levels) - 1))
    k = int(rng.integers(j + 1, len(levels)))
    A, lo, hi, _ = levels[j]
    i = int(rng.integers(A.shape[0]))
    c = float(rng.choice([1.0, -1.0, 2.0, 0.5]))
    a = c * A[i]
    if variant == "same":
        lo_r, hi_r = sorted((c * lo[i], c * hi[i]))
    else:
        side = float(np.where(np.isfinite(lo[i]), lo[i], hi[i]))
        t = c * side + rng.uniform(0.5, 3.0) * rng.choice([-1.0, 1.0])
        lo_r = hi_r = t
    levels[k] = _with_row(levels[k], a, lo_r, hi_r, rng)
    return FamilyProblem("repeated", variant, 0, n, levels, lower, upper, box=box)


def _zero_row(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    levels, lower, upper = base_problem(rng, n, box)
    k = int(rng.integers(len(levels)))
    a = np.zeros(n) if variant == "zero" else _unit_rows(rng, 1, n)[0] * 10.0 ** rng.uniform(
        -12, -8)
    t = rng.uniform(0.5, 2.0) * rng.choice([-1.0, 1.0])
    lo_r, hi_r = (t, t) if rng.uniform() < 0.7 else (abs(t), np.inf)
    levels[k] = _with_row(levels[k], a, lo_r, hi_r, rng)
    return FamilyProblem("zero_row", variant, 0, n, levels, lower, upper, box=box)


def _near_singular(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    levels, lower, upper = base_problem(rng, n, box, ineq_share=0.2)
    k = int(rng.integers(len(levels)))
    A = levels[k][0]
    m = max(2, min(A.shape[0], n - 1))
    if variant == "cond":
        cond = 10.0 ** rng.uniform(6, 10)
        U, _ = np.linalg.qr(rng.standard_normal((m, m)))
        V, _ = np.linalg.qr(rng.standard_normal((n, m)))
        sv = np.logspace(0, -math.log10(cond), m)
        Ak = (U * sv) @ V.T
        x_t = rng.normal(size=n)
        y = Ak @ x_t + rng.normal(scale=0.05, size=m)
        levels[k] = (Ak, y.copy(), y.copy(), np.ones(m))
    else:
        a = _unit_rows(rng, 1, n)[0]
        v = rng.standard_normal(n)
        v -= (v @ a) * a
        v /= np.linalg.norm(v)
        theta = 1e-7
        b = math.cos(theta) * a + math.sin(theta) * v
        t1 = float(rng.normal())
        t2 = t1 + rng.uniform(0.1, 1.0) * rng.choice([-1.0, 1.0])
        levels[k] = _with_row(_with_row(levels[k], a, t1, t1, rng), b, t2, t2, rng)
    return FamilyProblem("near_singular", variant, 0, n, levels, lower, upper, box=box)


def _ill_conditioned(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    levels, lower, upper = base_problem(rng, n, box)
    k = int(rng.integers(len(levels)))
    if variant == "cond":
        # a 2 x 2 level of condition ~2e4 on two of the variables
        i, j = rng.choice(n, size=2, replace=False)
        eps = 1.0 / 2e4 * 2.0
        A2 = np.zeros((2, n))
        A2[0, [i, j]] = [1.0, 1.0]
        A2[1, [i, j]] = [1.0, 1.0 + eps]
        y = A2 @ rng.normal(scale=0.5, size=n) + rng.normal(scale=0.1, size=2)
        levels[k] = (A2, y.copy(), y.copy(), np.ones(2))
    else:
        A, lo, hi, w = levels[k]
        s = 10.0 ** rng.uniform(-3, 3, A.shape[0])
        levels[k] = (A * s[:, None], lo * s, hi * s, w)
    return FamilyProblem("ill_conditioned", variant, 0, n, levels, lower, upper, box=box)


def _no_box_repeat(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    if variant == "canonical":
        a = np.array([[1.0, 2.0]])
        levels = [(a, np.array([10.0]), np.array([10.0]), np.ones(1)),
                  (a.copy(), np.array([1.0]), np.array([1.0]), np.ones(1))]
        return FamilyProblem("no_box_repeat", variant, 0, 2, levels, np.full(2, -np.inf),
                             np.full(2, np.inf), box="none")
    p = _repeated(rng, n, "wide", "conflict")
    free = rng.uniform(size=n) < (1.0 if variant == "none" else 0.4)
    free[int(rng.integers(n))] = True
    p.lower[free], p.upper[free] = -np.inf, np.inf
    p.family, p.variant, p.box = "no_box_repeat", variant, "none" if free.all() else "partial"
    return p


def _well(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    levels, lower, upper = base_problem(rng, n, box)
    return FamilyProblem("well", variant, 0, n, levels, lower, upper, box=box)


def _scaled_rows(rng: np.random.Generator, n: int, box: str, variant: str) -> FamilyProblem:
    levels, lower, upper = base_problem(rng, n, box)
    if variant == "large":
        k = int(rng.integers(len(levels)))
        A, lo, hi, w = levels[k]
        s = 10.0 ** rng.uniform(4, 5.3, A.shape[0])
        levels[k] = (A * s[:, None], lo * s, hi * s, w)
    else:
        a = _unit_rows(rng, 1, n)[0] * 10.0 ** rng.uniform(-15, -13)
        t = rng.uniform(0.5, 2.0) * rng.choice([-1.0, 1.0])
        lo_r, hi_r = (t, t) if rng.uniform() < 0.7 else (abs(t), np.inf)
        levels[0] = _with_row(levels[0], a, lo_r, hi_r, rng)
    return FamilyProblem("scaled_rows", variant, 0, n, levels, lower, upper, box=box)


_MATRIX: dict[str, tuple[Callable[..., FamilyProblem], tuple[str, ...]]] = {
    "well": (_well, ("base",)),
    "repeated": (_repeated, ("same", "conflict")),
    "zero_row": (_zero_row, ("zero", "tiny")),
    "near_singular": (_near_singular, ("cond", "angle")),
    "ill_conditioned": (_ill_conditioned, ("cond", "spread")),
    "no_box_repeat": (_no_box_repeat, ("canonical", "partial", "none")),
    "scaled_rows": (_scaled_rows, ("large", "tiny")),
}


def matrix_problem(family: str, seed: int) -> FamilyProblem:
    """One problem of a plain-matrix family, deterministic in ``(family, seed)``."""
    make, variants = _MATRIX[family]
    rng = np.random.default_rng([seed, (MATRIX_FAMILIES + SCALE_FAMILIES).index(family),
                                 0xCE47])
    variant = str(variants[seed % len(variants)])
    n = int(rng.integers(6, 31))
    box = str(BOX_KINDS[int(rng.integers(3))])
    p = make(rng, n, box, variant)
    p.seed = seed
    return p


def family(name: str, count: int, seed: int = 0, models: dict[str, Any] | None = None
           ) -> list[FamilyProblem]:
    """``count`` problems of family ``name`` with seeds ``seed .. seed + count - 1``."""
    if name in _MATRIX:
        return [matrix_problem(name, seed + i) for i in range(count)]
    if name in CONTROLLER_FAMILIES:
        return [controller_problem(name, seed + i, models) for i in range(count)]
    raise KeyError(f"unknown family {name!r}; known: "
                   f"{', '.join(MATRIX_FAMILIES + SCALE_FAMILIES + CONTROLLER_FAMILIES)}")


# ---------------------------------------------------------------------------- controller
def controller_stack(name: str, target: list[float]) -> Any:
    """The stack of a controller family, its end-effector task (level 0) aimed at ``target``.

    ``shared_yaw`` and ``shared_joint`` (else the demo stack), under the families' bounds;
    ``target`` [m, world].
    """
    bounds = [JointPositionBounds(gain=0.5), JointVelocityBounds(),
              VehicleRateBounds(linear=0.5, angular=0.3)]
    if name == "shared_yaw":
        return Stack(levels=[
            Level(EndEffectorTask(position=target, gain=2.0)),
            Level(StationKeepingTask(gain=1.0)),  # x, y, z, psi: holds the yaw row
            Level(CurrentAlignmentTask(heading=0.78, gain=0.5)),  # the same yaw row
            Level(VehicleMotionTask(beta=0.8), PostureTask(gain=0.2)),
        ], constraints=bounds)
    if name == "shared_joint":
        return Stack(levels=[
            Level(EndEffectorTask(position=target, gain=2.0)),
            Level(JointLimitMarginTask(margin=0.1, gain=2.0)),  # joint-rate rows
            Level(PostureTask(gain=0.2)),  # the same joint-rate rows
        ], constraints=bounds)
    return demo_stack(position=target)


def controller_problem(name: str, seed: int, models: dict[str, Any] | None = None
                       ) -> FamilyProblem:
    """One control problem of a controller family on a random BlueROV2 state.

    The tool target is the tool position plus a normal draw of 0.3 m; ``singular`` draws the
    arm configuration with the smallest position-Jacobian singular value out of 24 and pitches
    the vehicle to 89.99 deg. Rows and box come from today's
    :class:`~uvms_qp.controller.Controller` (``level_rows`` and ``bounds``).
    """
    cache = models if models is not None else {}
    model = cache.get("bluerov2_heavy_alpha5")
    if model is None:
        model = cache["bluerov2_heavy_alpha5"] = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng([seed, CONTROLLER_FAMILIES.index(name), 0xB10E])
    if name == "singular":
        q = _singular_configuration(model, rng)
        eta, joints = model.split(q)
        eta[4] = math.radians(89.99)
        q = model.configuration(eta, joints)
    else:
        q = model.random_configuration(rng)
    state = model.state(q)
    target = state.position("tool") + rng.normal(scale=0.3, size=3)
    stack = controller_stack(name, [float(v) for v in target])
    ctrl = Controller(model, stack, dt=float(rng.choice([0.01, 0.05, 0.1])))
    rows = ctrl.level_rows(state, 0.0)
    lower, upper = ctrl.bounds(state)
    levels = [(r.A.copy(), r.lower.copy(), r.upper.copy(),
               r.weights.copy() if r.weights is not None else np.ones(r.m)) for r in rows]
    return FamilyProblem(name, "bluerov2", seed, int(model.nv), levels, lower, upper, box="rate")
