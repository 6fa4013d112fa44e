"""Selections of joints and columns shared by tasks and constraints (names -> indices)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import InputError, UnknownJointError


def joint_indices(model: Any, joints: Sequence[str] | None, label: str) -> np.ndarray:
    """Indices (into the arm joint vector) of the named joints; all joints when None."""
    names = tuple(model.joint_names)
    if joints is None:
        return np.arange(len(names))
    out = []
    for j in joints:
        if j not in names:
            raise UnknownJointError(j, names)
        out.append(names.index(j))
    if len(set(out)) != len(out):
        raise InputError(f"{label}: a joint is named twice")
    return np.asarray(out, dtype=int)



def check_joint_list(joints: Any, label: str) -> list[str] | None:
    """Validate an optional list of joint names (type only; existence is checked at bind)."""
    if joints is None:
        return None
    if isinstance(joints, str):
        joints = [joints]
    if not isinstance(joints, list | tuple) or not joints or not all(
        isinstance(j, str) for j in joints
    ):
        raise InputError(f"{label}: expected a non-empty list of joint names, got {joints!r}")
    return list(joints)



def compact_index(indices: Any) -> Any:
    """A slice when ``indices`` are consecutive (basic indexing: a view, no copy), else an array."""
    idx = np.asarray(indices, dtype=int)
    if idx.size and np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size)):
        return slice(int(idx[0]), int(idx[0]) + idx.size)
    return idx
