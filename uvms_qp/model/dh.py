"""Serial arms from Denavit-Hartenberg tables, built as Pinocchio models.

Two conventions are supported; row ``i`` (1-based) of a table describes link ``i``:

- ``"standard"`` (distal): ``T_{i-1,i} = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``;
  joint ``i`` moves about (revolute) or along (prismatic) ``z_{i-1}``.
- ``"modified"`` (proximal, Craig): ``T_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i + q_i)
  Tz(d_i)``; joint ``i`` moves about ``z_i``. A row's ``a`` and ``alpha`` are then the Craig
  ``a_{i-1}`` and ``alpha_{i-1}`` (as printed in Wang et al. (2017), Table 1).

For a prismatic joint ``q_i`` is added to ``d_i`` instead of ``theta_i``. A ``"fixed"`` row is a
constant link transform (for example the tool row 6 of that table).

Each row becomes ``pre @ motion(q_i) @ post`` with constant ``pre``/``post``; consecutive constants
are folded into the placement of the next Pinocchio joint. The DH frame ``i`` is exposed as a
frame named ``link<i>``; frame 0 is the arm base.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validation import as_scalar
from ..errors import InputError, ModelError, ShapeError
from .transforms import to_se3

FloatArray = NDArray[np.float64]
Convention = Literal["standard", "modified"]
JointKind = Literal["revolute", "prismatic", "fixed"]

_ROW_KEYS = ("a", "alpha", "d", "theta", "kind", "name", "lower", "upper", "rate_limit")


@dataclass(frozen=True)
class DHRow:
    """One row of a Denavit-Hartenberg table.

    Attributes:
        a: Link length [m] (``a_i`` standard, ``a_{i-1}`` modified).
        alpha: Link twist [rad] (``alpha_i`` standard, ``alpha_{i-1}`` modified).
        d: Link offset [m].
        theta: Joint angle offset [rad] (added to the joint variable of a revolute joint).
        kind: ``"revolute"``, ``"prismatic"`` or ``"fixed"``.
        name: Joint name (default ``joint<k>``, k counting moving joints from 1).
        lower: Lower joint position limit [rad or m] (``-inf`` = none).
        upper: Upper joint position limit [rad or m] (``inf`` = none).
        rate_limit: Symmetric joint rate limit [rad/s or m/s] (``inf`` = none).
    """

    a: float = 0.0
    alpha: float = 0.0
    d: float = 0.0
    theta: float = 0.0
    kind: JointKind = "revolute"
    name: str | None = None
    lower: float = -math.inf
    upper: float = math.inf
    rate_limit: float = math.inf


def _rx(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array(((1, 0, 0, 0), (0, c, -s, 0), (0, s, c, 0), (0, 0, 0, 1.0)))


def _rz(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array(((c, -s, 0, 0), (s, c, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1.0)))


def _tx(dist: float) -> FloatArray:
    T = np.eye(4)
    T[0, 3] = dist
    return T


def _tz(dist: float) -> FloatArray:
    T = np.eye(4)
    T[2, 3] = dist
    return T


def as_row(value: Any, index: int) -> DHRow:
    """Validate one table row given as a :class:`DHRow` or a mapping with DHRow's field names.

    Raises:
        InputError: unknown keys, non-numeric or non-finite geometry, bad kind or limits.
    """
    where = f"table[{index}]"
    if isinstance(value, DHRow):
        fields = {k: getattr(value, k) for k in _ROW_KEYS}
    elif isinstance(value, Mapping):
        unknown = sorted(set(value) - set(_ROW_KEYS))
        if unknown:
            raise InputError(f"{where}: unknown keys {unknown}; known: {', '.join(_ROW_KEYS)}")
        fields = {k: getattr(DHRow(), k) for k in _ROW_KEYS} | dict(value)
    else:
        raise InputError(
            f"{where}: expected a DHRow or a mapping with keys a, alpha, d, theta "
            f"(positional tuples are ambiguous between conventions), got {type(value).__name__}"
        )
    geom = {k: as_scalar(fields[k], f"{where}.{k}") for k in ("a", "alpha", "d", "theta")}
    if fields["kind"] not in ("revolute", "prismatic", "fixed"):
        raise InputError(
            f"{where}.kind: unknown {fields['kind']!r}; known: revolute, prismatic, fixed"
        )
    lower = as_scalar(fields["lower"], f"{where}.lower", allow_inf=True)
    upper = as_scalar(fields["upper"], f"{where}.upper", allow_inf=True)
    if lower > upper:
        raise InputError(f"{where}: lower limit {lower} > upper limit {upper}")
    rate = as_scalar(fields["rate_limit"], f"{where}.rate_limit", positive=True, allow_inf=True)
    name = fields["name"]
    if name is not None and (not isinstance(name, str) or not name):
        raise InputError(f"{where}.name: expected a non-empty string, got {name!r}")
    return DHRow(**geom, kind=fields["kind"], name=name, lower=lower, upper=upper, rate_limit=rate)


def _split(row: DHRow, convention: Convention) -> tuple[FloatArray, FloatArray]:
    """Constant transforms ``(pre, post)`` such that the row is ``pre @ motion(q) @ post``."""
    if convention == "standard":
        if row.kind == "prismatic":
            return _rz(row.theta) @ _tz(row.d), _tx(row.a) @ _rx(row.alpha)
        return _rz(row.theta), _tz(row.d) @ _tx(row.a) @ _rx(row.alpha)
    # modified (Craig)
    pre = _rx(row.alpha) @ _tx(row.a) @ _rz(row.theta)
    if row.kind == "prismatic":
        return pre @ _tz(row.d), np.eye(4)
    return pre, _tz(row.d)


@dataclass(frozen=True)
class DHArm:
    """A fixed-base Pinocchio arm built from a DH table.

    Attributes:
        model: Pinocchio model rooted at DH frame 0 (the arm base).
        joint_names: Moving joint names, in chain order.
        lower: Lower joint limits [rad or m].
        upper: Upper joint limits [rad or m].
        rate_limit: Joint rate limits [rad/s or m/s].
        flange: Name of the last DH frame (``link<n>``), where the tool is attached.
    """

    model: pin.Model
    joint_names: tuple[str, ...]
    lower: FloatArray
    upper: FloatArray
    rate_limit: FloatArray
    flange: str


def build_dh_arm(
    table: Sequence[Any], convention: str = "standard", joint_names: Sequence[str] | None = None
) -> DHArm:
    """Build a fixed-base Pinocchio arm from a DH table.

    Args:
        table: Rows as :class:`DHRow` or mappings (keys ``a, alpha, d, theta, kind, name, lower,
            upper, rate_limit``); lengths [m], angles [rad].
        convention: ``"standard"`` or ``"modified"`` (Craig).
        joint_names: Names of the moving joints, overriding the rows' names.

    Returns:
        The arm with frames ``link1`` ... ``link<len(table)>``.

    Raises:
        InputError: bad convention or row.
        ModelError: empty table, no moving joint, or duplicate joint names.
        ShapeError: ``joint_names`` has the wrong length.
    """
    if convention not in ("standard", "modified"):
        raise InputError(f"convention: unknown {convention!r}; known: standard, modified")
    if isinstance(table, (str, bytes)) or not isinstance(table, Sequence) or len(table) == 0:
        raise ModelError("DH table: expected a non-empty sequence of rows")
    rows = [as_row(r, i) for i, r in enumerate(table)]
    n_moving = sum(r.kind != "fixed" for r in rows)
    if n_moving == 0:
        raise ModelError("DH table: no revolute or prismatic joint")
    if joint_names is not None:
        if isinstance(joint_names, str | bytes) or not isinstance(joint_names, Sequence):
            raise InputError(
                f"joint_names: expected a list of names, got {type(joint_names).__name__}")
        given = tuple(joint_names)
        for k, item in enumerate(given):
            if not isinstance(item, str) or not item:
                raise InputError(f"joint_names[{k}]: expected a non-empty string, got {item!r}")
        if len(given) != n_moving:
            raise ShapeError(f"joint_names: expected {n_moving} names, got {len(given)}")
        moving = iter(given)
        rows = [
            r if r.kind == "fixed" else DHRow(**{**r.__dict__, "name": next(moving)}) for r in rows
        ]
    model = pin.Model()
    model.name = "dh_arm"
    parent_joint, parent_frame = 0, 0
    pending = np.eye(4)
    names: list[str] = []
    lower: list[float] = []
    upper: list[float] = []
    rate: list[float] = []
    for i, row in enumerate(rows, start=1):
        pre, post = _split(row, convention)  # type: ignore[arg-type]
        if row.kind == "fixed":
            pending = pending @ pre @ post
        else:
            name = row.name or f"joint{len(names) + 1}"
            if name in names:
                raise ModelError(f"DH table: duplicate joint name {name!r}")
            jmodel = pin.JointModelRZ() if row.kind == "revolute" else pin.JointModelPZ()
            inf = np.array([np.inf])
            parent_joint = model.addJoint(
                parent_joint,
                jmodel,
                to_se3(pending @ pre),
                name,
                inf,  # effort
                np.array([row.rate_limit]),
                np.array([row.lower]),
                np.array([row.upper]),
            )
            parent_frame = model.addJointFrame(parent_joint, parent_frame)
            names.append(name)
            lower.append(row.lower)
            upper.append(row.upper)
            rate.append(row.rate_limit)
            pending = post
        parent_frame = model.addFrame(
            pin.Frame(f"link{i}", parent_joint, parent_frame, to_se3(pending), pin.FrameType.BODY)
        )
    return DHArm(
        model=model,
        joint_names=tuple(names),
        lower=np.array(lower),
        upper=np.array(upper),
        rate_limit=np.array(rate),
        flange=f"link{len(rows)}",
    )
