"""A small fuzzy system for Wang et al.'s (2017) weights beta, alpha_1, alpha_2 (a reconstruction).

Wang et al. (2017) takes its fuzzy system from another work (its reference 19) and does
not print the rule base. This module is this library's reconstruction, consistent with the text:

- beta (arm share of the motion, Eq. 14) is high while the manipulability is high, and falls as the
  arm nears a singularity (the vehicle then moves); with a payload it is lowered, so the arm
  stretches less (case 3 "limits the movement of the manipulator");
- alpha_1 (weight of the manipulability gradient, Eq. 23) grows as the manipulability falls;
- alpha_2 (weight of the payload-moment gradient) grows with the payload.

Inputs are the normalised manipulability ``mu = delta / delta_ref`` (the paper plots a
"normalized MOM") and the payload ratio ``phi = F / F_max``, both clipped to [0, 1]. Each input has
three triangular sets (low, medium, high) centred at the given breakpoints, forming a partition of
unity; a zero-order Sugeno system with the rule tables below and weighted-average defuzzification
then reduces to a piecewise-bilinear interpolation of the tables, continuous in both inputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .._validation import as_scalar
from ..errors import InputError


class FuzzyWeights(NamedTuple):
    """Outputs of :func:`fuzzy_weights`, each in [0, 1]."""

    beta: float
    alpha_1: float
    alpha_2: float


@dataclass(frozen=True)
class FuzzyRules:
    """Rule base of the reconstruction (data, so a scenario can override it).

    Attributes:
        mu_centres: Centres of the low / medium / high sets of the normalised manipulability.
        phi_centres: Centres of the low / medium / high sets of the payload ratio.
        beta: 3 x 3 table, rows mu (low, medium, high), columns phi (low, medium, high).
        alpha_1: Consequents for mu low / medium / high.
        alpha_2: Consequents for phi low / medium / high.
    """

    mu_centres: tuple[float, float, float] = (0.2, 0.5, 0.8)
    phi_centres: tuple[float, float, float] = (0.0, 0.5, 1.0)
    beta: tuple[tuple[float, float, float], ...] = field(
        default=((0.10, 0.10, 0.10), (0.60, 0.50, 0.40), (0.98, 0.85, 0.70))
    )
    alpha_1: tuple[float, float, float] = (1.0, 0.5, 0.05)
    alpha_2: tuple[float, float, float] = (0.0, 0.5, 1.0)

    def __post_init__(self) -> None:
        for name in ("mu_centres", "phi_centres"):
            c = getattr(self, name)
            if len(c) != 3 or not (c[0] < c[1] < c[2]):
                raise InputError(f"{name}: expected three increasing centres, got {c}")
        table = np.asarray(self.beta, dtype=np.float64)
        if table.shape != (3, 3):
            raise InputError(f"beta: expected a 3 x 3 table, got shape {table.shape}")
        for name in ("beta", "alpha_1", "alpha_2"):
            values = np.asarray(getattr(self, name), dtype=np.float64)
            if not ((values >= 0.0) & (values <= 1.0)).all():
                raise InputError(f"{name}: expected consequents in [0, 1]")


DEFAULT_RULES = FuzzyRules()


def memberships(x: float, centres: tuple[float, float, float]) -> np.ndarray:
    """Degrees of membership of x in the low / medium / high triangular sets (sum to one)."""
    lo, mid, hi = centres
    if x <= lo:
        return np.array([1.0, 0.0, 0.0])
    if x >= hi:
        return np.array([0.0, 0.0, 1.0])
    if x <= mid:
        t = (x - lo) / (mid - lo)
        return np.array([1.0 - t, t, 0.0])
    t = (x - mid) / (hi - mid)
    return np.array([0.0, 1.0 - t, t])


def fuzzy_weights(
    manipulability_ratio: float,
    payload_ratio: float = 0.0,
    rules: FuzzyRules = DEFAULT_RULES,
) -> FuzzyWeights:
    """beta, alpha_1, alpha_2 for Wang et al. (2017), Eq. (14) and (23) (reconstruction).

    Args:
        manipulability_ratio: Normalised manipulability mu (clipped to [0, 1]).
        payload_ratio: F / F_max (clipped to [0, 1]); paper case 3 uses 0.5.
        rules: Rule base (default :data:`DEFAULT_RULES`).

    Returns:
        :class:`FuzzyWeights`; beta is non-decreasing in mu and non-increasing in phi with the
        default rules, alpha_1 non-increasing in mu, alpha_2 non-decreasing in phi.
    """
    mu = min(max(as_scalar(manipulability_ratio, "manipulability_ratio"), 0.0), 1.0)
    phi = min(max(as_scalar(payload_ratio, "payload_ratio"), 0.0), 1.0)
    m = memberships(mu, rules.mu_centres)
    p = memberships(phi, rules.phi_centres)
    beta = float(m @ np.asarray(rules.beta) @ p)
    alpha_1 = float(m @ np.asarray(rules.alpha_1))
    alpha_2 = float(p @ np.asarray(rules.alpha_2))
    return FuzzyWeights(beta, alpha_1, alpha_2)
