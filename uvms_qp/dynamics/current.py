"""Water currents: uniform and irrotational, constant or slowly varying in time.

A current is the water's velocity in the world frame (NED) [m/s], the same everywhere (Fossen
(2011), Section 8.3: an irrotational current; its velocity in a body frame is ``R^T V_c``). A
plant asks a current for its velocity and acceleration at a time ``t``:

- :class:`ConstantCurrent`: a fixed velocity (horizontal or not);
- :class:`SinusoidalCurrent`: ``V_c(t) = mean + amplitude sin(2 pi t / period + phase)``, a simple
  model of a slowly varying (tidal or swell-driven) current;
- :class:`FunctionCurrent`: any function ``t -> V_c(t)``, its acceleration by central difference.

:func:`as_current` accepts any of these, a 3-vector (constant) or a callable.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .._validation import as_scalar, as_vector
from ..errors import InputError

FloatArray = NDArray[np.float64]


@runtime_checkable
class Current(Protocol):
    """What a plant asks a current: world velocity and acceleration at time ``t``."""

    #: True when the acceleration is zero at every time (the plant skips its terms).
    steady: bool

    def velocity(self, t: float) -> FloatArray:
        """Water velocity in the world frame [m/s] (3,)."""
        ...

    def acceleration(self, t: float) -> FloatArray:
        """Its time derivative in the world frame [m/s^2] (3,)."""
        ...


class ConstantCurrent:
    """A current of constant world velocity.

    Args:
        velocity: World (NED) velocity of the water [m/s] (3,).
    """

    steady = True

    def __init__(self, velocity: Any) -> None:
        self._velocity = as_vector(velocity, "current velocity", 3).copy()
        self._velocity.flags.writeable = False
        self._zero = np.zeros(3)
        self._zero.flags.writeable = False

    def velocity(self, t: float) -> FloatArray:
        """The constant velocity [m/s]."""
        return self._velocity

    def acceleration(self, t: float) -> FloatArray:
        """Zero [m/s^2]."""
        return self._zero

    def __repr__(self) -> str:
        return f"ConstantCurrent({self._velocity.tolist()})"


class SinusoidalCurrent:
    """``V_c(t) = mean + amplitude * sin(2 pi t / period + phase)`` (world frame).

    Args:
        mean: Mean world velocity [m/s] (3,).
        amplitude: Amplitude of the variation per axis [m/s] (3,).
        period: Period [s], > 0 (slowly varying: long against the vehicle's time constants).
        phase: Phase [rad].
    """

    steady = False

    def __init__(self, mean: Any, amplitude: Any, period: float, phase: float = 0.0) -> None:
        self.mean = as_vector(mean, "current mean", 3).copy()
        self.amplitude = as_vector(amplitude, "current amplitude", 3).copy()
        self.period = as_scalar(period, "current period", positive=True)
        self.phase = as_scalar(phase, "current phase")
        self._omega = 2.0 * math.pi / self.period

    def velocity(self, t: float) -> FloatArray:
        """World velocity at ``t`` [m/s]."""
        return self.mean + self.amplitude * math.sin(self._omega * t + self.phase)

    def acceleration(self, t: float) -> FloatArray:
        """World acceleration at ``t`` [m/s^2]."""
        return self.amplitude * (self._omega * math.cos(self._omega * t + self.phase))

    def __repr__(self) -> str:
        return (f"SinusoidalCurrent(mean={self.mean.tolist()}, amplitude="
                f"{self.amplitude.tolist()}, period={self.period:g}, phase={self.phase:g})")


class FunctionCurrent:
    """A current given by a function of time.

    Args:
        function: ``t [s] -> world velocity [m/s] (3,)``; smooth on the scale of ``step``.
        step: Half-width of the central difference that gives the acceleration [s].
    """

    steady = False

    def __init__(self, function: Callable[[float], Any], step: float = 1e-3) -> None:
        if not callable(function):
            raise InputError(f"current: expected a callable t -> velocity, got {function!r}")
        self.function = function
        self.step = as_scalar(step, "current step", positive=True)

    def velocity(self, t: float) -> FloatArray:
        """World velocity at ``t`` [m/s] (the function's value, checked)."""
        return as_vector(self.function(t), f"current velocity at t={t:g}", 3)

    def acceleration(self, t: float) -> FloatArray:
        """Central difference of the velocity [m/s^2]."""
        h = self.step
        return (self.velocity(t + h) - self.velocity(t - h)) / (2.0 * h)

    def __repr__(self) -> str:
        return f"FunctionCurrent({self.function!r})"


def as_current(value: Any) -> Current | None:
    """None (still water), a :class:`Current`, a 3-vector (constant) or a callable of time.

    Raises:
        InputError, ShapeError, NonFiniteError: anything else.
    """
    if value is None:
        return None
    if isinstance(value, Current):
        return value
    if callable(value):
        return FunctionCurrent(value)
    return ConstantCurrent(value)
