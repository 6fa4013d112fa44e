"""Reference trajectories for a frame: position and optional orientation as functions of time.

Every trajectory implements :meth:`Trajectory.sample` and returns a :class:`TrajectorySample` with
the position ``p(t)`` [m] and velocity ``p_dot(t)`` [m/s] in the world frame, and, when an
orientation is prescribed, the rotation ``R(t) = R_world_frame`` and the angular velocity
``omega(t)`` [rad/s] in world axes. Tasks consume them as targets with feed-forward terms
(closed-loop inverse kinematics, Soylu et al. (2007), Eq. (16)).

Time is clamped: before ``start_time`` a trajectory holds its first sample, after
``start_time + duration`` its last one, both with zero velocity. Planar scenarios use the same
3-vectors with ``z = 0``: points may be given as ``(x, y)``, all of a trajectory's points with the
same number of coordinates, and :attr:`Trajectory.dimension` records 2 so that a task bound to a
non-planar model rejects the trajectory instead of driving the frame to ``z = 0``.

Rotations between two orientations follow the geodesic ``R(s) = R0 Exp(s log(R0^T R1))``, whose
world angular velocity is ``omega = R0 log(R0^T R1) s_dot`` (the axis is constant along a geodesic).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np
import pinocchio as pin

from .._validation import FloatArray, as_matrix, as_scalar, as_vector
from ..errors import InputError, ShapeError

Profile = Literal["quintic", "linear"]
_ZERO3 = np.zeros(3)


@dataclass(frozen=True)
class TrajectorySample:
    """One sample of a reference trajectory.

    Attributes:
        position: Target position (3,) [m], world frame.
        velocity: Feed-forward linear velocity (3,) [m/s], world frame.
        rotation: Target rotation ``R_world_frame`` (3, 3), or None for a position-only trajectory.
        angular_velocity: Feed-forward angular velocity (3,) [rad/s] in world axes, or None.
    """

    position: FloatArray
    velocity: FloatArray
    rotation: FloatArray | None = None
    angular_velocity: FloatArray | None = None


def _points(named: Sequence[tuple[str, Any]]) -> tuple[list[FloatArray], int]:
    """Validate points given with the same number of coordinates; return them as 3-vectors.

    Args:
        named: ``(argument name, value)`` pairs, each 2 ``(x, y)`` or 3 ``(x, y, z)`` values [m].

    Returns:
        The points as 3-vectors (``z = 0`` for 2 values) and the number of coordinates given.

    Raises:
        ShapeError: a point with neither 2 nor 3 coordinates.
        InputError: two points with different numbers of coordinates (a 2-value point next to
            a 3-value one would silently be taken at ``z = 0``).
    """
    out: list[FloatArray] = []
    first = ""
    size = 0
    for name, value in named:
        array = as_vector(value, name)
        if array.shape[0] not in (2, 3):
            raise ShapeError(f"{name}: expected 2 or 3 coordinates, got {array.shape[0]}")
        if not out:
            first, size = name, array.shape[0]
        elif array.shape[0] != size:
            raise InputError(
                f"{name}: got {array.shape[0]} coordinates but {first} has {size}; give every "
                "point 3 coordinates (x, y, z), or 2 (x, y) on planar models"
            )
        out.append(array if size == 3 else np.array([array[0], array[1], 0.0]))
    return out, size


def as_rotation(value: Any, name: str) -> FloatArray:
    """Validate a rotation: a 3x3 orthonormal matrix with det +1, or ``[roll, pitch, yaw]`` [rad].

    Euler angles follow the Z-Y-X convention of ``docs/notation.md``: ``R = Rz(yaw) Ry(pitch)
    Rx(roll)``.

    Raises:
        ShapeError: neither 3 angles nor a 3x3 matrix.
        InputError: a matrix that is not a rotation (tolerance 1e-6).
    """
    try:
        ndim = np.ndim(value)
    except ValueError as exc:
        raise InputError(f"{name}: expected 3 angles or a 3x3 matrix") from exc
    if ndim <= 1:
        rpy = as_vector(value, name, 3)
        return np.asarray(pin.rpy.rpyToMatrix(rpy), dtype=np.float64)
    R = as_matrix(value, name, 3, 3)
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0.0:
        raise InputError(f"{name}: expected a rotation matrix (orthonormal, det +1)")
    return R


def _time_scaling(tau: float, profile: Profile) -> tuple[float, float]:
    """Return ``(s, ds/dtau)`` of a rest-to-rest time scaling on ``tau`` in [0, 1].

    Quintic: ``s = 10 tau^3 - 15 tau^4 + 6 tau^5`` (zero velocity and acceleration at both ends);
    linear: ``s = tau`` (constant speed).
    """
    if profile == "linear":
        return tau, 1.0
    t2 = tau * tau
    return t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2), 30.0 * t2 * (1.0 - 2.0 * tau + t2)


class Trajectory(ABC):
    """Base class: a reference for one frame over ``[start_time, start_time + duration]``.

    Attributes:
        duration: Length of the moving part [s].
        start_time: Time at which the motion starts [s]; the first sample is held before it.
        dimension: Number of coordinates the points were given with: 3 ``(x, y, z)``, or 2
            ``(x, y)`` for a planar trajectory (samples are still 3-vectors, with ``z = 0``).
    """

    dimension: int = 3

    def __init__(self, duration: float, start_time: float = 0.0) -> None:
        self.duration = as_scalar(duration, "duration", positive=True)
        self.start_time = as_scalar(start_time, "start_time", nonnegative=True)

    @property
    def end_time(self) -> float:
        """Time at which the motion ends [s]."""
        return self.start_time + self.duration

    def sample(self, t: float) -> TrajectorySample:
        """Return the reference at time ``t`` [s] (clamped to the trajectory's time span)."""
        local = float(t) - self.start_time
        if not math.isfinite(local):
            raise InputError(f"t: expected a finite time, got {t}")
        if local <= 0.0:
            return self._at_rest(self._sample(0.0))
        if local >= self.duration:
            return self._at_rest(self._sample(self.duration))
        return self._sample(local)

    @staticmethod
    def _at_rest(sample: TrajectorySample) -> TrajectorySample:
        omega = None if sample.rotation is None else _ZERO3.copy()
        return TrajectorySample(sample.position, _ZERO3.copy(), sample.rotation, omega)

    @abstractmethod
    def _sample(self, local_t: float) -> TrajectorySample:
        """Return the sample at ``local_t`` in ``[0, duration]`` (time since start)."""


class _Geodesic:
    """Rotation path ``R(s) = R0 Exp(s w)`` with ``w = log(R0^T R1)``."""

    def __init__(self, R0: FloatArray, R1: FloatArray) -> None:
        self.R0 = R0
        self.w = np.asarray(pin.log3(R0.T @ R1), dtype=np.float64)
        self.w_world = R0 @ self.w

    def at(self, s: float, s_dot: float) -> tuple[FloatArray, FloatArray]:
        R = self.R0 @ np.asarray(pin.exp3(s * self.w), dtype=np.float64)
        return R, self.w_world * s_dot


class SegmentTrajectory(Trajectory):
    """Straight-line motion between two points with a rest-to-rest or constant-speed profile.

    ``p(t) = p0 + s(t/T) (p1 - p0)``, ``p_dot = s'(t/T) (p1 - p0) / T``, with ``s`` quintic
    (:class:`QuinticTrajectory`) or linear (:class:`LineTrajectory`). An orientation, when both
    ``start_rotation`` and ``goal_rotation`` are given, follows the geodesic with the same ``s``.

    Args:
        start: Start position (3,) [m], world frame (or ``(x, y)`` for a planar model).
        goal: Goal position [m], world frame, with as many coordinates as ``start``.
        duration: Motion time T [s] (> 0).
        start_rotation: Optional start orientation (3x3 or roll-pitch-yaw [rad]).
        goal_rotation: Optional goal orientation; defaults to ``start_rotation``.
        start_time: Start of the motion [s].
        profile: ``"quintic"`` or ``"linear"``.
    """

    def __init__(
        self,
        start: Sequence[float] | FloatArray,
        goal: Sequence[float] | FloatArray,
        duration: float,
        start_rotation: Any = None,
        goal_rotation: Any = None,
        start_time: float = 0.0,
        profile: Profile = "quintic",
    ) -> None:
        super().__init__(duration, start_time)
        if profile not in ("quintic", "linear"):
            raise InputError(f"profile: expected 'quintic' or 'linear', got {profile!r}")
        self.profile: Profile = profile
        (self.start, self.goal), self.dimension = _points([("start", start), ("goal", goal)])
        self._delta = self.goal - self.start
        self._geodesic: _Geodesic | None = None
        if start_rotation is None and goal_rotation is not None:
            raise InputError("start_rotation: required when goal_rotation is given")
        if start_rotation is not None:
            R0 = as_rotation(start_rotation, "start_rotation")
            R1 = R0 if goal_rotation is None else as_rotation(goal_rotation, "goal_rotation")
            self._geodesic = _Geodesic(R0, R1)

    def _sample(self, local_t: float) -> TrajectorySample:
        s, ds = _time_scaling(local_t / self.duration, self.profile)
        s_dot = ds / self.duration
        position = self.start + s * self._delta
        velocity = s_dot * self._delta
        if self._geodesic is None:
            return TrajectorySample(position, velocity)
        R, omega = self._geodesic.at(s, s_dot)
        return TrajectorySample(position, velocity, R, omega)


class _FixedProfileSegment(SegmentTrajectory):
    """A :class:`SegmentTrajectory` whose time scaling is set by the class (``_profile``).

    Its constructor has no ``profile`` argument, so a scenario cannot contradict the type.
    """

    _profile: ClassVar[Profile] = "quintic"

    def __init__(
        self,
        start: Sequence[float],
        goal: Sequence[float],
        duration: float,
        start_rotation: Any = None,
        goal_rotation: Any = None,
        start_time: float = 0.0,
    ) -> None:
        super().__init__(
            start, goal, duration, start_rotation, goal_rotation, start_time, self._profile
        )


class QuinticTrajectory(_FixedProfileSegment):
    """Point-to-point motion along a straight line with a quintic, rest-to-rest time scaling."""

    _profile = "quintic"


class LineTrajectory(_FixedProfileSegment):
    """Straight line at constant speed (Nenchev and Tsumaki's straight-line runs, Section 4)."""

    _profile = "linear"


class CircleTrajectory(Trajectory):
    """Circle at constant angular rate in a plane (dos Santos et al. (2006): 1 m diameter, 2 turns).

    ``p(t) = c + r (cos(a) e1 + sin(a) e2)``, ``a = a0 + 2 pi n t / T``, with ``e1``, ``e2`` an
    orthonormal basis of the plane whose normal is ``normal`` (positive turns are counter-clockwise
    about ``normal``). The orientation, when given, is held constant.

    Args:
        center: Circle centre (3,) [m], world frame.
        radius: Radius r [m] (> 0).
        duration: Time T for all turns [s].
        turns: Number of turns n (non-zero; negative turns run clockwise).
        start_angle: Angle a0 of the first point [rad], measured from ``e1``.
        normal: Plane normal (3,), world frame; default world z (the horizontal plane).
        rotation: Optional constant orientation (3x3 or roll-pitch-yaw [rad]).
        start_time: Start of the motion [s].
    """

    def __init__(
        self,
        center: Sequence[float],
        radius: float,
        duration: float,
        turns: float = 1.0,
        start_angle: float = 0.0,
        normal: Sequence[float] = (0.0, 0.0, 1.0),
        rotation: Any = None,
        start_time: float = 0.0,
    ) -> None:
        super().__init__(duration, start_time)
        (self.center,), self.dimension = _points([("center", center)])
        self.radius = as_scalar(radius, "radius", positive=True)
        self.turns = as_scalar(turns, "turns")
        if self.turns == 0.0:
            raise InputError("turns: expected a non-zero number of turns")
        self.start_angle = as_scalar(start_angle, "start_angle")
        n = as_vector(normal, "normal", 3)
        norm = float(np.linalg.norm(n))
        if norm < 1e-9:
            raise InputError("normal: expected a non-zero vector")
        n = n / norm
        seed = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        e1 = seed - n * float(seed @ n)
        self._e1 = e1 / np.linalg.norm(e1)
        self._e2 = np.cross(n, self._e1)
        self._rate = 2.0 * math.pi * self.turns / self.duration  # [rad/s]
        self.rotation = None if rotation is None else as_rotation(rotation, "rotation")

    def _sample(self, local_t: float) -> TrajectorySample:
        a = self.start_angle + self._rate * local_t
        c, s = math.cos(a), math.sin(a)
        position = self.center + self.radius * (c * self._e1 + s * self._e2)
        velocity = self.radius * self._rate * (-s * self._e1 + c * self._e2)
        if self.rotation is None:
            return TrajectorySample(position, velocity)
        return TrajectorySample(position, velocity, self.rotation, _ZERO3.copy())


class WaypointTrajectory(Trajectory):
    """Rest-to-rest quintic segments through a list of waypoints reached at given times.

    Segment ``k`` goes from ``points[k]`` at ``times[k]`` to ``points[k+1]`` at ``times[k+1]`` with
    the quintic scaling of :class:`QuinticTrajectory` (the frame stops at every waypoint). The
    first time is the start time. Orientations, when given (one per waypoint), follow the geodesic
    of each segment.

    Args:
        points: Waypoints (k >= 2, 3) [m], world frame (or all ``(x, y)`` for a planar model).
        times: Strictly increasing arrival times (k,) [s], ``times[0] >= 0``.
        rotations: Optional orientation per waypoint (3x3 or roll-pitch-yaw [rad]).
    """

    def __init__(
        self,
        points: Sequence[Sequence[float]],
        times: Sequence[float],
        rotations: Sequence[Any] | None = None,
    ) -> None:
        pts, dimension = _points([(f"points[{i}]", p) for i, p in enumerate(points)])
        if len(pts) < 2:
            raise InputError(f"points: expected at least 2 waypoints, got {len(pts)}")
        ts = as_vector(times, "times", len(pts))
        steps = np.diff(ts)
        if np.any(steps <= 0.0):
            i = int(np.flatnonzero(steps <= 0.0)[0])
            raise InputError(f"times: expected strictly increasing times (times[{i + 1}])")
        super().__init__(float(ts[-1] - ts[0]), float(ts[0]))
        self.points = np.array(pts)
        self.times = ts
        self.dimension = dimension
        rots: list[FloatArray] | None = None
        if rotations is not None:
            if len(rotations) != len(pts):
                raise ShapeError(f"rotations: expected {len(pts)} rotations, got {len(rotations)}")
            rots = [as_rotation(r, f"rotations[{i}]") for i, r in enumerate(rotations)]
        self._segments = [
            SegmentTrajectory(
                pts[k],
                pts[k + 1],
                float(ts[k + 1] - ts[k]),
                None if rots is None else rots[k],
                None if rots is None else rots[k + 1],
                0.0,
                "quintic",
            )
            for k in range(len(pts) - 1)
        ]

    def _sample(self, local_t: float) -> TrajectorySample:
        t = local_t + self.start_time
        k = int(np.searchsorted(self.times, t, side="right")) - 1
        k = min(max(k, 0), len(self._segments) - 1)
        segment = self._segments[k]
        return segment._sample(min(t - float(self.times[k]), segment.duration))


class FixedTarget(Trajectory):
    """A constant target (position and optional orientation) with zero feed-forward velocity.

    Args:
        position: Target position (3,) [m], world frame.
        rotation: Optional orientation (3x3 or roll-pitch-yaw [rad]).
    """

    def __init__(self, position: Sequence[float], rotation: Any = None) -> None:
        super().__init__(1.0, 0.0)
        (self.position,), self.dimension = _points([("position", position)])
        self.rotation = None if rotation is None else as_rotation(rotation, "rotation")

    def _sample(self, local_t: float) -> TrajectorySample:
        omega = None if self.rotation is None else _ZERO3.copy()
        return TrajectorySample(self.position, _ZERO3.copy(), self.rotation, omega)


#: Scenario ``type`` strings of the trajectory classes.
TRAJECTORY_TYPES: dict[str, type[Trajectory]] = {
    "quintic": QuinticTrajectory,
    "line": LineTrajectory,
    "circle": CircleTrajectory,
    "waypoints": WaypointTrajectory,
    "fixed": FixedTarget,
}
