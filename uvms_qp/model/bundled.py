"""Bundled models: the four papers' systems and a real BlueROV2 Heavy + Reach Alpha 5.

Each entry is a factory building a fresh :class:`~uvms_qp.model.model.Model` (each model owns its
Pinocchio buffers). Names are part of the public surface; see ``docs/models.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from ..errors import UnknownModelError
from .dh import DHRow
from .model import Model
from .transforms import flu_to_frd, transform
from .vehicle import Vehicle

PAPER_000 = "Soylu et al. (2007)"
PAPER_001 = "dos Santos et al. (2006)"
PAPER_002 = "Nenchev and Tsumaki"
PAPER_003 = "Wang et al. (2017)"

#: Published mount of the Reach Alpha 5 base on the BlueROV2 Heavy body, ROS FLU body axes:
#: ``xyz`` [m], ``rpy`` [rad].
BLUEROV2_ALPHA5_MOUNT_FLU = {"xyz": (0.24, -0.099, 0.029), "rpy": (0.0, 0.0, 0.0)}
#: Published maximum forward speed of the BlueROV2 [m/s]; other rates have no published figure.
BLUEROV2_MAX_SURGE = 1.5
#: Mount chosen for the wang_9dof arm (Wang et al. (2017) give none): 0.5 m ahead of and 0.3 m below
#: the vehicle origin, arm base axes aligned with the FRD body axes.
WANG_MOUNT = {"xyz": (0.5, 0.0, 0.3), "rpy": (0.0, 0.0, 0.0)}


def _planar_arm(
    name: str, link: float, reach: float, home: tuple[float, ...], source: str
) -> Model:
    """Planar vehicle with a 3-link planar arm whose base is ``reach`` m ahead of the origin."""
    rows = [DHRow(a=link, name=f"joint{i}") for i in (1, 2, 3)]
    return Model.from_dh(
        rows,
        "standard",
        vehicle=Vehicle("planar"),
        mount=transform((reach, 0.0, 0.0)),
        home=home,
        name=name,
        source=source,
    )


def soylu_planar() -> Model:
    """ROPOS planar UVMS: vehicle (x, y, psi), arm base r = 1 m ahead, three 1 m links.

    Soylu et al. (2007), Section 3; home q = [pi/3, -pi/3, pi/3] puts the tool at
    (3, 1.7321) m.
    """
    third = math.pi / 3
    return _planar_arm("soylu_planar", 1.0, 1.0, (third, -third, third), f"{PAPER_000}, Section 3")


def santos_planar() -> Model:
    """Planar UVMS of dos Santos et al.: arm base 2.5 m ahead, three 2 m links.

    dos Santos et al. (2006), Simulation Results; home q = [1.47, -1, 0.3] rad puts the
    tool at (5.92, 4.29) m with heading 0.77 rad.
    """
    return _planar_arm(
        "santos_planar", 2.0, 2.5, (1.47, -1.0, 0.3), f"{PAPER_001}, Simulation Results"
    )


def wang_9dof() -> Model:
    """9-DOF UVMS of Wang et al.: 4 actuated vehicle rates (u, v, w, r) + 5-joint arm.

    Wang et al. (2017), Table 1 (modified D-H, row 6 is the fixed tool link) and
    Simulation setup (joint limits, home q = [0, -45, 90, 45, 0] deg). Roll and pitch are
    passive. The arm base is mounted at :data:`WANG_MOUNT` (our choice).
    """
    deg = math.radians
    table = [
        DHRow(alpha=0.0, a=0.0, d=0.0),
        DHRow(alpha=deg(90.0), a=0.172, d=0.068),
        DHRow(alpha=0.0, a=0.33, d=-0.068),
        DHRow(alpha=0.0, a=0.33, d=0.068),
        DHRow(alpha=deg(-90.0), a=0.242, d=0.048),
        DHRow(alpha=0.0, a=0.121, d=0.0, kind="fixed"),
    ]
    limits = np.radians([60.0, 90.0, 110.0, 120.0, 120.0])
    return Model.from_dh(
        table,
        "modified",
        vehicle=Vehicle("spatial", actuated=("u", "v", "w", "r")),
        mount=WANG_MOUNT,
        joint_lower=-limits,
        joint_upper=limits,
        home=np.radians([0.0, -45.0, 90.0, 45.0, 0.0]),
        name="wang_9dof",
        source=f"{PAPER_003}, Table 1 and Simulation setup",
    )


def nenchev_pa10_arm() -> Model:
    """4-DOF positioning arm of a PA-10-like arm (d3 = d5 = 1 m) on a fixed base.

    Nenchev and Tsumaki, Section 3: standard D-H with twists (90, -90, 90, -90) deg,
    ``d3 = 1`` m on row 3 and the wrist centre ``d5 = 1`` m along ``z4`` (the tool). This table
    reproduces the paper's Jacobian entries ``j11 .. j34`` and the wrist centre (1, 0, 1) m at
    (0, 0, 0, -90) deg. The world frame is the paper's base frame (z along joint 1).
    """
    half = math.pi / 2
    table = [
        DHRow(alpha=half),
        DHRow(alpha=-half),
        DHRow(alpha=half, d=1.0),
        DHRow(alpha=-half),
    ]
    return Model.from_dh(
        table,
        "standard",
        vehicle=Vehicle("fixed"),
        tool=transform((0.0, 0.0, 1.0)),
        home=np.radians([0.0, 0.0, 0.0, -90.0]),
        name="nenchev_pa10_arm",
        source=f"{PAPER_002}, Section 3",
    )


def bluerov2_urdf_path() -> Path:
    """Path of the bundled Reach Alpha 5 URDF (package data)."""
    return Path(str(resources.files(__package__).joinpath("data/bluerov2_heavy_alpha5.urdf")))


def bluerov2_heavy_alpha5(mount: object = None) -> Model:
    """BlueROV2 Heavy (6 actuated DOF) carrying a Reach Alpha 5 (joints axis_e .. axis_b).

    The arm URDF (package data) keeps the arm's ROS frames. The published mount
    :data:`BLUEROV2_ALPHA5_MOUNT_FLU` is given in the ROS FLU body frame; it is converted to the
    FRD body frame by :func:`~uvms_qp.model.transforms.flu_to_frd`:
    ``T_frd_arm = diag(1, -1, -1, 1) @ T_flu_arm`` (position (0.24, 0.099, -0.029) m, arm base
    turned half a turn about the forward axis, so its z axis points up).

    Args:
        mount: Override of ``T_vehicle_arm_base`` in the FRD body frame (4x4 or
            ``{"xyz", "rpy"}``); default the converted published mount.
    """
    if mount is None:
        mount = flu_to_frd(transform(**BLUEROV2_ALPHA5_MOUNT_FLU))
    return Model.from_urdf(
        bluerov2_urdf_path(),
        vehicle=Vehicle("spatial", rate_limit=(BLUEROV2_MAX_SURGE, *([math.inf] * 5))),
        mount=mount,
        tool="jaws_base_link",
        home=(math.pi, 0.8, 1.8, math.pi),
        name="bluerov2_heavy_alpha5",
        source="public BlueROV2 Heavy and Reach Alpha 5 descriptions",
    )


@dataclass(frozen=True)
class BundledModel:
    """Registry entry of a bundled model.

    Attributes:
        name: Public name.
        build: Factory returning a fresh model.
        summary: One line on what it is.
    """

    name: str
    build: Callable[[], Model]
    summary: str


_REGISTRY: dict[str, BundledModel] = {
    entry.name: entry
    for entry in (
        BundledModel(
            "soylu_planar", soylu_planar, "ROPOS planar UVMS, 3 x 1 m links (Soylu et al. 2007)"
        ),
        BundledModel(
            "santos_planar", santos_planar, "planar UVMS, 3 x 2 m links (dos Santos et al. 2006)"
        ),
        BundledModel(
            "wang_9dof", wang_9dof,
            "4-DOF vehicle, passive roll/pitch, 5-DOF arm (Wang et al. 2017)",
        ),
        BundledModel(
            "nenchev_pa10_arm", nenchev_pa10_arm,
            "PA-10 4-DOF positioning arm, fixed base (Nenchev and Tsumaki)",
        ),
        BundledModel(
            "bluerov2_heavy_alpha5",
            bluerov2_heavy_alpha5,
            "BlueROV2 Heavy + Reach Alpha 5, from URDF",
        ),
    )
}


def bundled_models() -> list[str]:
    """Names of the bundled models."""
    return list(_REGISTRY)


def bundled_entry(name: str) -> BundledModel:
    """Registry entry of a bundled model.

    Raises:
        UnknownModelError: unknown name (the message lists the bundled models).
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise UnknownModelError(name, _REGISTRY) from None
