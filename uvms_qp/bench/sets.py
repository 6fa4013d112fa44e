"""Benchmark test sets: what every solver and scheme is run on.

Three sets, each a list of :class:`BenchProblem` built deterministically from a seed:

* ``scenarios``: every bundled scenario, run in closed loop; each control step is one timed trial
  (the horizon is capped at ``max_steps`` steps so that slow back-ends finish).
* ``random``: seeded random UVMS problems (one control step each): random models (planar and
  spatial vehicles, 3-7 joint arms from random Denavit-Hartenberg tables, and the bundled models),
  random states (including near-singular arms and joints exactly at their limits), random stacks
  of 2-6 levels mixing equality and inequality tasks under hard bounds tight enough to be active.
  One draw in five is a single weighted level (tool frame + posture) that Pink can express too.
* ``raw``: plain :func:`uvms_qp.hqp.solve_hierarchy` problems with levels of sizes
  ``[6, 3, 1, 4]`` at ``n = 10, 13, 30`` under wide, tight and saturated box bounds.

The generators are library code (they are also used by the tests and the ``benchmarks/``
scripts); :func:`random_uvms_problem` is the draw of one ``random`` problem.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from .._validation import FloatArray
from ..errors import InputError
from ..model import Model, bundled_models, load_model
from ..model.vehicle import Vehicle
from ..sim.scenario import bundled_scenarios
from ..tasks import EndEffectorTask
from .stacks import random_bounds, random_stack, random_target, tool_posture_stack

#: Names of the test sets, in run order.
SET_NAMES: tuple[str, ...] = ("scenarios", "random", "raw")

#: Level sizes of the raw problems (issue "lexicographic solver", performance section).
RAW_LEVEL_SIZES: tuple[int, ...] = (6, 3, 1, 4)
RAW_SIZES: tuple[int, ...] = (10, 13, 30)
RAW_BOUNDS: tuple[str, ...] = ("wide", "tight", "saturated")


@dataclass
class UvmsDraw:
    """One random UVMS control problem (built fresh for every solver).

    Attributes:
        model: The :class:`~uvms_qp.model.Model`.
        q: Configuration (nq,).
        stack: The :class:`~uvms_qp.stack.Stack` (new task objects on every build).
        dt: Control period [s].
        pink: Description of the equivalent Pink problem (tool frame target, gains, posture
            weight) when the stack is one weighted level Pink can express, else None.
        notes: Short tags of the draw (``"singular"``, ``"at-limits"``, ``"dh"``...).
    """

    model: Any
    q: FloatArray
    stack: Any
    dt: float
    pink: dict[str, Any] | None = None
    notes: tuple[str, ...] = ()


@dataclass
class BenchProblem:
    """One benchmark item of a set.

    Attributes:
        set: Set name (``"scenarios"``, ``"random"``, ``"raw"``).
        name: Problem name, unique within the set; the random and raw names carry the seed, so
            a resumed run with another seed adds rows instead of skipping them.
        kind: ``"scenario"``, ``"uvms"`` or ``"raw"``.
        info: Plain description written to the results (model, n, level sizes, tags...).
        scenario: Bundled scenario name (kind ``"scenario"``).
        max_steps: Horizon cap in control steps (kind ``"scenario"``).
        build: Builds a fresh :class:`UvmsDraw` (kind ``"uvms"``).
        levels: Levels as ``(A, lo, hi)`` triples (kind ``"raw"``).
        lower: Hard lower bounds (kind ``"raw"``).
        upper: Hard upper bounds (kind ``"raw"``).
        all_equality: Every level holds only equality rows.
    """

    set: str
    name: str
    kind: str
    info: dict[str, Any] = field(default_factory=dict)
    scenario: str | None = None
    max_steps: int | None = None
    build: Callable[[], UvmsDraw] | None = None
    levels: list[list[tuple[FloatArray, FloatArray, FloatArray]]] | None = None
    lower: FloatArray | None = None
    upper: FloatArray | None = None
    all_equality: bool = True


@dataclass(frozen=True)
class SetConfig:
    """Sizes of the test sets.

    Attributes:
        max_steps: Horizon cap per scenario [steps].
        scenarios: Bundled scenario names to run (None: all).
        random_count: Number of random UVMS problems.
        raw_per_case: Raw problems per (n, bound kind).
    """

    max_steps: int = 200
    scenarios: tuple[str, ...] | None = None
    random_count: int = 40
    raw_per_case: int = 6

    @classmethod
    def quick(cls) -> SetConfig:
        """The ``--quick`` smoke sizes (the whole run takes well under a minute)."""
        return cls(max_steps=15, scenarios=("bluerov2_demo", "paper001_circle"),
                   random_count=6, raw_per_case=1)


# ----------------------------------------------------------------------------------- scenarios


def scenario_set(config: SetConfig) -> list[BenchProblem]:
    """Every bundled scenario (or ``config.scenarios``), closed loop, capped at ``max_steps``."""
    names = list(config.scenarios) if config.scenarios is not None else bundled_scenarios()
    known = set(bundled_scenarios())
    for name in names:
        if name not in known:
            raise InputError(f"scenario {name!r} is not bundled; bundled: "
                             f"{', '.join(sorted(known))}")
    return [BenchProblem("scenarios", name, "scenario", {"scenario": name,
                                                         "max_steps": config.max_steps},
                         scenario=name, max_steps=config.max_steps) for name in names]


# ------------------------------------------------------------------------------------ raw set


def raw_problem(n: int, bounds: str, rng: np.random.Generator,
                sizes: tuple[int, ...] = RAW_LEVEL_SIZES) -> tuple[list[Any], FloatArray,
                                                                     FloatArray]:
    """One raw lexicographic problem: equality levels of ``sizes`` rows over ``x`` in R^n.

    The targets are ``b_k = A_k x_0`` for one random ``x_0`` (scale 1) plus noise, so the first
    levels are consistent and the later ones conflict once ``sum(sizes) > n``. Box bounds, with
    ``s = |x_0|_inf``:

    * ``wide``: ``|x_i| <= 10 s`` (never active);
    * ``tight``: ``|x_i| <= 0.5 s`` (a few active);
    * ``saturated``: ``|x_i| <= 0.05 s`` (most active).

    Returns:
        ``(levels, lower, upper)`` with levels as lists of ``(A, b, b)`` triples.
    """
    factors = {"wide": 10.0, "tight": 0.5, "saturated": 0.05}
    if bounds not in factors:
        raise InputError(f"bounds: expected one of {', '.join(factors)}, got {bounds!r}")
    x0 = rng.normal(size=n)
    levels = []
    for m in sizes:
        A = rng.normal(size=(m, n))
        b = A @ x0 + 0.1 * rng.normal(size=m)
        levels.append([(A, b, b.copy())])
    s = float(np.abs(x0).max())
    half = factors[bounds] * s
    return levels, np.full(n, -half), np.full(n, half)


def raw_set(config: SetConfig, seed: int) -> list[BenchProblem]:
    """The raw ``[6, 3, 1, 4]`` problems at n = 10, 13, 30 with wide/tight/saturated bounds."""
    out = []
    for n in RAW_SIZES:
        for bounds in RAW_BOUNDS:
            for i in range(config.raw_per_case):
                rng = np.random.default_rng([seed, n, RAW_BOUNDS.index(bounds), i])
                levels, lo, hi = raw_problem(n, bounds, rng)
                out.append(BenchProblem(
                    "raw", f"n{n}-{bounds}-s{seed}-{i}", "raw",
                    {"n": n, "bounds": bounds, "levels": list(RAW_LEVEL_SIZES)},
                    levels=levels, lower=lo, upper=hi, all_equality=True))
    return out


# --------------------------------------------------------------------------------- random UVMS


def random_dh_model(rng: np.random.Generator, name: str, *, planar: bool | None = None,
                    n_joints: int | None = None) -> Any:
    """A random UVMS: planar or spatial vehicle and a 3-7 joint revolute arm from a DH table.

    Link lengths ``a`` in [0, 0.4] m, offsets ``d`` in [0, 0.2] m, twists from
    ``{0, +/-pi/2}`` (planar vehicles: all 0, so the arm moves in the plane), joint limits
    ``+/-`` 1-3 rad, joint rate limits 0.5-2 rad/s. Spatial vehicles actuate all six DOFs or
    the 4-DOF ROV set ``u, v, w, r``.

    Args:
        rng: Random generator (consumed).
        name: The model's name.
        planar: Planar (True) or spatial (False) vehicle; drawn (35 % planar) when None.
        n_joints: Number of arm joints; drawn from 3-7 when None.
    """
    if planar is None:
        planar = bool(rng.uniform() < 0.35)
    if n_joints is None:
        n_joints = int(rng.integers(3, 8))
    rows = []
    for _ in range(n_joints):
        alpha = 0.0 if planar else float(rng.choice([0.0, math.pi / 2, -math.pi / 2]))
        limit = float(rng.uniform(1.0, 3.0))
        rows.append({"a": float(rng.uniform(0.05, 0.4)), "alpha": alpha,
                     "d": 0.0 if planar else float(rng.uniform(0.0, 0.2)),
                     "theta": 0.0, "lower": -limit, "upper": limit,
                     "rate_limit": float(rng.uniform(0.5, 2.0))})
    if planar:
        vehicle = Vehicle("planar")
        mount = {"xyz": [0.3, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0]}
    else:
        actuated = None if rng.uniform() < 0.5 else ("u", "v", "w", "r")
        vehicle = Vehicle("spatial", actuated=actuated)
        mount = {"xyz": [0.3, 0.0, 0.2], "rpy": [0.0, float(rng.choice([0.0, math.pi / 2])), 0.0]}
    return Model.from_dh(rows, vehicle=vehicle, mount=mount, name=name)


def _singular_configuration(model: Any, rng: np.random.Generator, draws: int = 24) -> FloatArray:
    """The draw (out of ``draws``) whose arm position Jacobian has the smallest singular value."""
    best, best_sv = model.random_configuration(rng), math.inf
    for _ in range(draws):
        q = model.random_configuration(rng)
        J = model.state(q).arm_jacobian("tool", rows="position")
        sv = float(np.linalg.svd(J, compute_uv=False).min()) if J.size else 0.0
        if sv < best_sv:
            best, best_sv = q, sv
    return best


def _at_limits_configuration(model: Any, rng: np.random.Generator) -> FloatArray:
    """A random configuration with about half of the bounded joints exactly at a limit."""
    q = model.random_configuration(rng)
    eta, joints = model.split(q)
    lo, hi = np.asarray(model.joint_lower), np.asarray(model.joint_upper)
    for j in range(joints.size):
        if rng.uniform() < 0.5:
            side = lo[j] if rng.uniform() < 0.5 else hi[j]
            if math.isfinite(side):
                joints[j] = side
    return model.configuration(eta, joints)


def _fully_actuated(model: Any) -> bool:
    return int(model.nv) == int(model.pin_model.nv)


def random_uvms_problem(seed: int, models: dict[str, Any] | None = None) -> UvmsDraw:
    """Draw one random UVMS control problem (deterministic in ``seed``).

    Args:
        seed: Seed of the draw.
        models: Cache of bundled models by name (filled on first use).

    Returns:
        A :class:`UvmsDraw` whose stack has 2-6 levels mixing equality and inequality tasks
        (:func:`~uvms_qp.bench.stacks.random_stack`; or, one draw in five on a fully actuated
        model, one weighted level Pink can express), and hard joint position, joint rate and
        vehicle rate bounds tight enough to be active
        (:func:`~uvms_qp.bench.stacks.random_bounds`).
    """
    rng = np.random.default_rng([seed, 0x55])
    cache = models if models is not None else {}
    notes: list[str] = []
    if rng.uniform() < 0.5:
        model = random_dh_model(rng, f"dh_{seed}")
        notes.append(f"dh{model.n_joints}-{model.vehicle_kind}")
    else:
        name = str(rng.choice(bundled_models()))
        if name not in cache:
            cache[name] = load_model(name)
        model = cache[name]
        notes.append(name)
    u = rng.uniform()
    if u < 0.25:
        q = _singular_configuration(model, rng)
        notes.append("singular")
    elif u < 0.5:
        q = _at_limits_configuration(model, rng)
        notes.append("at-limits")
    else:
        q = model.random_configuration(rng)
    state = model.state(q)
    dt = float(rng.choice([0.01, 0.05, 0.1]))
    constraints = random_bounds(model, rng)

    if _fully_actuated(model) and rng.uniform() < 0.2:
        # one weighted level: tool frame + posture regularisation (expressible in Pink)
        mode: Literal["position", "pose"] = (
            "pose" if model.vehicle_kind == "spatial" and rng.uniform() < 0.5 else "position")
        target = random_target(state, model, rng, 0.3)
        rotation = None
        if mode == "pose":
            rotation = model.frame_pose(model.random_configuration(rng), "tool")[:3, :3]
        gain = float(rng.uniform(0.5, 3.0))
        posture_weight = 1e-3
        kwargs: dict[str, Any] = {"position": list(target)}
        if rotation is not None:
            kwargs["rotation"] = rotation.tolist()
        stack = tool_posture_stack(EndEffectorTask(mode=mode, gain=gain, **kwargs),
                                   posture_gain=1.0, posture_weight=posture_weight,
                                   constraints=constraints)
        pink = {"position": target, "rotation": rotation, "gain": gain,
                "posture_weight": posture_weight}
        notes.append("one-level")
        return UvmsDraw(model, q, stack, dt, pink, tuple(notes))

    stack = random_stack(model, state, rng, constraints)
    notes.append(f"{len(stack.levels)}-levels")
    return UvmsDraw(model, q, stack, dt, None, tuple(notes))


def random_set(config: SetConfig, seed: int) -> list[BenchProblem]:
    """``config.random_count`` random UVMS problems (see :func:`random_uvms_problem`)."""
    models: dict[str, Any] = {}
    out = []
    for i in range(config.random_count):
        draw_seed = seed * 100_003 + i
        probe = random_uvms_problem(draw_seed, models)
        info = {"model": probe.model.name, "nv": int(probe.model.nv),
                "levels": len(probe.stack.levels), "tags": list(probe.notes),
                "pink": probe.pink is not None}

        def build(s: int = draw_seed) -> UvmsDraw:
            return random_uvms_problem(s, models)

        out.append(BenchProblem("random", f"uvms-s{seed}-{i:03d}", "uvms", info, build=build,
                                all_equality=False))
    return out


def build_sets(names: list[str], seed: int, config: SetConfig) -> list[BenchProblem]:
    """The problems of the named sets, in order.

    Raises:
        InputError: an unknown set name (the known names are listed).
    """
    makers: dict[str, Callable[[], list[BenchProblem]]] = {
        "scenarios": lambda: scenario_set(config),
        "random": lambda: random_set(config, seed),
        "raw": lambda: raw_set(config, seed),
    }
    out: list[BenchProblem] = []
    for name in names:
        if name not in makers:
            raise InputError(f"unknown set {name!r}; known sets: {', '.join(SET_NAMES)}")
        out.extend(makers[name]())
    return out
