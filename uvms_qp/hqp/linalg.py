"""The solve path's calls into compiled linear algebra, each given only inputs it accepts.

A native routine handed an input it was not written for may not raise: SciPy 1.17's
``nnls`` frees its work memory twice on a matrix without columns and aborts the process
(exit status 134), and returns uninitialised memory for a matrix without rows; LAPACK
routines called directly may loop or return garbage on NaN. A controller must never take its
host down, so every such call of the solve path goes through this module, which answers the
degenerate shapes itself and refuses non-finite input before the native code sees it.
``tests/unit/hqp/test_linalg.py`` holds the cases; :mod:`uvms_qp.testing.fuzz` feeds the
certificate, the repair and the damping screen degenerate problems in child processes and
counts aborts.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import nnls as _scipy_nnls

from .._validation import FloatArray


def nnls(A: FloatArray, b: FloatArray, maxiter: int | None = None) -> tuple[FloatArray, float]:
    """``argmin_{c >= 0} |A c - b|`` and the residual norm, for any shape of ``A`` (m, k).

    No column: ``c`` is empty and the residual ``|b|``. No row: ``c = 0``, residual 0. A
    non-finite entry in ``A`` or ``b``: ``c = 0`` and the residual ``|b|`` (inf if ``b`` is not
    finite), never an exception: the certificate's bound holds for any multipliers, so zero
    multipliers are a sound (if weak) answer.
    """
    m, k = A.shape
    if k == 0 or m == 0:
        return np.zeros(k), (float(np.linalg.norm(b)) if m else 0.0)
    if not (np.isfinite(A).all() and np.isfinite(b).all()):
        size = float(np.linalg.norm(b))
        return np.zeros(k), size if math.isfinite(size) else math.inf
    c, r = _scipy_nnls(np.ascontiguousarray(A, dtype=np.float64),
                       np.ascontiguousarray(b, dtype=np.float64),
                       maxiter=maxiter if maxiter is not None else 50 * max(m, k, 10))
    return c, float(r)


def finite(*arrays: FloatArray) -> bool:
    """True when every entry of every array is finite."""
    return all(bool(np.isfinite(a).all()) for a in arrays)
