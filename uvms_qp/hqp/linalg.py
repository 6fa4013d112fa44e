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

It also holds the layer's kernels: the numpy ufuncs and reductions its hot loops call, bound
once, and the two LAPACK routines the damping screen calls directly (``gesdd``, ``potrf``) on
the rows of a validated problem, which are finite by construction.
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np
from scipy.linalg import lapack
from scipy.optimize import nnls as _scipy_nnls

from .._validation import FloatArray

try:  # numpy >= 2
    from numpy._core import multiarray as _multiarray
except ImportError:  # numpy 1.x
    from numpy.core import multiarray as _multiarray  # type: ignore[no-redef]

# -- Kernels of the solve path's hot loops, bound once -----------------------------------------
# The solve path calls numpy's ufuncs and reductions on arrays of tens of entries, where the
# interpreter's lookups cost as much as the arithmetic: each module of the layer takes these
# names from here (``from .linalg import absolute as _absolute``) instead of binding its own.
# They are numpy's and LAPACK's own callables, not re-implementations;
# ``tests/unit/hqp/test_linalg.py`` checks each against the plain numpy form it stands for.
absolute, add, divide, dot, multiply = np.absolute, np.add, np.divide, np.dot, np.multiply
sqrt, square, subtract = np.sqrt, np.square, np.subtract
maximum, minimum = np.maximum, np.minimum
greater_equal, less_equal, logical_or = np.greater_equal, np.less_equal, np.logical_or
isfinite = np.isfinite
#: ``np.max``/``np.min`` without their Python wrappers (``initial=``, ``where=`` and ``axis=``
#: as the ufunc's ``reduce`` takes them).
max_of, min_of = np.maximum.reduce, np.minimum.reduce
#: The largest entry of each segment ``a[starts[i]:starts[i+1]]`` (``np.maximum.reduceat``).
segment_max = np.maximum.reduceat
#: ``np.concatenate`` and ``np.vdot`` without numpy's ``__array_function__`` dispatch (a Python
#: call per use, about a third of the call on arrays of tens of entries): for plain float64
#: arrays the solve path built itself, which no other array type can override.
concatenate = getattr(np.concatenate, "_implementation", np.concatenate)
vdot = getattr(np.vdot, "_implementation", np.vdot)
#: ``np.count_nonzero`` of a whole array without its Python wrapper: numpy's C function (a
#: count of true entries costs a fraction of a ufunc reduction's set-up).
count_nonzero = _multiarray.count_nonzero
#: LAPACK's divide-and-conquer SVD (``dgesdd``) and Cholesky factorisation (``dpotrf``), called
#: without SciPy's wrappers: finite input only (a validated problem's rows; the fuzz harness
#: drives the damping screen on degenerate levels).
gesdd, potrf = lapack.dgesdd, lapack.dpotrf


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


class OneBlasThread:
    """A context in which the BLAS libraries of the process run one thread, restored after.

    The solve path's linear algebra is small (matrices of tens of rows): a second BLAS thread
    buys nothing there, and on a loaded machine it spin-waits for a core and stalls the call
    (least squares on 40-120 wide systems measured 0.3 s with one thread, 3-6 s with two, for
    the same problem). The user's other code keeps its own setting: the limit holds only inside
    the context. The libraries are found once by ``threadpoolctl`` (on first entry, once numpy
    and SciPy have loaded theirs); an entry then costs two C calls per library (a few
    microseconds). Re-entering from the same thread costs a counter, so every entry point of
    the solve path (the solvers, the certificate's cold solves, the repair, the damping
    screen's examination) enters it without paying twice. Each thread counts its own entries
    and sets and restores the count itself (OpenBLAS does not always let one thread's setting
    reach another's calls). A step of a small problem on DAQP does not enter it at all
    (:func:`single_threaded`): its products run on one thread whatever the setting, and the
    parts above, which factorise, enter it themselves.
    """

    def __init__(self) -> None:
        self._libs: list[Any] | None = None
        self._local = threading.local()  # per thread: depth and the counts to restore

    def _find(self) -> list[Any]:
        from threadpoolctl import ThreadpoolController

        libs = [lib for lib in ThreadpoolController().lib_controllers if lib.user_api == "blas"]
        self._libs = libs
        return libs

    def __enter__(self) -> OneBlasThread:
        local = self._local
        depth = getattr(local, "depth", 0)
        local.depth = depth + 1
        if depth:  # inside an outer context of this thread: one thread already
            return self
        saved = local.saved = []
        for lib in self._libs if self._libs is not None else self._find():
            count = lib.get_num_threads()
            if count is not None and count != 1:
                lib.set_num_threads(1)
                saved.append((lib, count))
        return self

    def __exit__(self, *_: object) -> None:
        local = self._local
        local.depth -= 1
        if local.depth:
            return
        for lib, count in local.saved:
            lib.set_num_threads(count)
        local.saved = []


#: The one limiter of the solve path (entered by every solve and every control step whose
#: problem is not :func:`single_threaded`, and by the parts that factorise matrices).
one_blas_thread = OneBlasThread()

#: Largest ``M * M * n`` of a problem (M stacked rows, n variables) whose solve path is left
#: without the limit: OpenBLAS (0.3.x, every architecture) runs one thread for a matrix
#: product of fewer than ``4 * 65536`` multiply-adds and for matrix-vector products far larger
#: than these, and the products a solve forms outside the parts that enter the limit
#: themselves (``A x``, the Gram matrices of a problem's rows, their Cholesky factors) take at
#: most ``M * M * n``. A factor 4 below OpenBLAS's threshold, measured:
#: ``tests/unit/hqp/test_linalg.py`` counts no work on OpenBLAS's threads through whole solves
#: at this size with two threads and no limit. SVDs and least squares start threading at much
#: smaller sizes (a 40 x 40 SVD): the parts that call them enter the limit wherever they run.
SINGLE_THREADED_SIZE = 65536


def single_threaded(rows: int, cols: int) -> bool:
    """True when the products of a problem of ``rows`` x ``cols`` never run a second BLAS thread.

    The solve path then skips :data:`one_blas_thread` around the whole step (its two C calls
    per library, about 37 k instructions, would cost more than the step's products); the parts
    that factorise matrices (the certificate's cold solves, the repair, the damping screen's
    examination, the degenerate rows' SVD, the hard rows' least squares) enter it themselves.
    """
    return rows * rows * cols <= SINGLE_THREADED_SIZE


def warm_up() -> None:
    """Pay the process's one-time costs of the solve path now, not in a first control step.

    Finding the BLAS libraries (about 40 ms) and numpy's first ``unique`` (its lazily loaded
    module, about 10 ms) would otherwise fall into the first step and eat its deadline; a safe
    solver calls this when it is built. Idempotent.
    """
    if one_blas_thread._libs is None:
        one_blas_thread._find()
        np.unique(np.zeros(1))
