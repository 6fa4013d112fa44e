"""The controller's measured pose on the kinematic plant: noise and delay between it and truth.

A scheme wrapper: every control period the wrapped scheme is given the state of the true
configuration of ``delay`` seconds earlier (whole control periods: the states the loop keeps)
with independent Gaussian noise on the vehicle's world position (``position_noise`` [m] per
axis), its attitude angles (``attitude_noise`` [rad] each) and each joint angle
(``joint_noise`` [rad], clipped into the joint's limits: an encoder does not read beyond its
joint's travel). The recorded series and metrics stay those of the true state. The noise comes
from one generator seeded with ``seed``, so a run is repeated exactly.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import FloatArray


@dataclass(frozen=True)
class PoseNoise:
    """Noise standard deviations [m, rad], delay [s] and seed of the measured pose."""

    position_noise: float = 0.0
    attitude_noise: float = 0.0
    joint_noise: float = 0.0
    delay: float = 0.0
    seed: int = 0

    @property
    def exact(self) -> bool:
        """Whether the controller sees the true, current configuration."""
        return not (self.position_noise or self.attitude_noise or self.joint_noise
                    or self.delay)


class MeasuredScheme:
    """A scheme that steps on the measured state instead of the true one.

    Args:
        scheme: The scheme (``step(state, t)``, ``reset()``), e.g. a controller.
        model: The model.
        noise: What the measurement does to the truth.
        dt: Control period [s] (the delay is rounded to whole periods).
    """

    def __init__(self, scheme: Any, model: Any, noise: PoseNoise, dt: float) -> None:
        self.scheme = scheme
        self.model = model
        self.noise = noise
        self.solver_name = getattr(scheme, "solver_name", None)
        self.stack = getattr(scheme, "stack", None)
        self._delay = round(noise.delay / dt)
        self._rng = np.random.default_rng(noise.seed)
        self._past: deque[FloatArray] = deque(maxlen=self._delay + 1)
        size = int(model.eta_size)
        sigma = np.zeros(size)
        if model.vehicle_kind == "spatial":
            sigma[:3], sigma[3:] = noise.position_noise, noise.attitude_noise
        elif model.vehicle_kind == "planar":
            sigma[:2], sigma[2] = noise.position_noise, noise.attitude_noise
        self._eta_sigma = sigma

    def reset(self) -> None:
        """Reset the scheme, the delay line and the generator (a run starts again exactly)."""
        reset = getattr(self.scheme, "reset", None)
        if callable(reset):
            reset()
        self._rng = np.random.default_rng(self.noise.seed)
        self._past.clear()

    def measure(self, q: FloatArray) -> FloatArray:
        """The configuration the scheme receives when the truth is ``q`` (nq,)."""
        self._past.append(np.array(q, dtype=np.float64))
        old = self._past[0]
        noise = self.noise
        if not (noise.position_noise or noise.attitude_noise or noise.joint_noise):
            return old
        model = self.model
        eta, joints = model.split(old)
        eta = np.asarray(eta, dtype=np.float64) + self._rng.standard_normal(
            self._eta_sigma.shape) * self._eta_sigma
        joints = np.asarray(joints, dtype=np.float64)
        if noise.joint_noise:
            joints = np.clip(joints + noise.joint_noise * self._rng.standard_normal(
                joints.shape), model.joint_lower, model.joint_upper)
        return np.asarray(model.configuration(eta, joints), dtype=np.float64)

    def step(self, state: Any, t: float) -> Any:
        """The scheme's step on the measured state."""
        return self.scheme.step(self.model.state(self.measure(state.q)), t)
