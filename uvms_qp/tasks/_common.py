"""Small helpers shared by the task modules (axis parsing, angle wrapping, rotation checks)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from operator import itemgetter
from typing import Any

import numpy as np
import pinocchio as pin

from .._validation import FloatArray, as_matrix, as_vector
from ..errors import InputError, ShapeError

TWIST_AXES = ("x", "y", "z", "rx", "ry", "rz")
"""Row names of a twist ``[v; omega]``: linear x, y, z [m/s] then angular x, y, z [rad/s]."""


def wrap_angle(angle: float | FloatArray) -> Any:
    """Wrap an angle [rad] (or an array of angles) to ``[-pi, pi)``."""
    return (np.asarray(angle) + math.pi) % (2.0 * math.pi) - math.pi


def parse_axes(axes: Any, allowed: Sequence[str], label: str) -> list[str]:
    """Validate a list of axis names (each in ``allowed``, no duplicates) and return it.

    A single string is accepted as one axis (``"z"``) or as a compact list (``"xy"`` -> x, y)
    when every character is an allowed axis.
    """
    if isinstance(axes, str):
        if axes in allowed:
            axes = [axes]
        elif all(c in allowed for c in axes):
            axes = list(axes)
        else:
            raise InputError(f"{label}: unknown axis {axes!r}; known axes: {', '.join(allowed)}")
    if not isinstance(axes, list | tuple) or not axes:
        raise InputError(f"{label}: expected a non-empty list of axis names from "
                         f"{', '.join(allowed)}, got {axes!r}")
    out: list[str] = []
    for a in axes:
        if a not in allowed:
            raise InputError(f"{label}: unknown axis {a!r}; known axes: {', '.join(allowed)}")
        if a in out:
            raise InputError(f"{label}: axis {a!r} given twice")
        out.append(a)
    return out


def as_rotation(value: Any, label: str) -> FloatArray:
    """Validate a rotation: a 3x3 orthonormal matrix with det +1, or ``[roll, pitch, yaw]`` [rad].

    Euler angles follow the Z-Y-X convention: ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    Raises:
        ShapeError: neither 3 angles nor a 3x3 matrix.
        InputError: a matrix that is not a rotation (orthonormality tolerance 1e-6).
    """
    try:
        ndim = np.ndim(value)
    except ValueError as exc:  # ragged nested lists
        raise ShapeError(f"{label}: expected 3 angles or a 3x3 matrix") from exc
    if ndim <= 1:
        rpy = as_vector(value, label, 3)
        return np.asarray(pin.rpy.rpyToMatrix(rpy), dtype=np.float64)
    R = as_matrix(value, label, 3, 3)
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > 1e-6:
        raise InputError(f"{label}: not a rotation matrix (|R'R - I| = {err:.2e})")
    if np.linalg.det(R) < 0.0:
        raise InputError(f"{label}: not a rotation matrix (det < 0, a reflection)")
    return R


def as_point(value: Any, label: str, vehicle_kind: str | None = None) -> FloatArray:
    """A 3-vector [m] (or [m/s]), world frame; a 2-vector gets ``z = 0`` on planar models only.

    Args:
        value: 3 coordinates ``(x, y, z)``, or 2 coordinates ``(x, y)`` for a planar model.
        label: Name of the argument, used in error messages.
        vehicle_kind: Kind of the model the point is for (``"planar"``, ``"spatial"``,
            ``"fixed"``), or None when it is not known yet (the caller re-checks at bind with
            :func:`check_planar_point`).

    Raises:
        ShapeError: not 2 or 3 coordinates, or 2 coordinates for a non-planar model.
    """
    p = as_vector(value, label)
    if p.shape[0] == 2:
        check_planar_point(label, vehicle_kind)
        p = np.array([p[0], p[1], 0.0])
    if p.shape[0] != 3:
        raise ShapeError(f"{label}: expected 2 or 3 coordinates, got {p.shape[0]}")
    return p


def check_planar_point(label: str, vehicle_kind: str | None) -> None:
    """Reject a 2-coordinate point ``label`` unless the model is planar (or not known yet).

    Raises:
        ShapeError: ``vehicle_kind`` is known and not ``"planar"`` (the z coordinate would be
            silently taken as 0 on a model that moves in 3-D).
    """
    if vehicle_kind is not None and vehicle_kind != "planar":
        raise ShapeError(f"{label}: got 2 coordinates, but the model is {vehicle_kind}; "
                         "give 3 (x, y, z) (2 are allowed only on planar models)")






def check_frame(model: Any, frame: Any, label: str) -> str:
    """Check that ``frame`` names a frame of ``model`` (raises UnknownFrameError otherwise)."""
    if not isinstance(frame, str):
        raise InputError(f"{label}: expected a frame name, got {type(frame).__name__}")
    model.frame_id(frame)  # raises UnknownFrameError listing the known frames
    return frame


def eta_axes(model: Any) -> tuple[str, ...]:
    """Names of the vehicle pose coordinates of ``model`` (``eta``)."""
    if model.vehicle_kind == "planar":
        return ("x", "y", "psi")
    if model.vehicle_kind == "spatial":
        return ("x", "y", "z", "phi", "theta", "psi")
    return ()




ANGLE_AXES = frozenset({"phi", "theta", "psi"})
_TWO_PI = 2.0 * math.pi


def pose_units(axes: Sequence[str]) -> tuple[str, str]:
    """``(error unit, rate unit)`` of rows over the pose axes ``axes``.

    Positions (``x, y, z``) in m and m/s, angles (any other axis: ``rx``..., ``phi``...) in
    rad and rad/s; ``("m, rad", "m/s, rad/s")`` for a mix.
    """
    linear = any(a in _POSITION_AXES for a in axes)
    angular = any(a not in _POSITION_AXES for a in axes)
    error = ", ".join(u for u, on in (("m", linear), ("rad", angular)) if on)
    rate = ", ".join(u for u, on in (("m/s", linear), ("rad/s", angular)) if on)
    return error, rate


_LINEAR_RATES = frozenset({"u", "v", "w"})
_POSITION_AXES = frozenset({"x", "y", "z"})


class EtaRows:
    """Writer of selected rows of the vehicle-pose Jacobian ``J_eta`` into a row block.

    At bind: the entries of the rows that can be non-zero (a position coordinate moves with the
    linear rates u, v, w only, an angle with the angular rates p, q, r only; joint columns are
    zero), as flat positions in the ``(len(rows), nv)`` block and positions in the state's
    :meth:`~uvms_qp.model.State.eta_jacobian_values`. Per tick :meth:`write` zeroes the block and
    puts those plain floats (two array calls, no ``(eta_size, nv)`` matrix).

    Args:
        model: The bound model.
        rows: Indices of the selected coordinates in ``eta``.
    """

    def __init__(self, model: Any, rows: Sequence[int]) -> None:
        axes = eta_axes(model)
        n_full = model.vehicle.nv  # row length of eta_jacobian_values (all vehicle rates)
        columns = model._eta_columns or list(range(model.n_vehicle))
        dst: list[int] = []
        src: list[int] = []
        for i, r in enumerate(rows):
            for c, rate in enumerate(model.actuated):
                if (axes[r] in _POSITION_AXES) == (rate in _LINEAR_RATES):
                    dst.append(i * model.nv + c)
                    src.append(r * n_full + columns[c])
        self.dst = np.asarray(dst, dtype=np.intp)
        # one C-level pick of the entries (a 1-tuple wrapper keeps a single entry a sequence)
        self._pick: Callable[[Sequence[float]], Sequence[float]]
        if len(src) > 1:
            self._pick = itemgetter(*src)
        elif src:
            k = src[0]
            self._pick = lambda values: (values[k],)
        else:  # no actuated rate moves these coordinates: zero rows
            self._pick = lambda values: ()

    def write(self, state: Any, A: FloatArray) -> None:
        """Write the rows at ``state`` into ``A`` (every entry)."""
        A.fill(0.0)
        A.put(self.dst, self._pick(state.eta_jacobian_values()))


def vehicle_pose_jacobian(state: Any) -> FloatArray:
    """``state.vehicle_pose_jacobian()`` (read-only, computed once per state by the state)."""
    return state.vehicle_pose_jacobian()  # type: ignore[no-any-return]


def wrap_angles_in_place(e: FloatArray, positions: Sequence[int]) -> None:
    """Wrap the entries ``e[i]``, ``i`` in ``positions``, to ``[-pi, pi)`` in place.

    The same operations as :func:`wrap_angle`, per entry in plain floats (cheaper than masks
    for the one to three angles of a vehicle pose).
    """
    for i in positions:
        e[i] = (e.item(i) + math.pi) % _TWO_PI - math.pi
