"""Currents: constant, sinusoidal, any function of time; what the plant accepts."""

import math

import numpy as np
import pytest

from uvms_qp.dynamics import ConstantCurrent, FunctionCurrent, SinusoidalCurrent, as_current
from uvms_qp.errors import InputError, NonFiniteError, ShapeError


def test_constant_current_has_zero_acceleration():
    c = ConstantCurrent([0.3, -0.1, 0.05])
    np.testing.assert_array_equal(c.velocity(12.0), [0.3, -0.1, 0.05])
    np.testing.assert_array_equal(c.acceleration(12.0), 0.0)
    assert c.steady


def test_sinusoidal_current_acceleration_is_the_derivative():
    c = SinusoidalCurrent([0.2, 0, 0], [0.1, 0.05, -0.02], period=8.0, phase=0.3)
    assert not c.steady
    for t in (0.0, 1.3, 7.9):
        h = 1e-6
        np.testing.assert_allclose(c.acceleration(t),
                                   (c.velocity(t + h) - c.velocity(t - h)) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(c.velocity(2.0), [0.2 + 0.1 * math.sin(math.pi / 2 + 0.3),
                                                 0.05 * math.sin(math.pi / 2 + 0.3),
                                                 -0.02 * math.sin(math.pi / 2 + 0.3)])


def test_function_current_differentiates_its_function():
    c = FunctionCurrent(lambda t: [0.1 * t * t, 0.0, math.sin(t)])
    np.testing.assert_allclose(c.acceleration(2.0), [0.4, 0.0, math.cos(2.0)], atol=1e-6)
    with pytest.raises(ShapeError, match="current velocity at t=1"):
        FunctionCurrent(lambda t: [1.0, 2.0]).velocity(1.0)


def test_as_current_accepts_the_documented_forms():
    assert as_current(None) is None
    assert isinstance(as_current([0.1, 0, 0]), ConstantCurrent)
    assert isinstance(as_current(lambda t: [0, 0, 0]), FunctionCurrent)
    c = SinusoidalCurrent([0, 0, 0], [0.1, 0, 0], 5.0)
    assert as_current(c) is c
    with pytest.raises(ShapeError):
        as_current([0.1, 0.2])
    with pytest.raises(NonFiniteError):
        as_current([0.1, float("nan"), 0.0])
    with pytest.raises(InputError):
        SinusoidalCurrent([0, 0, 0], [0.1, 0, 0], period=0.0)
