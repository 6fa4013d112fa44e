"""What a view draws of a robot: its skeleton and a box for the vehicle body, from kinematics.

The bundled models have no meshes (the BlueROV2 URDF has no ``<visual>``; DH and planar models
have only their kinematics), so every model is drawn with the same primitives:

- the **skeleton**: one segment from each drawn frame to its parent (the nearest ancestor among
  ``model.frames`` in Pinocchio's frame tree): the mount (``vehicle`` -> ``arm_base``), then the
  arm's links down to the ``tool``. A branching URDF draws as the tree it is.
- the **body**: a box centred on the vehicle origin and aligned with its body axes, of size
  :data:`BODY_SIZES` for the bundled vehicles, otherwise reaching forward to the arm base
  (length twice the mount's x offset, or the arm's extent when that is 0; width 0.6 and height
  0.4 of the length, 0.1 for a planar vehicle). A fixed base gets a
  flat plate under the arm base instead, 0.3 times the arm's extent at its home configuration.

All positions are world coordinates [m] (NED for a vehicle; the arm's base frame for a fixed
base).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..._validation import FloatArray
from ...errors import InputError

#: Body boxes (length, width, height) [m] of bundled vehicles, by model name. BlueROV2 Heavy:
#: the 0.457 m x 0.575 m frame of its public descriptions' collision box, and the vendor's
#: published height of 0.254 m.
BODY_SIZES: dict[str, tuple[float, float, float]] = {
    "bluerov2_heavy_alpha5": (0.457, 0.575, 0.254),
}
#: Corners of the unit box, centred on the origin (x, y, z in {-1/2, 1/2}).
BOX_CORNERS: FloatArray = np.array(
    [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
)
#: The box's 12 edges as pairs of corner indices.
BOX_EDGES: tuple[tuple[int, int], ...] = (
    (0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7),
)
#: The box's 12 triangles (two per face) as corner indices.
BOX_TRIANGLES: tuple[tuple[int, int, int], ...] = (
    (0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
    (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3),
)
#: Frames never drawn as skeleton points of their own.
_NOT_DRAWN = ("world",)


def polyline(pairs: FloatArray) -> FloatArray:
    """(K, 2, 3) segments as one (3K, 3) polyline, a row of NaN between segments."""
    out = np.full((3 * len(pairs), 3), np.nan)
    out[0::3] = pairs[:, 0]
    out[1::3] = pairs[:, 1]
    return out


def skeleton_edges(model: Any) -> list[tuple[str, str]]:
    """``(parent, child)`` frame pairs of the skeleton (see the module docstring)."""
    pin_model = model.pin_model
    names = [f for f in model.frames if f not in _NOT_DRAWN]
    drawn = set(names)
    edges = []
    for child in names:
        if child == "vehicle":
            continue
        frame = pin_model.frames[model.frame_id(child)]
        parent_id = int(frame.parentFrame)
        while parent_id and pin_model.frames[parent_id].name not in drawn:
            parent_id = int(pin_model.frames[parent_id].parentFrame)
        if parent_id:
            parent = str(pin_model.frames[parent_id].name)
        else:  # the arm is appended below arm_base, which hangs from the vehicle
            parent = "vehicle" if child == "arm_base" else "arm_base"
        if parent != child:
            edges.append((parent, child))
    return edges


def default_body_size(model: Any) -> tuple[float, float, float]:
    """Body box (length, width, height) [m] of ``model`` (see the module docstring)."""
    if model.name in BODY_SIZES:
        return BODY_SIZES[model.name]
    state = model.state(model.home())
    base = state.position("arm_base")
    extent = max((float(np.linalg.norm(state.position(f) - base)) for f in model.frames),
                 default=0.0) or 1.0
    if model.vehicle_kind == "fixed":
        return (0.3 * extent, 0.3 * extent, 0.02 * extent)
    ahead = abs(float(np.asarray(model.mount)[0, 3]))
    length = 2.0 * ahead if ahead > 0.0 else extent
    height = 0.1 if model.vehicle_kind == "planar" else 0.4
    return (length, 0.6 * length, height * length)


class RobotScene:
    """The drawn geometry of a model at any configuration.

    Args:
        model: The UVMS model.
        body_size: Body box (length, width, height) [m]; default :func:`default_body_size`.

    Raises:
        InputError: a body size that is not three positive finite numbers.
    """

    def __init__(self, model: Any, body_size: Any = None) -> None:
        self.model = model
        self.edges = skeleton_edges(model)
        self.frames: tuple[str, ...] = tuple(dict.fromkeys(f for e in self.edges for f in e))
        self._index = {f: i for i, f in enumerate(self.frames)}
        size = np.asarray(default_body_size(model) if body_size is None else body_size,
                          dtype=np.float64)
        if size.shape != (3,) or not np.all(np.isfinite(size)) or not np.all(size > 0):
            raise InputError(f"body_size: expected three positive lengths [m], got {body_size!r}")
        self.body_size: tuple[float, float, float] = (float(size[0]), float(size[1]),
                                                      float(size[2]))
        self.has_vehicle = model.vehicle_kind != "fixed"

    def geometry(self, q: Any) -> tuple[FloatArray, FloatArray]:
        """World positions of :attr:`frames` (F, 3) and body box corners (8, 3) at ``q`` [m].

        The corners are in the order of :data:`BOX_CORNERS`; the vehicle's box moves with the
        vehicle, a fixed base's plate lies under the arm base.
        """
        state = self.model.state(q)
        positions = np.array([state.position(f) for f in self.frames])
        local = BOX_CORNERS * np.asarray(self.body_size)
        if self.has_vehicle:
            pose = state.pose("vehicle")
        else:
            pose = np.array(state.pose("arm_base"), dtype=np.float64)
            pose[:3, 3] -= pose[:3, :3] @ np.array([0.0, 0.0, 0.5 * self.body_size[2]])
        return positions, local @ pose[:3, :3].T + pose[:3, 3]

    def segments(self, positions: FloatArray) -> FloatArray:
        """The skeleton's segments (E, 2, 3) [m] from the positions of :meth:`geometry`."""
        index = self._index
        return np.array([[positions[index[a]], positions[index[b]]] for a, b in self.edges])
