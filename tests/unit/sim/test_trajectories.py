"""Trajectories: feed-forward rates are the time derivatives of the samples; ends and clamping."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.errors import InputError, NonFiniteError, ShapeError
from uvms_qp.sim.trajectories import (
    TRAJECTORY_TYPES,
    CircleTrajectory,
    FixedTarget,
    LineTrajectory,
    QuinticTrajectory,
    WaypointTrajectory,
)

coord = st.floats(-2.0, 2.0)
point = st.tuples(coord, coord, coord)
angles = st.tuples(st.floats(-3.0, 3.0), st.floats(-1.4, 1.4), st.floats(-3.0, 3.0))


def _check_derivatives(traj, t: float, h: float = 1e-6) -> None:
    """Central differences of position/rotation against the sampled velocity/angular velocity."""
    before, now, after = traj.sample(t - h), traj.sample(t), traj.sample(t + h)
    np.testing.assert_allclose((after.position - before.position) / (2 * h), now.velocity,
                               atol=1e-6)
    if now.rotation is not None:
        omega_fd = pin.log3(after.rotation @ before.rotation.T) / (2 * h)
        np.testing.assert_allclose(omega_fd, now.angular_velocity, atol=1e-6)
        np.testing.assert_allclose(now.rotation.T @ now.rotation, np.eye(3), atol=1e-12)


@given(point, point, st.floats(0.5, 10.0), angles, angles, st.floats(0.02, 0.98))
def test_quintic_derivatives_and_ends(p0, p1, T, r0, r1, frac):
    traj = QuinticTrajectory(p0, p1, T, start_rotation=r0, goal_rotation=r1, start_time=1.0)
    _check_derivatives(traj, 1.0 + frac * T)
    start, end = traj.sample(1.0), traj.sample(1.0 + T)
    np.testing.assert_allclose(start.position, p0, atol=1e-12)
    np.testing.assert_allclose(end.position, p1, atol=1e-12)
    np.testing.assert_allclose(start.rotation, pin.rpy.rpyToMatrix(np.array(r0)), atol=1e-9)
    np.testing.assert_allclose(end.rotation, pin.rpy.rpyToMatrix(np.array(r1)), atol=1e-9)
    # rest-to-rest: zero velocity at both ends and while held before/after
    for t in (0.0, 1.0, 1.0 + T, 2.0 + 2 * T):
        np.testing.assert_allclose(traj.sample(t).velocity, 0.0, atol=1e-12)


@given(point, point, st.floats(0.5, 10.0), st.floats(0.02, 0.98))
def test_line_has_constant_speed_along_the_segment(p0, p1, T, frac):
    traj = LineTrajectory(p0, p1, T)
    sample = traj.sample(frac * T)
    np.testing.assert_allclose(sample.velocity, (np.array(p1) - np.array(p0)) / T, atol=1e-12)
    np.testing.assert_allclose(sample.position, np.array(p0) + frac * (np.array(p1) - p0),
                               atol=1e-12)
    assert sample.rotation is None and sample.angular_velocity is None


@given(point, st.floats(0.1, 2.0), st.floats(1.0, 20.0), st.floats(-3.0, 3.0),
       st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.2, 1)), st.floats(0.0, 1.0))
def test_circle_radius_plane_and_derivative(center, radius, T, turns, normal, frac):
    if abs(turns) < 0.1:
        turns = 1.0
    traj = CircleTrajectory(center, radius, T, turns=turns, normal=normal)
    t = frac * T * 0.98 + 0.01 * T
    sample = traj.sample(t)
    offset = sample.position - np.array(center)
    n = np.array(normal) / np.linalg.norm(normal)
    assert abs(np.linalg.norm(offset) - radius) < 1e-9
    assert abs(offset @ n) < 1e-9
    assert abs(np.linalg.norm(sample.velocity) - 2 * math.pi * abs(turns) * radius / T) < 1e-9
    _check_derivatives(traj, t)


def test_paper_001_circle_two_turns_in_ten_seconds():
    # dos Santos et al. (2006): a 1 m-diameter circle, two returns in 10 s
    traj = CircleTrajectory([1.0, 2.0, 0.0], 0.5, 10.0, turns=2.0)
    np.testing.assert_allclose(traj.sample(0.0).position, traj.sample(5.0).position, atol=1e-12)
    np.testing.assert_allclose(traj.sample(2.5).position, [0.5, 2.0, 0.0], atol=1e-12)


def test_waypoints_pass_through_points_at_their_times_and_stop():
    points = [[0, 0, 0], [1, 0, 0], [1, 1, 0.5]]
    rotations = [[0, 0, 0], [0, 0, 1], [0, 0.5, 1]]
    traj = WaypointTrajectory(points, [1.0, 3.0, 6.0], rotations=rotations)
    for p, t in zip(points, (1.0, 3.0, 6.0), strict=True):
        sample = traj.sample(t)
        np.testing.assert_allclose(sample.position, p, atol=1e-12)
        np.testing.assert_allclose(sample.velocity, 0.0, atol=1e-12)
    assert traj.duration == 5.0 and traj.start_time == 1.0
    for t in (1.5, 2.9, 3.1, 4.7):
        _check_derivatives(traj, t)


def test_planar_points_get_zero_z_and_fixed_target_holds():
    traj = QuinticTrajectory([0.0, 1.0], [2.0, 3.0], 2.0)
    assert traj.sample(1.0).position.shape == (3,)
    assert traj.sample(1.0).position[2] == 0.0
    fixed = FixedTarget([1.0, 2.0, 3.0], rotation=np.eye(3))
    sample = fixed.sample(123.0)
    np.testing.assert_array_equal(sample.position, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(sample.velocity, 0.0)
    np.testing.assert_array_equal(sample.angular_velocity, 0.0)


def test_registry_names():
    assert set(TRAJECTORY_TYPES) == {"quintic", "line", "circle", "waypoints", "fixed"}


@pytest.mark.parametrize(
    ("build", "error", "culprit"),
    [
        (lambda: QuinticTrajectory([0, 0, 0], [1, 1, 1], 0.0), InputError, "duration"),
        (lambda: QuinticTrajectory([0, 0, 0], [1, 1, 1], -1.0), InputError, "duration"),
        (lambda: QuinticTrajectory([0, 0], [1, 1, 1, 1], 1.0), ShapeError, "goal"),
        (lambda: QuinticTrajectory([0, 0, math.nan], [1, 1, 1], 1.0), NonFiniteError, "start"),
        (lambda: QuinticTrajectory([0, 0, 0], [1, 1, 1], 1.0, goal_rotation=[0, 0, 1]),
         InputError, "start_rotation"),
        (lambda: QuinticTrajectory([0, 0, 0], [1, 1, 1], 1.0, start_rotation=2 * np.eye(3)),
         InputError, "start_rotation"),
        (lambda: CircleTrajectory([0, 0, 0], 0.0, 1.0), InputError, "radius"),
        (lambda: CircleTrajectory([0, 0, 0], 1.0, 1.0, turns=0.0), InputError, "turns"),
        (lambda: CircleTrajectory([0, 0, 0], 1.0, 1.0, normal=[0, 0, 0]), InputError, "normal"),
        (lambda: WaypointTrajectory([[0, 0, 0]], [0.0]), InputError, "points"),
        (lambda: WaypointTrajectory([[0, 0, 0], [1, 0, 0]], [1.0, 1.0]), InputError, "times"),
        (lambda: WaypointTrajectory([[0, 0, 0], [1, 0, 0]], [0.0]), ShapeError, "times"),
        (lambda: LineTrajectory([0, 0, 0], [1, 0, 0], 1.0).sample(math.nan), InputError, "t"),
    ],
)
def test_bad_input_names_the_culprit(build, error, culprit):
    with pytest.raises(error, match=rf"^{culprit}\b"):
        build()


# ------------------------------------------------------- mixed point sizes are refused
@pytest.mark.parametrize("cls", [QuinticTrajectory, LineTrajectory])
def test_segment_rejects_start_and_goal_of_different_lengths(cls):
    with pytest.raises(InputError, match=r"^goal: got 3 coordinates but start has 2"):
        cls(start=[1, 2], goal=[1, 2, 3], duration=1)
    with pytest.raises(InputError, match=r"^goal: got 2 coordinates but start has 3"):
        cls(start=[1, 2, 3], goal=[1, 2], duration=1)


def test_waypoints_reject_points_of_different_lengths():
    with pytest.raises(InputError, match=r"^points\[2\]: got 3 coordinates but points\[0\] has 2"):
        WaypointTrajectory([[0, 0], [1, 1], [1, 1, 1]], [0, 1, 2])


def test_same_length_points_keep_their_dimension():
    assert QuinticTrajectory([1, 2], [1, 3], 1).dimension == 2
    assert QuinticTrajectory([1, 2, 3], [1, 3, 3], 1).dimension == 3
    assert WaypointTrajectory([[0, 0], [1, 1]], [0, 1]).dimension == 2
    assert CircleTrajectory([0, 0], 1.0, 2.0).dimension == 2
    assert CircleTrajectory([0, 0, -1], 1.0, 2.0).dimension == 3
    assert FixedTarget([0, 0]).dimension == 2
    # planar samples are still 3-vectors with z = 0, halfway along the segment at t = T/2
    sample = QuinticTrajectory([1, 2], [1, 4], 2.0).sample(1.0)
    np.testing.assert_allclose(sample.position, [1.0, 3.0, 0.0])
