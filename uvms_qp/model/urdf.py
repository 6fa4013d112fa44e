"""Serial arms from URDF files, loaded through Pinocchio.

The URDF describes the arm only; its root link is the arm base, attached to the vehicle by the
model's mount transform. Supported joints are ``revolute`` and ``prismatic`` (each with a
``<limit>``) and ``fixed``; ``continuous``, ``floating`` and ``planar`` joints are rejected,
because every arm coordinate must be a single bounded angle or length, and so are ``<mimic>``
joints (a mimic joint is not a free coordinate, and reading it as one would let the controller
move it on its own).

The file is untrusted input: it is first checked with the standard XML parser, element by
element, so that an error names the file, the element and the attribute at fault (a zero or
non-numeric axis, limits that are missing, not numbers or in the wrong order, a missing
``effort`` or ``velocity``); Pinocchio then builds the model (fixed joints become frames). The
accepted size is bounded: :data:`MAX_FILE_BYTES` per file, :data:`MAX_MOVING_JOINTS` moving
joints and :data:`MAX_LINKS` links (Pinocchio's buffers grow with the cube of the joint count).
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import InputError, ModelError, ModelFileError

FloatArray = NDArray[np.float64]

#: Largest URDF file read [bytes] (a robot description with meshes referenced by path is a few
#: kilobytes to a few hundred).
MAX_FILE_BYTES = 4 * 1024 * 1024
#: Largest number of revolute and prismatic joints of an arm.
MAX_MOVING_JOINTS = 64
#: Largest number of links.
MAX_LINKS = 512

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


def _numbers(path: Path, where: str, text: str | None, count: int) -> tuple[float, ...]:
    """``count`` finite numbers from an attribute's text (``where`` names the element)."""
    parts = (text or "").split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise _fail(path, f"{where}: expected {count} finite number{'s' * (count > 1)}, "
                          f"got {text!r}")
    return values


def _check_joint(path: Path, joint: ET.Element, link_names: set[str]) -> tuple[str, str, str]:
    """Check one ``<joint>``; return ``(name, parent link, child link)``."""
    name = joint.get("name")
    kind = joint.get("type")
    if not name:
        raise _fail(path, "a <joint> has no name")
    where = f"joint {name!r}"
    if kind not in _SUPPORTED:
        raise ModelError(
            f"URDF {str(path)!r}: {where} has type {kind!r}; supported: "
            f"{', '.join(_SUPPORTED)} (give a continuous joint revolute limits)"
        )
    mimic = joint.find("mimic")
    if mimic is not None:
        raise ModelError(
            f"URDF {str(path)!r}: {where} <mimic joint={mimic.get('joint')!r}> is not supported: "
            "a mimic joint is not a free coordinate (model it as a fixed joint, or drop <mimic> "
            "to control it on its own)"
        )
    parent = joint.find("parent")
    child = joint.find("child")
    if parent is None or child is None:
        raise _fail(path, f"{where} needs <parent link=...> and <child link=...>")
    p, c = parent.get("link"), child.get("link")
    for role, link in (("parent", p), ("child", c)):
        if link not in link_names:
            raise _fail(path, f"{where}: {role} link {link!r} is not a <link>")
    origin = joint.find("origin")
    if origin is not None:
        for attribute in ("xyz", "rpy"):
            if origin.get(attribute) is not None:
                _numbers(path, f"{where} <origin {attribute}>", origin.get(attribute), 3)
    if kind in _MOVING:
        axis = joint.find("axis")
        if axis is not None:  # URDF's default axis is x
            xyz = _numbers(path, f"{where} <axis xyz>", axis.get("xyz"), 3)
            if math.hypot(*xyz) < 1e-9:
                raise _fail(path, f"{where} <axis xyz={axis.get('xyz')!r}> is zero: the joint "
                                  "would move nothing")
        limit = joint.find("limit")
        if limit is None:
            raise _fail(path, f"{where} ({kind}) needs <limit lower=... upper=... effort=... "
                              "velocity=...>")
        values = {}
        for attribute in ("lower", "upper", "effort", "velocity"):
            if limit.get(attribute) is None:
                raise _fail(path, f"{where} <limit> has no {attribute}= (URDF requires lower "
                                  "and upper for a bounded joint, effort and velocity always)")
            values[attribute] = _numbers(path, f"{where} <limit {attribute}>",
                                         limit.get(attribute), 1)[0]
        if values["lower"] >= values["upper"]:
            raise ModelError(
                f"URDF {str(path)!r}: {where} has lower limit {values['lower']} >= upper limit "
                f"{values['upper']} (use a fixed joint for a locked axis)"
            )
        for attribute in ("effort", "velocity"):
            if values[attribute] < 0.0:
                raise _fail(path, f"{where} <limit {attribute}={limit.get(attribute)!r}> is "
                                  "negative")
    return name, str(p), str(c)


def _check_xml(path: Path) -> tuple[str, tuple[str, ...], tuple[str, ...]]:
    """Check the structure the loader relies on; return (root link, leaf links, all links)."""
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise _fail(path, f"{size} bytes; a URDF arm may have at most {MAX_FILE_BYTES} bytes")
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
    if len(link_names) > MAX_LINKS:
        raise ModelError(f"URDF {str(path)!r}: {len(link_names)} links; at most {MAX_LINKS}")
    if len(set(link_names)) != len(link_names):
        twice = sorted({n for n in link_names if link_names.count(n) > 1})
        raise _fail(path, f"link names {twice} appear more than once")
    known = set(link_names)
    joints = robot.findall("joint")
    moving = sum(j.get("type") in _MOVING for j in joints)
    if moving > MAX_MOVING_JOINTS:
        raise ModelError(f"URDF {str(path)!r}: {moving} moving joints; an arm may have at "
                         f"most {MAX_MOVING_JOINTS}")
    children: dict[str, str] = {}
    parents: set[str] = set()
    names: set[str] = set()
    for joint in joints:
        name, p, c = _check_joint(path, joint, known)
        if name in names:
            raise _fail(path, f"joint name {name!r} appears more than once")
        names.add(name)
        if c in children:
            raise _fail(path, f"link {c!r} is the child of joints {children[c]!r} and {name!r}")
        children[c] = name
        parents.add(p)
    if not moving:
        raise ModelError(f"URDF {str(path)!r}: no revolute or prismatic joint; an arm needs "
                         "at least one moving joint")
    roots = [n for n in link_names if n not in children]
    if len(roots) != 1:
        raise _fail(path, f"expected one root link, found {roots}")
    leaves = tuple(n for n in link_names if n not in parents)
    return roots[0], leaves, link_names


def check_path(path: Any) -> Path:
    """A URDF path given as ``str`` or ``os.PathLike``.

    Raises:
        InputError: anything else (None, a number, ...).
    """
    if not isinstance(path, str | PathLike):
        raise InputError(f"path: expected a URDF file path, got {type(path).__name__} {path!r}")
    return Path(path)


def load_urdf_arm(path: str | Path) -> UrdfArm:
    """Read a URDF arm into a fixed-base Pinocchio model.

    Args:
        path: URDF file.

    Returns:
        The arm, its joint names and limits.

    Raises:
        InputError: ``path`` is not a path.
        ModelFileError: the file is missing, too large, does not parse, or an element is
            malformed (the message names it).
        ModelError: unsupported joints (types, mimic), no moving joint, too many joints or
            links, inconsistent limits.
    """
    path = check_path(path)
    if not path.is_file():
        where = ""
        if not path.is_absolute():
            where = (f" ({os.path.abspath(path)}, relative to the working directory "
                     f"{os.getcwd()})")
        raise ModelFileError(f"URDF {str(path)!r}: no such file{where}")
    root, leaves, links = _check_xml(path)
    try:
        model = pin.buildModelFromUrdf(str(path))
    except (ValueError, RuntimeError) as exc:
        raise _fail(path, f"Pinocchio could not build it ({exc})") from exc
    names = tuple(str(n) for n in model.names[1:])
    for jid in range(1, model.njoints):
        if model.joints[jid].nq != 1 or model.joints[jid].nv != 1:
            raise ModelError(f"URDF {str(path)!r}: joint {names[jid - 1]!r} is not 1-DOF")
    rate = np.array(model.velocityLimit, dtype=np.float64)
    rate[rate <= 0.0] = math.inf
    return UrdfArm(
        model=model,
        joint_names=names,
        lower=np.array(model.lowerPositionLimit, dtype=np.float64),
        upper=np.array(model.upperPositionLimit, dtype=np.float64),
        rate_limit=rate,
        root=root,
        leaves=leaves,
        links=links,
    )
