"""The one measure of an answer (uvms_qp.hqp.measure): the hard violation against its plain form."""

import math

import numpy as np

from uvms_qp.hqp.measure import hard_violation


def plain_hard_violation(x, lower, upper, A, lo, hi):
    """``max`` of every distance outside the box and the rows, ``inf`` when one is NaN."""
    z = A @ x
    d = np.concatenate((x - np.clip(x, lower, upper), z - np.clip(z, lo, hi)))
    return math.inf if np.isnan(d).any() else float(np.abs(d).max(initial=0.0))


def test_hard_violation_is_the_largest_distance_and_inf_wherever_a_nan_sits():
    rng = np.random.default_rng(4)
    with np.errstate(invalid="ignore"):
        for _ in range(500):
            n, m = int(rng.integers(1, 8)), int(rng.integers(1, 5))
            x = rng.normal(size=n)
            lower, upper = -rng.random(n), rng.random(n)
            A = rng.normal(size=(m, n))
            lo, hi = -rng.random(m), rng.random(m)
            if rng.random() < 0.5:  # a NaN in x at any place: every row it meets is NaN
                x[rng.integers(n)] = np.nan
            if rng.random() < 0.3:  # a NaN side of one row
                lo[rng.integers(m)] = np.nan
            assert hard_violation(x, lower, upper, A, lo, hi) == plain_hard_violation(
                x, lower, upper, A, lo, hi)
