"""Serial arms from URDF files, loaded through Pinocchio.

The URDF describes the arm only; its root link is the arm base, attached to the vehicle by the
model's mount transform. Supported joints are ``revolute`` and ``prismatic`` (each with a
``<limit>``) and ``fixed``; ``continuous``, ``floating`` and ``planar`` joints are rejected,
because every arm coordinate must be a single bounded angle or length.

The file is first checked with the standard XML parser so that errors name the file, the line
and the element at fault; Pinocchio then builds the model (fixed joints become frames).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import ModelError, ModelFileError

FloatArray = NDArray[np.float64]

_MOVING = ("revolute", "prismatic")
_SUPPORTED = (*_MOVING, "fixed")


@dataclass(frozen=True)
class UrdfArm:
    """A fixed-base Pinocchio arm read from a URDF file.

    Attributes:
        model: Pinocchio model rooted at the URDF root link.
        joint_names: Moving joint names, in Pinocchio (depth-first) order.
        lower: Lower joint limits [rad or m] from ``<limit lower>``.
        upper: Upper joint limits [rad or m] from ``<limit upper>``.
        rate_limit: Joint rate limits [rad/s or m/s] from ``<limit velocity>`` (``inf`` if 0).
        root: Name of the root link (the arm base).
        leaves: Links without children (candidate tools), in file order.
        links: All link names, in file order.
    """

    model: pin.Model
    joint_names: tuple[str, ...]
    lower: FloatArray
    upper: FloatArray
    rate_limit: FloatArray
    root: str
    leaves: tuple[str, ...]
    links: tuple[str, ...]


def _fail(path: Path, message: str) -> ModelFileError:
    return ModelFileError(f"URDF {str(path)!r}: {message}")


def _check_xml(path: Path) -> tuple[str, tuple[str, ...], tuple[str, ...]]:
    """Check the structure the loader relies on; return (root link, leaf links, all links)."""
    try:
        tree = ET.parse(path)
    except ET.ParseError as exc:
        raise _fail(path, f"does not parse as XML ({exc})") from exc
    robot = tree.getroot()
    if robot.tag != "robot":
        raise _fail(path, f"root element is <{robot.tag}>, expected <robot>")
    links = [link.get("name") for link in robot.findall("link")]
    if not links or any(not n for n in links):
        raise _fail(path, "every <link> needs a name and there must be at least one")
    link_names = tuple(str(n) for n in links)
    children: set[str] = set()
    parents: set[str] = set()
    for joint in robot.findall("joint"):
        name = joint.get("name")
        kind = joint.get("type")
        where = f"joint {name!r}"
        if not name:
            raise _fail(path, "a <joint> has no name")
        if kind not in _SUPPORTED:
            raise ModelError(
                f"URDF {str(path)!r}: {where} has type {kind!r}; supported: "
                f"{', '.join(_SUPPORTED)} (give a continuous joint revolute limits)"
            )
        parent = joint.find("parent")
        child = joint.find("child")
        if parent is None or child is None:
            raise _fail(path, f"{where} needs <parent link=...> and <child link=...>")
        p, c = parent.get("link"), child.get("link")
        for role, link in (("parent", p), ("child", c)):
            if link not in link_names:
                raise _fail(path, f"{where}: {role} link {link!r} is not a <link>")
        if kind in _MOVING:
            limit = joint.find("limit")
            if limit is None or limit.get("lower") is None or limit.get("upper") is None:
                raise _fail(path, f"{where} ({kind}) needs <limit lower=... upper=...>")
        children.add(str(c))
        parents.add(str(p))
    roots = [n for n in link_names if n not in children]
    if len(roots) != 1:
        raise _fail(path, f"expected one root link, found {roots}")
    leaves = tuple(n for n in link_names if n not in parents)
    return roots[0], leaves, link_names


def load_urdf_arm(path: str | Path) -> UrdfArm:
    """Read a URDF arm into a fixed-base Pinocchio model.

    Args:
        path: URDF file.

    Returns:
        The arm, its joint names and limits.

    Raises:
        ModelFileError: the file is missing or does not parse.
        ModelError: unsupported joint types or inconsistent limits.
    """
    path = Path(path)
    if not path.is_file():
        raise ModelFileError(f"URDF {str(path)!r}: no such file")
    root, leaves, links = _check_xml(path)
    try:
        model = pin.buildModelFromUrdf(str(path))
    except (ValueError, RuntimeError) as exc:
        raise _fail(path, f"Pinocchio could not build it ({exc})") from exc
    names = tuple(str(n) for n in model.names[1:])
    for jid in range(1, model.njoints):
        if model.joints[jid].nq != 1 or model.joints[jid].nv != 1:
            raise ModelError(f"URDF {str(path)!r}: joint {names[jid - 1]!r} is not 1-DOF")
    lower = np.array(model.lowerPositionLimit, dtype=np.float64)
    upper = np.array(model.upperPositionLimit, dtype=np.float64)
    rate = np.array(model.velocityLimit, dtype=np.float64)
    rate[rate <= 0.0] = math.inf
    bad = np.flatnonzero(lower >= upper)
    if bad.size:
        i = int(bad[0])
        raise ModelError(
            f"URDF {str(path)!r}: joint {names[i]!r} has lower limit {lower[i]} >= upper "
            f"limit {upper[i]} (use a fixed joint for a locked axis)"
        )
    return UrdfArm(
        model=model,
        joint_names=names,
        lower=lower,
        upper=upper,
        rate_limit=rate,
        root=root,
        leaves=leaves,
        links=links,
    )
