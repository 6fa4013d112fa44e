"""What the controller measures of the plant: noise and delay between the true state and it.

A real UVMS measures its pose with a navigation filter (DVL, IMU, depth, USBL) and its joint
angles with encoders; both arrive noisy and late. :class:`Sensors` models that between the plant
and the controller:

- **pose**: every control period, the controller is given the true configuration of ``delay``
  seconds earlier (rounded to whole control periods: the states the loop keeps) with independent
  Gaussian noise added to the world position of the vehicle (``position_noise`` [m] per axis),
  its roll, pitch and yaw (``attitude_noise`` [rad] per angle) and each joint angle
  (``joint_noise`` [rad]);
- **velocity** (dynamic plant only): the vehicle's body velocity read by the velocity loop and
  by arm-vehicle coordination gets Gaussian noise of ``linear_rate_noise`` [m/s] on ``u, v, w``
  and ``angular_rate_noise`` [rad/s] on ``p, q, r``.

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
        delay: Age of the pose the controller receives [s] (>= 0), rounded to whole control
            periods.
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
        self._past: deque[FloatArray] = deque(maxlen=self._delay + 1)
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

    def pose(self, q: FloatArray) -> FloatArray:
        """The configuration the controller receives when the plant is at ``q`` (nq,).

        The true ``q`` itself when the sensors are exact; else the configuration of ``delay``
        periods ago (the oldest kept while fewer have passed) with noise on ``eta`` and joints.
        """
        if self.sensors.pose_is_exact:
            return q
        self._past.append(np.array(q, dtype=np.float64))
        old = self._past[0]
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
        """The body velocity (6,) [m/s, rad/s] the velocity loop reads when the true one is nu."""
        if self.sensors.velocity_is_exact:
            return nu
        return nu + self._rng.standard_normal(6) * self._rate_sigma
