"""Final saturation of a command to the hard box, with the amount clipped reported.

Every command leaving the controller passes through :func:`saturate`: whatever produced it (a
verified solve, a fallback stage), the output lies inside ``[lower, upper]`` exactly (bit-exact:
``np.minimum(np.maximum(x, lower), upper)``). The amount clipped ``max_i |x_sat,i - x_i|``
[m/s or rad/s] is reported; after a verified solve it is round-off (<= the hard tolerance), so a
clip above ``flag_tol`` means something upstream went wrong and is flagged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray

#: Default threshold above which a clip is flagged [m/s, rad/s].
CLIP_FLAG_TOL = 1e-6


@dataclass(frozen=True, slots=True)
class Saturation:
    """Result of :func:`saturate`.

    Attributes:
        x: The saturated command, inside ``[lower, upper]``, shape (n,).
        clipped: Largest absolute change made by the clip [units of x].
        flagged: True when ``clipped > flag_tol``.
    """

    x: FloatArray
    clipped: float
    flagged: bool


def saturate(x: FloatArray, lower: FloatArray, upper: FloatArray,
             flag_tol: float = CLIP_FLAG_TOL) -> Saturation:
    """Clip ``x`` into ``[lower, upper]`` and report how much was clipped.

    Args:
        x: Finite command, shape (n,) [m/s, rad/s].
        lower: Lower bounds, shape (n,) (``-inf`` allowed), ``lower <= upper``.
        upper: Upper bounds, shape (n,) (``+inf`` allowed).
        flag_tol: Clip amount above which :attr:`Saturation.flagged` is set.

    Returns:
        The saturated command and the clip amount.
    """
    xs = np.minimum(np.maximum(x, lower), upper)
    d = xs - x
    clipped = float(np.abs(d).max()) if d.size else 0.0  # NaN in x gives NaN here
    return Saturation(xs, clipped, clipped > flag_tol)
