"""Units of the recorded series, from the model's joint types.

``zeta`` is ``[actuated vehicle body rates; joint rates]``: the linear body rates ``u, v, w`` are
in [m/s], the angular ones ``p, q, r`` in [rad/s], a revolute joint's rate in [rad/s] and a
prismatic joint's in [m/s]; joint positions are in [rad] or [m] likewise.
"""

from __future__ import annotations

import re
from typing import Any

#: Pinocchio's prismatic joint models (``JointModelPX``, ..., ``JointModelPrismaticUnaligned``).
_PRISMATIC = re.compile(r"JointModel(P[XYZ]|PrismaticUnaligned)")
#: Linear vehicle body rates (the others are angular).
LINEAR_RATES = ("u", "v", "w")


def joint_units(model: Any) -> tuple[str, ...]:
    """Unit of each arm joint's position: ``"m"`` (prismatic) or ``"rad"`` (revolute)."""
    pin_model = model.pin_model
    units = []
    for name in model.joint_names:
        joint = pin_model.joints[pin_model.getJointId(name)]
        units.append("m" if _PRISMATIC.fullmatch(joint.shortname()) else "rad")
    return tuple(units)


def zeta_units(model: Any) -> tuple[str, ...]:
    """Unit of each entry of ``zeta`` (``model.zeta_names``): ``"m/s"`` or ``"rad/s"``."""
    vehicle = tuple("m/s" if name in LINEAR_RATES else "rad/s" for name in model.actuated)
    return vehicle + tuple(f"{unit}/s" for unit in joint_units(model))
