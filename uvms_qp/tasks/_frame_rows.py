"""Row maths of the frame tasks: orientation and pose rows on the SO(3) log map."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from .._validation import FloatArray


def skew(r: FloatArray) -> FloatArray:
    """``[r]_x`` with ``[r]_x w = r x w``."""
    x, y, z = r.tolist()
    return np.array(((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0)))



def pose_rows(J: FloatArray, T: FloatArray, p_d: Any, R_d: Any, v_d: Any, w_d: Any,
              J_ref: FloatArray | None, with_position: bool
              ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
    """Rows of the orientation and pose modes (all axes) of a frame task, in world axes.

    ``J_ref`` is the reference frame's twist Jacobian (None: the target does not move with
    zeta); ``p_d``, ``R_d``, ``v_d``, ``w_d`` the target and its rates in world axes;
    ``with_position``: the position rows first (pose), else the orientation rows only.
    """
    R_e = R_d @ T[:3, :3].T
    Jlog = pin.Jlog3(R_e)
    e_o = pin.log3(R_e)
    rows = np.empty((6 if with_position else 3, J.shape[1]))
    J_o = rows[3:] if with_position else rows
    np.dot(Jlog, J[3:], out=J_o)
    if J_ref is not None:
        J_o -= Jlog.T @ J_ref[3:]
    ff_o = None if w_d is None else Jlog.T @ w_d
    if not with_position:
        return rows, e_o, ff_o
    rows[:3] = J[:3]
    e = np.concatenate((p_d - T[:3, 3], e_o))
    if v_d is None and ff_o is None:
        return rows, e, None
    ff = np.zeros(6)
    if v_d is not None:
        ff[:3] = v_d
    if ff_o is not None:
        ff[3:] = ff_o
    return rows, e, ff
