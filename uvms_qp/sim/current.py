"""A constant, horizontal water current.

The kinematic simulation has no hydrodynamics. The current plays two roles:

- it gives a heading ``psi_c`` [rad] (world NED, measured from north toward east) that a
  current-alignment task turns the vehicle toward (dos Santos et al. (2006), Eq. (23)-(26)
  and its simulation: vehicle kept at rest with its yaw aligned to a current at 0.78 rad);
- optionally, it drifts the vehicle: a fraction ``drift`` of the current velocity
  ``v_c = speed [cos psi_c, sin psi_c, 0]`` [m/s] is added to the vehicle's world position rate,
  an unmodelled disturbance that the closed-loop tasks must reject. ``drift = 0`` (default) keeps
  the simulation purely kinematic.

On the dynamic plant (:mod:`uvms_qp.sim.dynamic_plant`) the current is the water's velocity past
every body, and it may vary slowly: ``oscillation`` [m/s] and ``period`` [s] make its speed
``speed + oscillation sin(2 pi t / period)`` along its direction (``drift`` does not apply there).
"""

from __future__ import annotations

import math

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError


class ConstantCurrent:
    """A constant horizontal current.

    Args:
        direction: Direction the water flows toward [rad], world NED yaw (0 = north, pi/2 = east).
        speed: Current speed [m/s] (>= 0).
        drift: Fraction of the current velocity that displaces the vehicle, in [0, 1].
        oscillation: Amplitude of the speed's slow variation on the dynamic plant [m/s] (>= 0).
        period: Period of that variation [s] (> 0).
    """

    def __init__(self, direction: float, speed: float = 0.0, drift: float = 0.0,
                 oscillation: float = 0.0, period: float = 60.0) -> None:
        self.direction = as_scalar(direction, "direction")
        self.speed = as_scalar(speed, "speed", nonnegative=True)
        self.drift = as_scalar(drift, "drift", nonnegative=True)
        if self.drift > 1.0:
            raise InputError(f"drift: expected a fraction in [0, 1], got {self.drift}")
        self.oscillation = as_scalar(oscillation, "oscillation", nonnegative=True)
        self.period = as_scalar(period, "period", positive=True)

    @property
    def heading(self) -> float:
        """Heading of the current [rad], wrapped to (-pi, pi]."""
        return wrap_angle(self.direction)

    def unit(self) -> FloatArray:
        """The unit vector (3,) the water flows along, world frame (horizontal)."""
        return np.array([math.cos(self.direction), math.sin(self.direction), 0.0])

    def velocity(self) -> FloatArray:
        """Current velocity ``v_c`` (3,) [m/s] in the world frame (horizontal)."""
        return self.speed * self.unit()

    def drift_velocity(self) -> FloatArray:
        """World velocity added to the vehicle by the current, ``drift * v_c`` (3,) [m/s]."""
        return self.drift * self.velocity()

    def __repr__(self) -> str:
        varying = (f", oscillation={self.oscillation:g}, period={self.period:g}"
                   if self.oscillation else "")
        return (
            f"ConstantCurrent(direction={self.direction:g}, speed={self.speed:g}, "
            f"drift={self.drift:g}{varying})"
        )


def wrap_angle(angle: float) -> float:
    """Wrap an angle [rad] to (-pi, pi]."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped
