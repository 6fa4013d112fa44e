"""What the controller measures of the plant: noise and delay between the true state and it.

A real UVMS measures its pose with a navigation filter (DVL, IMU, depth, USBL) and its joint
angles with encoders; both arrive noisy and late. :class:`Sensors` models that between the plant
and the controller:

- **the controller's state**: every control period, the controller is given the true state of
  ``delay`` seconds earlier (rounded to whole control periods: the states the loop keeps), its
  configuration and (dynamic plant) the vehicle's body velocity of that same instant: a
  navigation solution arrives late as a whole. Independent Gaussian noise is added to the world
  position of the vehicle (``position_noise`` [m] per axis), its roll, pitch and yaw
  (``attitude_noise`` [rad] per angle), each joint angle (``joint_noise`` [rad]) and the body
  velocity (``linear_rate_noise`` [m/s] on ``u, v, w``, ``angular_rate_noise`` [rad/s] on
  ``p, q, r``); arm-vehicle coordination uses that velocity;
- **the velocity loop's rates** (dynamic plant only): the vehicle's velocity loop, at the servo
  rate, reads the body velocity with the same rate noise and *no* delay: an inner loop closed on
  the rate sensors (DVL, gyroscopes), not on the navigation solution. ``delay`` does not apply to
  it.

The noise comes from one generator seeded with ``seed``, so a run is repeated exactly. With every
figure zero (the default) the controller sees the true state and no random number is drawn.
Noisy joint angles are clipped into the joint limits (an encoder does not read beyond its joint's
travel), and the recorded series and metrics stay those of the true state.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError


@dataclass(frozen=True)
class Sensors:
    """Noise and delay of the measurements the controller and the velocity loop receive.

    Attributes:
        position_noise: Standard deviation of each world position coordinate [m] (>= 0).
        attitude_noise: Standard deviation of roll, pitch and yaw [rad] (>= 0).
        joint_noise: Standard deviation of each joint position [rad or m] (>= 0).
        linear_rate_noise: Standard deviation of ``u, v, w`` [m/s] (>= 0, dynamic plant).
        angular_rate_noise: Standard deviation of ``p, q, r`` [rad/s] (>= 0, dynamic plant).
        delay: Age of the state the controller receives [s] (>= 0), rounded to whole control
            periods: its configuration and body velocity, both of that earlier instant (the
            velocity loop's rates are not delayed).
        seed: Seed of the noise generator.
    """

    position_noise: float = 0.0
    attitude_noise: float = 0.0
    joint_noise: float = 0.0
    linear_rate_noise: float = 0.0
    angular_rate_noise: float = 0.0
    delay: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("position_noise", "attitude_noise", "joint_noise", "linear_rate_noise",
                     "angular_rate_noise", "delay"):
            object.__setattr__(self, name, as_scalar(getattr(self, name), name,
                                                     nonnegative=True))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer):
            raise InputError(f"seed: expected an integer, got {self.seed!r}")
        if self.seed < 0:
            raise InputError(f"seed: expected a non-negative integer, got {self.seed}")

    @property
    def pose_is_exact(self) -> bool:
        """Whether the controller sees the true, current configuration."""
        return not (self.position_noise or self.attitude_noise or self.joint_noise
                    or self.delay)

    @property
    def velocity_is_exact(self) -> bool:
        """Whether the velocity loop sees the true body velocity."""
        return not (self.linear_rate_noise or self.angular_rate_noise)

    def delay_steps(self, dt: float) -> int:
        """The delay in whole control periods of ``dt`` [s] (nearest)."""
        return round(self.delay / dt)

    def channel(self, model: Any, dt: float) -> MeasurementChannel:
        """A fresh measurement channel for one run on ``model`` at period ``dt`` [s]."""
        return MeasurementChannel(self, model, dt)


class MeasurementChannel:
    """The run-time side of :class:`Sensors`: the generator and the delay line of one run."""

    def __init__(self, sensors: Sensors, model: Any, dt: float) -> None:
        self.sensors = sensors
        self.model = model
        self._rng = np.random.default_rng(sensors.seed)
        self._delay = sensors.delay_steps(dt)
        self._past: deque[tuple[FloatArray, FloatArray | None]] = deque(
            maxlen=self._delay + 1)
        kind = getattr(model, "vehicle_kind", "fixed")
        size = int(getattr(model, "eta_size", 0))
        sigma = np.zeros(size)
        if kind == "spatial":
            sigma[:3] = sensors.position_noise
            sigma[3:] = sensors.attitude_noise
        elif kind == "planar":
            sigma[:2] = sensors.position_noise
            sigma[2] = sensors.attitude_noise
        self._eta_sigma = sigma
        self._rate_sigma = np.array([sensors.linear_rate_noise] * 3
                                    + [sensors.angular_rate_noise] * 3)

    def state(self, q: FloatArray, nu: FloatArray | None = None
              ) -> tuple[FloatArray, FloatArray | None]:
        """The configuration and body velocity the controller receives, once per control period.

        Args:
            q: The plant's true configuration (nq,).
            nu: The vehicle's true body velocity (6,) [m/s, rad/s] (FRD), None on a plant
                without one (kinematic).

        Returns:
            ``(q, nu)`` as measured: the true ones themselves when the sensors are exact; else
            both of ``delay`` periods ago (the oldest kept while fewer have passed), with noise
            on ``eta``, the joints and ``nu`` (None stays None).
        """
        s = self.sensors
        if s.pose_is_exact:
            return q, (None if nu is None else self.body_velocity(nu))
        self._past.append((np.array(q, dtype=np.float64),
                           None if nu is None else np.array(nu, dtype=np.float64)))
        old, old_nu = self._past[0]
        return self._noisy_pose(old), (None if old_nu is None else self.body_velocity(old_nu))

    def pose(self, q: FloatArray) -> FloatArray:
        """The configuration the controller receives when the plant is at ``q`` (nq,).

        :meth:`state` without a velocity: call one of the two once per control period.
        """
        return self.state(q)[0]

    def _noisy_pose(self, old: FloatArray) -> FloatArray:
        s = self.sensors
        if not (s.position_noise or s.attitude_noise or s.joint_noise):
            return old
        model = self.model
        eta, joints = model.split(old)
        eta = np.asarray(eta, dtype=np.float64) + self._rng.standard_normal(eta.shape) \
            * self._eta_sigma
        joints = np.asarray(joints, dtype=np.float64)
        if s.joint_noise:
            joints = np.clip(joints + s.joint_noise * self._rng.standard_normal(joints.shape),
                             model.joint_lower, model.joint_upper)
        return np.asarray(model.configuration(eta, joints), dtype=np.float64)

    def body_velocity(self, nu: FloatArray) -> FloatArray:
        """The body velocity (6,) [m/s, rad/s] read when the true one is ``nu``: noise, no delay.

        What the velocity loop reads at every servo tick (:meth:`state` delays the controller's).
        """
        if self.sensors.velocity_is_exact:
            return nu
        return nu + self._rng.standard_normal(6) * self._rate_sigma
