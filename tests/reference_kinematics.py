"""Independent reference computations shared by the task tests (plain numpy, no fast paths)."""

from __future__ import annotations

import math

import numpy as np


def reference_manipulability(J6, rows):
    """``w = sqrt(det(J_S J_S^T))`` and ``dw/dq_i = w trace(dJ_S/dq_i J_S^+)``.

    ``000_7b5f597fe4e36aa4.txt``, Eq. (18)-(19), with the columns' derivatives of a serial arm's
    twist Jacobian ``J6 = [V; W]`` (arm-base axes): joint ``i`` moves the columns after it.

    Args:
        J6: Twist Jacobian (6, n) of the arm.
        rows: Selected rows ``S`` (any sequence of indices).
    """
    rows = list(rows)
    Js = J6[rows]
    k, n = Js.shape
    G = Js @ Js.T if k <= n else Js.T @ Js
    w = math.sqrt(max(np.linalg.det(G), 0.0))
    pinv = np.linalg.pinv(Js)
    V, W = J6[:3], J6[3:]
    grad = np.zeros(n)
    for i in range(n):
        dJ = np.zeros((6, n))
        for j in range(n):
            if i <= j:  # joint i moves the columns after it
                dJ[:3, j] = np.cross(W[:, i], V[:, j])
                dJ[3:, j] = np.cross(W[:, i], W[:, j])
            else:
                dJ[:3, j] = np.cross(W[:, j], V[:, i])
        grad[i] = w * np.trace(dJ[rows] @ pinv)
    return w, grad
