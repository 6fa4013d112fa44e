"""Where a frame task's trajectory starts, against where its frame is at the initial state.

A scenario whose trajectory starts away from the frame it moves runs (the hard bounds hold and
the error decays at the task's gain), but it is rarely what its author meant: the run begins
with a transient toward the path, and the tracking metrics (``ee_error_max``, the settling time)
measure that transient rather than the tracking. So loading such a scenario warns
(:class:`~uvms_qp.errors.ScenarioWarning`) with the distance and where the frame is; it does not
refuse it, because starting away on purpose (a convergence study, a target reached from afar)
is legitimate.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..errors import ScenarioWarning
from ..tasks.targets import InFrame, TrajectoryTarget

if TYPE_CHECKING:  # pragma: no cover
    from ..model import State
    from ..stack import Stack

#: Distance [m] from a trajectory's first position to its frame beyond which loading warns.
FAR_POSITION = 0.01
#: Angle [rad] between a trajectory's first rotation and its frame's beyond which loading warns.
FAR_ANGLE = 0.05

_POSITION_AXES = ("x", "y", "z")
_ROTATION_AXES = ("rx", "ry", "rz")


def far_starts(stack: Stack, state: State) -> list[str]:
    """One message per task whose trajectory starts away from its frame at ``state``.

    Only the axes a task controls count (a planar task ignores z). ``stack`` is bound;
    ``state`` is the initial one; the trajectory is sampled at ``t = 0``.
    """
    messages = []
    for task in stack.tasks:
        setpoint = getattr(task, "setpoint", None)
        target = setpoint.target if isinstance(setpoint, InFrame) else setpoint
        if not isinstance(target, TrajectoryTarget):
            continue
        p_d, R_d = task.target(0.0, state)  # type: ignore[attr-defined]
        frame = task.frame  # type: ignore[attr-defined]
        axes = task.axes  # type: ignore[attr-defined]
        p, R = state.position(frame), state.rotation(frame)
        found = []
        position_axes = [i for i, a in enumerate(_POSITION_AXES) if a in axes]
        if p_d is not None and position_axes:
            distance = float(np.linalg.norm((p_d - p)[position_axes]))
            if distance > FAR_POSITION:
                found.append(f"{distance:.3g} m from the frame {frame!r} (the trajectory at "
                             f"{_xyz(p_d)}, the frame at {_xyz(p)} [m], world)")
        rotation_axes = [i for i, a in enumerate(_ROTATION_AXES) if a in axes]
        if R_d is not None and rotation_axes:
            angle = float(np.linalg.norm(pin.log3(R_d @ R.T)[rotation_axes]))
            if angle > FAR_ANGLE:
                found.append(f"turned {angle:.3g} rad from the frame {frame!r}")
        if found:
            messages.append(
                f"task {task.name!r}: its trajectory starts {' and '.join(found)} at the initial "
                "configuration: the run begins with a transient toward the path, and the "
                "tracking metrics measure it; start the trajectory where the frame is (the "
                f"tool's pose at home, the start without [initial]: `uvms-qp models "
                f"{state.model.name}`)")
    return messages


def warn_far_starts(stack: Stack, state: State) -> None:
    """Warn (:class:`~uvms_qp.errors.ScenarioWarning`) once per message of :func:`far_starts`."""
    for message in far_starts(stack, state):
        warnings.warn(message, ScenarioWarning, stacklevel=3)


def _xyz(p: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4f}" for v in p) + "]"
