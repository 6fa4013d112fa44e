"""DAQP behind one small interface: its C entry points, called on the caller's arrays.

The DAQP back-end (:mod:`uvms_qp.hqp.backends.daqp`) sets a problem up once per structure and
then, every solve, writes the rows, sides and per-row soft weights into arrays it owns and asks
DAQP to take them over and solve; the optimality certificate solves its least-distance problems
the same way. :class:`NativeDaqp` calls DAQP's C entry points (``setup_daqp_main``,
``daqp_update_ldp``, ``daqp_solve``...), which its Python extension exports, through
:mod:`ctypes` on those arrays: a refresh is one C call that re-reads rows, sides and soft
weights, a solve one C call that writes ``x`` into a buffer; no argument conversion, copy or
dictionary per call. Its structures mirror DAQP's ``types.h`` and ``api.h`` of the versions in
:data:`SUPPORTED_VERSIONS` (the workspace only up to the fields read here), so another version
is refused with an error that says which one to install, before any structure is read: a
mirrored layout that does not match would read and write the wrong memory. The same interface
through ``daqp.Model`` (slower, obviously right) lives under ``tests/`` as the oracle that the
binding's answers, iterations and working sets are checked against, bit for bit.
"""

from __future__ import annotations

import ctypes as C
import importlib.metadata
from functools import cache
from typing import Any, Protocol

import numpy as np

from ..._validation import FloatArray

SUPPORTED_VERSIONS: tuple[str, ...] = ("0.11.0",)
"""DAQP versions whose C structure layout is mirrored here."""

_DP = C.POINTER(C.c_double)
_IP = C.POINTER(C.c_int)
_VP = C.c_void_p

# daqp_update_ldp mask bits (DAQP constants.h)
UPDATE_M = 2
UPDATE_D = 8
UPDATE_V = 4
UPDATE_SENSE = 16
_COLD = UPDATE_V | UPDATE_D | UPDATE_SENSE
_COLD_ROWS = UPDATE_M | UPDATE_V | UPDATE_D | UPDATE_SENSE


class _Problem(C.Structure):
    """``DAQPProblem``: the QP data (pointers into caller-owned arrays)."""

    _fields_ = [("n", C.c_int), ("m", C.c_int), ("ms", C.c_int), ("H", _DP), ("f", _DP),
                ("A", _DP), ("bupper", _DP), ("blower", _DP), ("sense", _IP),
                ("break_points", _IP), ("nh", C.c_int), ("problem_type", C.c_int)]


class _Settings(C.Structure):
    """``DAQPSettings``."""

    _fields_ = [("primal_tol", C.c_double), ("dual_tol", C.c_double),
                ("zero_tol", C.c_double), ("pivot_tol", C.c_double),
                ("progress_tol", C.c_double), ("cycle_tol", C.c_int), ("iter_limit", C.c_int),
                ("fval_bound", C.c_double), ("eps_prox", C.c_double), ("eta_prox", C.c_double),
                ("rho_soft", C.c_double), ("rel_subopt", C.c_double),
                ("abs_subopt", C.c_double), ("sing_tol", C.c_double),
                ("refactor_tol", C.c_double), ("time_limit", C.c_double),
                ("w_soft", C.c_double), ("eq_reduction", C.c_int), ("presolve", C.c_int)]


class _Result(C.Structure):
    """``DAQPResult``."""

    _fields_ = [("x", _DP), ("lam", _DP), ("fval", C.c_double), ("soft_slack", C.c_double),
                ("exitflag", C.c_int), ("iter", C.c_int), ("nodes", C.c_int),
                ("solve_time", C.c_double), ("setup_time", C.c_double)]


class _Workspace(C.Structure):
    """``DAQPWorkspace`` up to and including ``state`` (the memory is over-allocated)."""

    _fields_ = [("qp", _VP), ("n", C.c_int), ("m", C.c_int), ("ms", C.c_int), ("M", _DP),
                ("dupper", _DP), ("dlower", _DP), ("Rinv", _DP), ("v", _DP), ("sense", _IP),
                ("scaling", _DP), ("RinvD", _DP), ("x", _DP), ("xold", _DP), ("lam", _DP),
                ("lam_star", _DP), ("u", _DP), ("fval", C.c_double), ("L", _DP), ("D", _DP),
                ("xldl", _DP), ("zldl", _DP), ("reuse_ind", C.c_int), ("WS", _IP),
                ("n_active", C.c_int), ("iterations", C.c_int), ("sing_ind", C.c_int),
                ("prox_mask", _IP), ("n_prox", C.c_int), ("soft_slack", C.c_double),
                ("settings", C.POINTER(_Settings)), ("bnb", _VP), ("outer_iter", C.c_int),
                ("hierarchy", _VP), ("avi", _VP), ("eq", _VP), ("timer", _VP), ("Mu", _DP),
                ("rho_ls", _DP), ("rho_us", _DP), ("w_ls", _DP), ("w_us", _DP),
                ("state", C.c_int)]


_WORK_BYTES = C.sizeof(_Workspace) + 256  # slack in case of trailing padding
_SETTING_NAMES = tuple(field[0] for field in _Settings._fields_)


@cache
def _daqp_version() -> str | None:
    try:
        return importlib.metadata.version("daqp")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - daqp is a dependency
        return None


@cache
def _library() -> Any:
    """DAQP's extension loaded as a C library with typed entry points (raises if impossible)."""
    import daqp

    lib = C.CDLL(daqp.__file__)
    lib.allocate_daqp_settings.argtypes = [_VP]
    lib.allocate_daqp_settings.restype = None
    lib.daqp_default_settings.argtypes = [C.POINTER(_Settings)]
    lib.daqp_default_settings.restype = None
    lib.setup_daqp_main.argtypes = [C.POINTER(_Problem), _VP, _DP, C.c_int]
    lib.setup_daqp_main.restype = C.c_int
    lib.daqp_update_ldp.argtypes = [C.c_int, _VP, C.POINTER(_Problem)]
    lib.daqp_update_ldp.restype = C.c_int
    lib.daqp_solve.argtypes = [C.POINTER(_Result), _VP]
    lib.daqp_solve.restype = None
    lib.daqp_allocate_soft_weights.argtypes = [_VP]
    lib.daqp_allocate_soft_weights.restype = C.c_int
    lib.daqp_set_soft_weights.argtypes = [_VP, _DP, _DP, _DP, _DP]
    lib.daqp_set_soft_weights.restype = C.c_int
    lib.daqp_refresh_soft_weights.argtypes = [_VP]
    lib.daqp_refresh_soft_weights.restype = None
    lib.free_daqp_workspace.argtypes = [_VP]
    lib.free_daqp_workspace.restype = None
    lib.free_daqp_ldp.argtypes = [_VP]
    lib.free_daqp_ldp.restype = None
    return lib


def check_version() -> None:
    """Refuse a DAQP whose C structures this module does not mirror.

    Raises:
        ImportError: the installed version is not in :data:`SUPPORTED_VERSIONS` (the message
            says which to install), or its extension does not export the C entry points.
    """
    version = _daqp_version()
    if version not in SUPPORTED_VERSIONS:
        raise ImportError(f"uvms-qp drives DAQP through its C API as of version(s) "
                          f"{', '.join(SUPPORTED_VERSIONS)}; installed: {version}. Install it "
                          f"with: pip install daqp=={SUPPORTED_VERSIONS[-1]}")
    try:
        _library()
    except (OSError, AttributeError) as exc:
        raise ImportError(f"DAQP {version}: its extension does not export the C API ({exc})"
                          ) from exc


class DaqpBinding(Protocol):
    """The interface of :class:`NativeDaqp` (a test's oracle or fault injector offers it too).

    Attributes:
        x: Primal solution of the latest solve (may be a reused buffer: copy to keep).
        lam: Multipliers of the latest solve, one per constraint (simple bounds first; > 0 at
            an upper side, < 0 at a lower side; may be a reused buffer).
        solve_time: DAQP's own time of the latest solve [s].
        iterations: Iterations of the latest solve.
    """

    x: FloatArray
    lam: FloatArray
    solve_time: float
    iterations: int

    def setup(self, H: FloatArray, f: FloatArray, A: FloatArray, bupper: FloatArray,
              blower: FloatArray, sense: np.ndarray, break_points: np.ndarray
              ) -> tuple[int, float]:
        """Set a problem up on these arrays (kept: later refreshes re-read them in place).

        Returns:
            ``(exit flag, setup time [s])``; a negative flag means nothing else may be called.
        """

    @property
    def settings(self) -> dict[str, Any]:
        """DAQP's settings (assign a dict to change some)."""

    @settings.setter
    def settings(self, new: dict[str, Any]) -> None: ...

    def soft_weights(self, rho: FloatArray) -> bool:
        """Set the per-constraint reciprocal soft weights (both sides); False if unsupported."""

    def soft_weight_views(self) -> tuple[FloatArray, FloatArray] | None:
        """Arrays of per-constraint soft weights taken over by :meth:`refresh` (or None)."""

    def refresh(self) -> int:
        """Hand the rows, sides and soft weights written in place to DAQP (warm start kept)."""

    def restart(self, sense: np.ndarray) -> int:
        """Start the next solve cold, from the working set ``sense``."""

    def solve(self) -> int:
        """Solve; returns the exit flag (1 optimal, 2 soft optimal, negative on failure)."""

    def solve_ldp(self, rows: bool, warm: bool) -> int:
        """Re-read ``f``, the sides (and rows), solve; sets ``lam``.

        The solve starts from an empty working set, or (``warm``) from the working set of the
        latest solve (valid when the sides kept their pattern since then).
        """


def open_daqp() -> NativeDaqp:
    """A fresh DAQP workspace (:class:`NativeDaqp`); the version is checked on first use."""
    return NativeDaqp()


def _libc_free(pointer: Any) -> None:
    """Free memory DAQP allocated with ``malloc`` (its settings before any set-up)."""
    free = C.CDLL(None).free
    free.argtypes = [_VP]
    free.restype = None
    free(pointer)


def _ptr(array: np.ndarray, kind: Any = _DP) -> Any:
    return array.ctypes.data_as(kind)


def _contiguous(array: Any, dtype: Any) -> np.ndarray:
    return np.ascontiguousarray(array, dtype=dtype)


class NativeDaqp:
    """A DAQP workspace driven through its C API (see the module docstring).

    The rows and sides passed to :meth:`setup` are used in place (C-contiguous float64, else
    refused: :meth:`refresh` re-reads them); ``H``, ``f``, ``sense`` and ``break_points`` are
    copied when not C-contiguous of the right type (float64, C int).

    Args:
        lib: The loaded library (default: DAQP's extension, its version checked).
    """

    def __init__(self, lib: Any = None) -> None:
        if lib is None:
            check_version()
        self._lib = lib if lib is not None else _library()
        self._work: Any = C.create_string_buffer(_WORK_BYTES)
        self._view = _Workspace.from_buffer(self._work)
        self._lib.allocate_daqp_settings(self._work)
        self._qp = _Problem()
        self._qp_ref = C.byref(self._qp)
        self._held: tuple[np.ndarray, ...] = ()
        self._sense = np.zeros(0, dtype=np.intc)
        self._has_model = False
        self._warm = False  # qp.sense points at the working set of the latest solve
        self.x = np.zeros(0)
        self.lam = np.zeros(0)
        self._empty = np.zeros(0, dtype=np.intc)  # an empty working set (cold starts)
        self._empty_ptr: Any = None
        self._res = _Result()
        self._res_ref = C.byref(self._res)
        self._mask = C.c_int(UPDATE_M | UPDATE_D | UPDATE_SENSE)
        self._update = self._lib.daqp_update_ldp
        self._solve = self._lib.daqp_solve
        self.solve_time = 0.0
        self.iterations = 0

    def __del__(self) -> None:
        work = getattr(self, "_work", None)
        if work is None:
            return
        lib = self._lib
        if self._has_model:
            lib.free_daqp_workspace(work)
            lib.free_daqp_ldp(work)
        else:
            settings = self._view.settings
            if settings:
                _libc_free(C.cast(settings, _VP))
        self._work = None

    def setup(self, H: FloatArray, f: FloatArray, A: FloatArray, bupper: FloatArray,
              blower: FloatArray, sense: np.ndarray, break_points: np.ndarray
              ) -> tuple[int, float]:
        """``daqp.Model.setup`` on arrays kept in place; returns ``(flag, setup_time)``.

        Raises:
            ValueError: ``A``, ``bupper`` or ``blower`` is not C-contiguous float64: later
                refreshes re-read them in place, so a copy made here would hand DAQP the
                set-up's values on every later solve.
        """
        for name, array in (("A", A), ("bupper", bupper), ("blower", blower)):
            if not (isinstance(array, np.ndarray) and array.dtype == np.float64
                    and array.flags.c_contiguous):
                raise ValueError(f"DAQP set-up: {name} must be a C-contiguous float64 array "
                                 "(DAQP re-reads it in place)")
        H, f = _contiguous(H, np.float64), _contiguous(f, np.float64)
        bu, bl = bupper, blower
        sense = _contiguous(sense, np.intc)
        bp = _contiguous(break_points, np.intc)
        n, m = f.shape[0], bu.shape[0]
        lib, work, view = self._lib, self._work, self._view
        saved = _Settings.from_buffer_copy(view.settings.contents)
        if self._has_model:  # a new structure: start from a clean workspace, same settings
            lib.free_daqp_workspace(work)  # also frees the settings
            lib.free_daqp_ldp(work)
            self._has_model = False
            self._reset_workspace(saved)
        self._held = (H, f, A, bu, bl, sense, bp)
        self._sense = sense
        qp = self._qp
        qp.n, qp.m, qp.ms = n, m, n
        qp.H, qp.f, qp.A = _ptr(H), _ptr(f), _ptr(A)
        qp.bupper, qp.blower = _ptr(bu), _ptr(bl)
        qp.sense, qp.break_points = _ptr(sense, _IP), _ptr(bp, _IP)
        qp.nh, qp.problem_type = bp.shape[0], 0
        self._warm = False
        setup_time = C.c_double(0.0)
        flag = int(lib.setup_daqp_main(self._qp_ref, work, C.byref(setup_time), 0))
        if flag < 0:  # DAQP freed the workspace and its settings
            self._reset_workspace(saved)
            return flag, float(setup_time.value)
        self._has_model = True
        self.x = np.zeros(n)
        self.lam = np.zeros(m)
        self._empty = np.zeros(m, dtype=np.intc)
        self._empty_ptr = _ptr(self._empty, _IP)
        self._res.x, self._res.lam = _ptr(self.x), _ptr(self.lam)
        return flag, float(setup_time.value)

    def _reset_workspace(self, settings: _Settings) -> None:
        """Zero the (freed) workspace and give it fresh settings equal to ``settings``."""
        C.memset(self._work, 0, _WORK_BYTES)
        self._lib.allocate_daqp_settings(self._work)
        self._view.settings[0] = settings

    @property
    def settings(self) -> dict[str, Any]:
        """Current settings as a dict (``daqp.Model.settings``); assign a dict to change some."""
        s = self._view.settings.contents
        return {k: getattr(s, k) for k in _SETTING_NAMES}

    @settings.setter
    def settings(self, new: dict[str, Any]) -> None:
        s = self._view.settings.contents
        old = (s.rho_soft, s.w_soft)
        for key, value in new.items():
            if key in _SETTING_NAMES:
                setattr(s, key, value)
        if self._has_model and (s.rho_soft, s.w_soft) != old:
            self._lib.daqp_refresh_soft_weights(self._work)

    def soft_weights(self, rho: FloatArray) -> bool:
        """Copy ``rho`` (one entry per constraint, C-contiguous float64) to both sides."""
        ptr = _ptr(rho)
        return bool(self._lib.daqp_set_soft_weights(self._work, ptr, ptr, None, None))

    def soft_weight_views(self) -> tuple[FloatArray, FloatArray] | None:
        """DAQP's own per-constraint ``rho`` arrays (lower, upper sides) as numpy views.

        Values written into them take effect at the next :meth:`refresh` (which rebuilds the
        factorisation with them). Valid until the next :meth:`setup`; None on a DAQP built
        without per-constraint weights.
        """
        if not self._has_model or not self._lib.daqp_allocate_soft_weights(self._work):
            return None
        m = self._qp.m
        view = self._view
        return (np.ctypeslib.as_array(view.rho_ls, shape=(m,)),
                np.ctypeslib.as_array(view.rho_us, shape=(m,)))

    def refresh(self) -> int:
        """Hand the set-up arrays (rows, sides, weights written in place) to DAQP."""
        return self._update(self._mask, self._work, self._qp_ref)  # an int (restype)

    def restart(self, sense: np.ndarray) -> int:
        """Cold start: the next solve starts from the working set ``sense``."""
        self._sense[...] = sense
        self._qp.sense = _ptr(self._sense, _IP)
        self._warm = False
        return int(self._lib.daqp_update_ldp(UPDATE_SENSE, self._work, self._qp_ref))

    def solve(self) -> int:
        """Solve; returns DAQP's exit flag and sets ``x`` (a reused buffer), time, iterations."""
        res = self._res
        self._solve(self._res_ref, self._work)
        if not self._warm:  # later refreshes keep the working set of this solve
            self._qp.sense = self._view.sense
            self._warm = True
        self.solve_time = res.solve_time
        self.iterations = res.iter
        return res.exitflag  # an int (ctypes field)

    def solve_ldp(self, rows: bool, warm: bool) -> int:
        """Re-read ``f``, the sides (and rows) and solve; ``lam`` is set.

        From an empty working set, or (``warm``) from the latest solve's.
        """
        lib, qp, res = self._lib, self._qp, self._res
        if warm:  # DAQP activates the constraints its own sense array marks active
            qp.sense = self._view.sense
        else:
            qp.sense = self._empty_ptr  # DAQP copies it: the array stays empty
        lib.daqp_update_ldp(_COLD_ROWS if rows else _COLD, self._work, self._qp_ref)
        self._warm = warm
        lib.daqp_solve(self._res_ref, self._work)
        self.iterations = res.iter
        return int(res.exitflag)
