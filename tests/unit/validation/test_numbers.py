"""Numbers at the public boundaries: real numbers only, never silently converted.

numpy reads ``True`` as 1, ``"2"`` as 2 and drops the imaginary part of a complex number; the
validation helpers refuse all three and name the argument.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from uvms_qp._validation import as_array, as_matrix, as_scalar, as_vector
from uvms_qp.errors import (
    InputError,
)


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
