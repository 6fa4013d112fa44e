"""Random models, states and stacks for the reliability tests, from the benchmark's generators.

Models and stacks are drawn by the one generator of :mod:`uvms_qp.bench` (``random_dh_model``,
``random_stack``, ``random_bounds``); this module fixes a model by vehicle kind, joint count and
seed (built once), adds configurations at or beyond the joint limits, and can put the tool's
target out of reach.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from uvms_qp.bench.sets import random_dh_model
from uvms_qp.bench.stacks import random_bounds, random_target
from uvms_qp.bench.stacks import random_stack as random_mission
from uvms_qp.model import Model
from uvms_qp.stack import Stack

KINDS = ("planar", "spatial")
JOINTS = (3, 4, 5, 6, 7)


@cache
def random_model(kind: str, n_joints: int, seed: int = 0) -> Model:
    """A random DH arm with ``n_joints`` revolute joints on a ``kind`` vehicle (cached)."""
    rng = np.random.default_rng([n_joints, seed, KINDS.index(kind)])
    return random_dh_model(rng, f"random_{kind}_{n_joints}_{seed}", planar=kind == "planar",
                           n_joints=n_joints)


def random_state(model: Model, rng: np.random.Generator, where: str) -> np.ndarray:
    """A configuration with joints ``inside``, ``at`` or just ``outside`` their limits.

    Spatial vehicles get random attitudes (roll and pitch up to +/-1.3 rad).
    """
    q = model.random_configuration(rng, tilt=1.3)
    eta, joints = model.split(q)
    lo, hi = model.joint_lower, model.joint_upper
    if where != "inside":
        pick = rng.uniform(size=model.n_joints) < 0.5
        side = rng.uniform(size=model.n_joints) < 0.5
        off = 0.0 if where == "at" else rng.choice([1e-9, 1e-6, 1e-3, 1e-2], model.n_joints)
        edge = np.where(side, lo - off, hi + off)
        joints = np.where(pick, edge, joints)
    return model.configuration(eta, joints)


def random_stack(model: Model, rng: np.random.Generator, reachable: bool) -> Stack:
    """A random mission stack under random hard bounds (tool target 5 m off if not reachable)."""
    state = model.state(random_state(model, rng, "inside"))
    stack = random_mission(model, state, rng, random_bounds(model, rng))
    if not reachable:
        stack.levels[0].tasks[0].set_target(position=random_target(state, model, rng, 5.0))
    return stack
