"""Targets of a frame task as values: fixed, along a trajectory, held, or in a moving frame.

A target says where a frame should be at time ``t``: a position [m], a rotation, and their
rates (feed-forward), in a reference frame. It is a value: it holds no run-time state, so one
target may serve any number of tasks and controllers; a held target keeps the pose it holds in
the slot of the task that evaluates it (:class:`~uvms_qp.tasks.slot.TaskSlot`), so each
controller holds its own.

* :class:`FixedPose`: a position and/or rotation (from a position, a rotation, a
  ``pinocchio.SE3``, a 4x4 homogeneous matrix or ``{"xyz", "rpy"}``), optional rates;
* :class:`TrajectoryTarget`: any object with ``sample(t)`` returning ``position``,
  ``velocity`` and optionally ``rotation``, ``angular_velocity``
  (:mod:`uvms_qp.sim.trajectories`);
* :class:`HeldPose`: the pose the frame has when the task starts ("stay where you are");
* :class:`InFrame`: any of these expressed in a frame of the model (``"vehicle"``,
  ``"arm_base"``, a link carrying an object) instead of the world frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_vector
from ..errors import InputError, ShapeError
from ._common import as_point, as_pose, as_rotation, check_choice, check_planar_point

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State
    from .slot import TaskSlot

_POINT = (3,)  # the shape of a sampled position or (angular) velocity
_ROTATION = (3, 3)  # the shape of a sampled rotation

#: ``(position [m], rotation, velocity [m/s], angular velocity [rad/s])``, each None when unset.
Sample = tuple[Any, Any, Any, Any]


class Target:
    """Where a frame should be at time ``t``, in its reference frame (:attr:`frame`)."""

    frame = "world"

    def sample(self, t: float, state: State, slot: TaskSlot, task: Any) -> Sample:
        """The target at ``(state, t)`` for ``task`` (evaluated with its memory ``slot``)."""
        raise NotImplementedError  # pragma: no cover


@dataclass(frozen=True, eq=False)
class FixedPose(Target):
    """A fixed position (3,) [m] and/or rotation (3, 3), with optional rates (validated)."""

    position: FloatArray | None = None
    rotation: FloatArray | None = None
    velocity: FloatArray | None = None
    angular_velocity: FloatArray | None = None
    planar: tuple[str, ...] = ()
    """Arguments given as ``(x, y)`` before the model was known (checked when bound)."""

    def sample(self, t: float, state: State, slot: TaskSlot, task: Any) -> Sample:
        """The fixed values."""
        return self.position, self.rotation, self.velocity, self.angular_velocity


@dataclass(frozen=True, eq=False)
class TrajectoryTarget(Target):
    """The samples of ``trajectory`` (``sample(t)``); ``rotation`` when its samples have none."""

    trajectory: Any
    rotation: FloatArray | None = None

    def sample(self, t: float, state: State, slot: TaskSlot, task: Any) -> Sample:
        """``trajectory.sample(t)``, its shapes checked (one test per tick)."""
        s = self.trajectory.sample(t)
        try:
            p, v = s.position, s.velocity
        except AttributeError:
            raise not_a_sample(task.name, s) from None
        p = np.asarray(p, dtype=np.float64)
        if v is not None:
            v = np.asarray(v, dtype=np.float64)
        if p.shape != _POINT or (v is not None and v.shape != _POINT):
            raise _shape_error(task.name, t, position=p, velocity=v)
        rot = getattr(s, "rotation", None)
        if rot is None:
            return p, self.rotation, v, None
        rot = np.asarray(rot, dtype=np.float64)
        w = getattr(s, "angular_velocity", None)
        if w is not None:
            w = np.asarray(w, dtype=np.float64)
        if rot.shape != _ROTATION or (w is not None and w.shape != _POINT):
            raise _shape_error(task.name, t, rotation=rot, angular_velocity=w)
        return p, rot, v, w


class HeldPose(Target):
    """The pose the frame has at its first evaluation with a slot.

    That is after the controller is built or reset, or when the task enters the stack; the pose
    is kept in the slot, one per controller.
    """

    def sample(self, t: float, state: State, slot: TaskSlot, task: Any) -> Sample:
        """The held pose, taken from ``state`` the first time."""
        held = slot.held  # type: ignore[attr-defined]
        if held is None or slot.held_for is not self:  # type: ignore[attr-defined]
            T = task.frame_pose(state)
            held = slot.held = (np.array(T[:3, 3]), np.array(T[:3, :3]))  # type: ignore[attr-defined]
            slot.held_for = self  # type: ignore[attr-defined]
        return held[0], held[1], None, None


@dataclass(frozen=True, eq=False)
class InFrame(Target):
    """``target`` expressed in the frame ``frame`` of the model (re-evaluated every tick)."""

    target: Target
    frame: str = "world"  # type: ignore[misc]

    def sample(self, t: float, state: State, slot: TaskSlot, task: Any) -> Sample:
        """The inner target's sample, in :attr:`frame`."""
        return self.target.sample(t, state, slot, task)


def target_from(keys: dict[str, Any], name: str, reference: str, model: Model | None,
                current: Target | None) -> Target:
    """The target of task ``name`` that the keys of ``EndEffectorTask.set_target`` give.

    Validated, in ``reference`` (an :class:`InFrame` unless ``"world"``). A fixed position or
    rotation left out keeps the one of the ``current`` fixed target.

    Raises:
        InputError: no target, or targets that exclude each other; not a rigid transform; not
            a rotation; a trajectory without ``sample``.
        ShapeError: wrong sizes (2 coordinates on a model known not to be planar).
    """
    if "target" in keys:
        keys = {("pose" if k == "target" else k): v for k, v in keys.items()}
    given: list[str] = sorted(k for k in ("trajectory", "hold") if k in keys)
    fixed: list[str] = sorted(k for k in ("position", "rotation", "pose", "velocity",
                                          "angular_velocity")
                              if k in keys and not (k == "rotation" and "trajectory" in keys))
    if "pose" in keys and ("position" in keys or "rotation" in keys):
        raise InputError(f"{name}: give pose= (or target=) or position=/rotation=, not both")
    if len(given) > 1 or (given and fixed):
        raise InputError(f"{name}: give one target: {', '.join(given + fixed)} exclude each "
                         "other")
    if not (given or fixed):
        raise InputError(f"{name}.set_target: give a position, rotation, pose, trajectory or "
                         "hold")
    target: Target
    if "hold" in keys:
        check_choice(keys["hold"], ("activation",), f"{name}.hold")
        target = HeldPose()
    elif "trajectory" in keys:
        trajectory = keys["trajectory"]
        if not callable(getattr(trajectory, "sample", None)):
            raise InputError(f"{name}.trajectory: expected an object with sample(t), got "
                             f"{type(trajectory).__name__}")
        if model is not None:
            check_trajectory(trajectory, model.vehicle_kind, name)
        rotation = keys.get("rotation")
        target = TrajectoryTarget(trajectory, None if rotation is None else as_rotation(
            rotation, f"{name}.rotation"))
    else:
        target = _fixed(keys, name, model, current)
    return target if reference == "world" else InFrame(target, reference)


def _fixed(keys: dict[str, Any], name: str, model: Model | None,
           current: Target | None) -> FixedPose:
    """A fixed target; a position or rotation left out keeps the ``current`` fixed one's."""
    kind = None if model is None else model.vehicle_kind
    if isinstance(current, InFrame):
        current = current.target
    p = R = None
    planar: list[str] = []
    if isinstance(current, FixedPose):
        p, R = current.position, current.rotation
        planar = [k for k in current.planar if k == "position"]
    if "pose" in keys:
        T = as_pose(keys["pose"], f"{name}.target")
        p, R, planar = T[:3, 3], T[:3, :3], []
    if "rotation" in keys:
        R = as_rotation(keys["rotation"], f"{name}.rotation")
    points = {}
    for key in ("position", "velocity"):
        if key in keys:
            points[key] = as_point(keys[key], f"{name}.{key}", kind)
            if key in planar:
                planar.remove(key)
            if kind is None and np.size(keys[key]) == 2:
                planar.append(key)
    w = keys.get("angular_velocity")
    return FixedPose(points.get("position", p), R, points.get("velocity"),
                       None if w is None else as_vector(w, f"{name}.angular_velocity", 3),
                       tuple(planar))


def check_trajectory(trajectory: Any, vehicle_kind: str, name: str) -> None:
    """Reject a trajectory whose positions do not fit the model of task ``name``.

    The number of coordinates is the trajectory's ``dimension`` attribute when it has one
    (2 for points given as ``(x, y)``), else the size of its position sampled once at its
    start time.

    Raises:
        ShapeError: 2 coordinates on a non-planar model (as for a 2-value ``position``), or
            a sampled position that is not a 3-vector.
    """
    label = f"{name}.trajectory"
    dimension = getattr(trajectory, "dimension", None)
    if dimension is None:
        start = getattr(trajectory, "start_time", 0.0)
        sample = trajectory.sample(start if isinstance(start, int | float) else 0.0)
        position = getattr(sample, "position", None)
        if position is None:
            raise not_a_sample(name, sample)
        dimension = int(np.size(position))
        if dimension == 2:
            check_planar_point(label, vehicle_kind)
        if dimension != 3:  # a sampled position must have 3 coordinates, z = 0 if planar
            raise ShapeError(f"{label}: sample(t).position has {dimension} coordinates; "
                             "expected 3 (x, y, z), with z = 0 on planar models")
    elif dimension == 2:
        check_planar_point(label, vehicle_kind)


def not_a_sample(name: str, sample: Any) -> InputError:
    """The error for a trajectory whose ``sample(t)`` has no ``position``/``velocity``."""
    return InputError(
        f"task {name!r}: trajectory.sample(t) returned a {type(sample).__name__}; "
        "expected a TrajectorySample (uvms_qp.sim.trajectories) or any object with "
        "attributes position (3,) [m] and velocity (3,) [m/s] or None, and optionally "
        "rotation (3, 3) and angular_velocity (3,) [rad/s]")


def _shape_error(name: str, t: float, **values: FloatArray | None) -> ShapeError:
    """The error naming the first of ``values`` (sampled at ``t`` [s]) of the wrong shape."""
    for key, value in values.items():
        expected = _ROTATION if key == "rotation" else _POINT
        if value is not None and value.shape != expected:
            break
    return ShapeError(f"task {name!r}: trajectory.sample({t:g}).{key} has shape "
                      f"{value.shape}; expected {expected}")  # type: ignore[union-attr]
