"""Numbers at the public boundaries: real numbers only, never silently converted.

numpy reads ``True`` as 1, ``"2"`` as 2 and drops the imaginary part of a complex number; the
validation helpers refuse all three and name the argument.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from uvms_qp._validation import as_array, as_matrix, as_scalar, as_vector
from uvms_qp.bench.stacks import demo_stack
from uvms_qp.controller import Controller
from uvms_qp.errors import InputError
from uvms_qp.hqp import solve_hierarchy
from uvms_qp.model import load_model


@pytest.mark.parametrize(
    ("value", "what"),
    [
        (["1", 2.0], "strings"),
        ("3", "strings"),
        (b"3", "bytes"),
        ([True, 2.0], "a boolean"),
        (np.array([True]), "booleans"),
        ([1 + 2j], "complex numbers"),
        (np.ones(2, dtype=np.complex64), "complex numbers"),
        ([None, 1.0], "NoneType"),
        ([[1.0, 2.0], [3.0]], "numbers, got list"),
    ],
)
def test_non_real_input_is_refused(value, what):
    for convert in (as_array, as_vector):
        with pytest.raises(InputError, match=f"x: expected .*{what}"):
            convert(value, "x")


def test_real_numbers_of_any_kind_are_accepted():
    np.testing.assert_array_equal(as_vector([1, 2.5, np.float32(3), Fraction(1, 2)], "x"),
                                  [1.0, 2.5, 3.0, 0.5])
    np.testing.assert_array_equal(as_matrix(np.arange(4, dtype=np.int8).reshape(2, 2), "A"),
                                  [[0.0, 1.0], [2.0, 3.0]])
    x = np.zeros(3)
    assert as_vector(x, "x") is x  # a float64 array is not copied
    for bad in (True, 1j, "1", None):
        with pytest.raises(InputError, match="y: expected a number"):
            as_scalar(bad, "y")


@pytest.mark.parametrize("metric", [["1"] * 10, [True] * 10, np.ones(10, dtype=complex)])
def test_a_controller_metric_must_be_real(metric):
    model = load_model("bluerov2_heavy_alpha5")
    with pytest.raises(InputError, match="metric: expected real numbers"):
        Controller(model, demo_stack(position=[0.5, 0.0, 0.0]), metric=metric)


@pytest.mark.parametrize("A", [[["1", "0"]], [[True, 1.0]], [[1j, 0.0]]])
def test_hierarchy_rows_must_be_real(A):
    with pytest.raises(InputError, match=r"levels\[0\]\[0\]\.A: expected real numbers"):
        solve_hierarchy([[(A, [0.0])]], [-1.0, -1.0], [1.0, 1.0])
