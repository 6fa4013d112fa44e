"""Davies method with a virtual PPPS chain (dos Santos et al. (2006), Eq. (5)-(8), (14)-(26)).

The UVMS is an open chain: the vehicle (itself a PPPS chain: three prismatic joints along the
reference axes and a spherical joint, Eq. 5-8) followed by the arm. A virtual PPPS chain from the
reference frame to the end effector closes it; the Kirchhoff-Davies circulation law
``N Psi = 0`` (Eq. 16) over the network matrix ``N = [N_vehicle, N_arm, -N_virtual]`` (Eq. 19)
then relates all rates. Splitting the magnitudes into primary (imposed) and secondary (solved)
ones gives ``Psi_s = -N_s^{-1} N_p Psi_p`` (Eq. 18):

- direct kinematics (Eq. 21-22): impose vehicle and arm rates, solve the virtual (end-effector)
  rates;
- kinematic-constraint inverse (Eq. 25-26): impose the end-effector rates *and* the vehicle rates
  (e.g. at rest, yaw rate aligning the heading with the current), solve the arm rates.

Magnitude order used throughout: each PPPS chain is ``[px, py, pz, rx, ry, rz]`` (the paper lists
the virtual ones as ``rz, ry, rx, pz, py, px``; the order is a convention). With the virtual
spherical joint centred at the end-effector point E, the virtual magnitudes are
``[v_E; omega_E]``: the linear velocity of E and the angular velocity, in the reference axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validation import as_matrix, as_vector
from ..errors import InputError, ShapeError
from ._checks import FloatArray, indices, jacobian
from .screws import planar_chain_points, planar_chain_screws, planar_rows, screw_transform

PPPS_NAMES = ("px", "py", "pz", "rx", "ry", "rz")


def ppps_screws(rotation: Any = None, centre: Any = None) -> FloatArray:
    """Normalised screws of a PPPS chain, columns ``[px, py, pz, rx, ry, rz]`` (Eq. (6)).

    In its own C-frame (rotation I, centre at the origin) these are the unit vectors of Eq. (6)
    (whose ``pz`` is misprinted as all zeros; it is ``(0, 0, 0; 0, 0, 1)``). ``rotation`` gives the
    chain axes in the reference frame (Eq. 8: ``V T_C`` with ``V R_C``) and ``centre`` the centre of
    the spherical joint (the vehicle origin, or the end-effector point for the virtual chain).

    Args:
        rotation: (3, 3) rotation from the chain frame to the reference frame; None means I.
        centre: (3,) spherical-joint centre in the reference frame [m]; None means the origin.

    Returns:
        (6, 6) screws as columns.
    """
    R = np.eye(3) if rotation is None else as_matrix(rotation, "rotation", 3, 3)
    c = np.zeros(3) if centre is None else as_vector(centre, "centre", 3)
    local = np.zeros((6, 6))
    local[3:, :3] = np.eye(3)  # prismatic: [0; S]
    local[:3, 3:] = np.eye(3)  # revolute through the chain origin: [S; 0]
    return screw_transform(R, c) @ local


def network_matrix(vehicle: Any, arm: Any, virtual: Any) -> FloatArray:
    """Network matrix ``N = [N_vehicle, N_arm, -N_virtual]`` of the closed loop, Eq. (19).

    Args:
        vehicle: (r, n_v) vehicle screws (r = 6, or 3 planar rows).
        arm: (r, n_a) arm screws.
        virtual: (r, n_e) virtual-chain screws.

    Returns:
        (r, n_v + n_a + n_e) matrix; ``N Psi = 0`` for the magnitudes ``[Psi_v; Psi_a; Psi_e]``.
    """
    V = jacobian(vehicle, "vehicle")
    A = jacobian(arm, "arm")
    E = jacobian(virtual, "virtual")
    r = V.shape[0]
    for name, M in (("arm", A), ("virtual", E)):
        if M.shape[0] != r:
            raise ShapeError(f"{name}: expected {r} rows like vehicle, got {M.shape[0]}")
    return np.hstack([V, A, -E])


def davies_solve(
    N: Any, primary: Sequence[int], primary_rates: Any, cond_max: float = 1e12
) -> FloatArray:
    """Solve the circulation law for the secondary magnitudes, Eq. (17)-(18).

    ``Psi_s = -N_s^{-1} N_p Psi_p``, with ``N_p`` the columns listed in ``primary`` and ``N_s``
    the others, which must form a square non-singular matrix.

    Args:
        N: (r, c) network matrix.
        primary: Indices of the c - r imposed magnitudes.
        primary_rates: Their values, in the same order.
        cond_max: Largest accepted condition number of ``N_s``.

    Returns:
        (c,) all magnitudes, imposed and solved, in column order.

    Raises:
        InputError: repeated/out-of-range indices, a non-square ``N_s``, or a singular ``N_s``
            (the chain is at a singularity for this choice of primary pairs).
    """
    N = jacobian(N, "N")
    r, c = N.shape
    idx = indices(primary, "primary")
    if len(set(idx)) != len(idx) or any(i < 0 or i >= c for i in idx):
        raise InputError(f"primary: expected distinct indices in [0, {c}), got {list(primary)}")
    rates = as_vector(primary_rates, "primary_rates", len(idx))
    secondary = [i for i in range(c) if i not in set(idx)]
    if len(secondary) != r:
        raise InputError(
            f"primary: {len(idx)} imposed magnitudes leave {len(secondary)} unknowns for {r} "
            f"loop equations; impose exactly {c - r}"
        )
    Ns = N[:, secondary]
    cond = np.linalg.cond(Ns)
    if not np.isfinite(cond) or cond > cond_max:
        raise InputError(
            f"secondary network matrix is singular (condition number {cond:.3g}); "
            "the chain is at a singularity for this choice of primary pairs"
        )
    out = np.zeros(c)
    out[idx] = rates
    out[secondary] = -np.linalg.solve(Ns, N[:, idx] @ rates)
    return out


def davies_direct(
    vehicle: Any, arm: Any, virtual: Any, vehicle_rates: Any, arm_rates: Any
) -> FloatArray:
    """UVMS direct kinematics by the Davies method, Eq. (19)-(22).

    Returns:
        (n_e,) virtual-chain magnitudes (the end-effector rates, e.g. ``[v_E; omega_E]``).
    """
    N = network_matrix(vehicle, arm, virtual)
    nv = np.shape(vehicle)[1]
    na = np.shape(arm)[1]
    rates = np.concatenate(
        [as_vector(vehicle_rates, "vehicle_rates", nv), as_vector(arm_rates, "arm_rates", na)]
    )
    return davies_solve(N, list(range(nv + na)), rates)[nv + na :]


def kinematic_constraint_inverse(
    vehicle: Any, arm: Any, virtual: Any, end_effector_rates: Any, vehicle_rates: Any
) -> FloatArray:
    """Kinematic-constraint inverse kinematics, Eq. (23)-(26).

    Primary (imposed) magnitudes: the virtual chain (desired end-effector rates) and the vehicle
    rates (e.g. zero linear rates to keep it at rest and a yaw rate aligning it with the current);
    secondary: the arm joint rates, ``Psi_a = -N_a^{-1} (N_v Psi_v - N_e Psi_e)``.

    Args:
        vehicle: (r, n_v) vehicle screws.
        arm: (r, r) arm screws (square: as many arm joints as loop equations).
        virtual: (r, n_e) virtual-chain screws.
        end_effector_rates: (n_e,) desired virtual magnitudes.
        vehicle_rates: (n_v,) imposed vehicle magnitudes.

    Returns:
        (r,) arm joint rates.
    """
    N = network_matrix(vehicle, arm, virtual)
    nv = np.shape(vehicle)[1]
    na = np.shape(arm)[1]
    ne = np.shape(virtual)[1]
    primary = list(range(nv)) + list(range(nv + na, nv + na + ne))
    rates = np.concatenate(
        [
            as_vector(vehicle_rates, "vehicle_rates", nv),
            as_vector(end_effector_rates, "end_effector_rates", ne),
        ]
    )
    return davies_solve(N, primary, rates)[nv : nv + na]


def planar_uvms_screws(
    vehicle_pose: Any,
    joint_angles: Any,
    link_lengths: Any,
    mount: Any = (0.0, 0.0),
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Planar screws ``(omega_z, v_x, v_y)`` of a planar UVMS closed by a virtual chain.

    Vehicle: ``[px, py, rz]`` through the vehicle origin (world axes, so its magnitudes are
    ``[x_dot, y_dot, psi_dot]``); arm: revolute z joints; virtual chain: ``[px, py, rz]`` centred at
    the tip, magnitudes ``[x_E_dot, y_E_dot, psi_E_dot]``. The simulation of
    dos Santos et al. (2006): 2 m links, ``mount = (2.5, 0)`` m ahead of the vehicle centre.

    Args:
        vehicle_pose: (3,) ``[x, y, psi]`` [m, m, rad].
        joint_angles: (n,) arm joint angles [rad].
        link_lengths: (n,) link lengths [m].
        mount: (2,) arm base in the vehicle frame [m].

    Returns:
        ``(vehicle, arm, virtual)`` planar screws, shapes (3, 3), (3, n), (3, 3).
    """
    x, y, psi = as_vector(vehicle_pose, "vehicle_pose", 3)
    m = as_vector(mount, "mount", 2)
    c, s = np.cos(psi), np.sin(psi)
    base = np.array([x + c * m[0] - s * m[1], y + s * m[0] + c * m[1]])
    points, _ = planar_chain_points(joint_angles, link_lengths, base, psi)
    pick = [0, 1, 5]  # px, py, rz
    vehicle = planar_rows(ppps_screws(centre=[x, y, 0.0]))[:, pick]
    arm = planar_rows(planar_chain_screws(joint_angles, link_lengths, base, psi))
    virtual = planar_rows(ppps_screws(centre=points[-1]))[:, pick]
    return vehicle, arm, virtual
