"""DAQP's C entry points called directly, for the per-tick hot path.

DAQP's Python extension carries the whole C library and exports its symbols (``setup_daqp_main``,
``daqp_update_ldp``, ``daqp_solve``...). :class:`NativeDaqp` calls them through :mod:`ctypes` on
arrays the caller owns and fills in place: an update is one C call that re-reads the rows and
sides, a solve is one C call that writes ``x`` into a buffer, with no argument conversion, copy
or dictionary per call. It offers the subset of ``daqp.Model`` that the back-end uses
(``setup``, ``update``, ``solve``, ``settings``) plus the allocation-free pair :meth:`refresh` /
:meth:`solve_in_place`.

The structures below mirror DAQP's ``types.h`` and ``api.h`` of the versions listed in
:data:`SUPPORTED_VERSIONS` (the workspace only up to the fields read here). For any other
installed version, on a platform whose extension does not export the symbols, or when the
start-up check fails (the settings DAQP allocates must equal its documented defaults, and a small
hierarchical problem must give ``daqp.Model``'s answer bit for bit), :func:`native_available` is
False and callers use ``daqp.Model``: same answers, a few microseconds slower.
"""

from __future__ import annotations

import ctypes as C
import importlib.metadata
from functools import cache
from typing import Any

import numpy as np

from .._validation import FloatArray

SUPPORTED_VERSIONS: tuple[str, ...] = ("0.11.0",)
"""DAQP versions whose C structure layout is mirrored here."""

_DP = C.POINTER(C.c_double)
_IP = C.POINTER(C.c_int)
_VP = C.c_void_p

# daqp_update_ldp mask bits (DAQP constants.h)
UPDATE_M = 2
UPDATE_D = 8
UPDATE_SENSE = 16


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


@cache
def native_available() -> bool:
    """True when :class:`NativeDaqp` can be used (see the module docstring); checked once."""
    if _daqp_version() not in SUPPORTED_VERSIONS:
        return False
    try:
        lib = _library()
    except (ImportError, OSError, AttributeError):
        return False
    return _self_check(lib)


def _self_check(lib: Any) -> bool:
    """Defaults read through the mirrored layout, and one hierarchical solve vs ``daqp.Model``."""
    import daqp

    expected = _Settings()
    lib.daqp_default_settings(C.byref(expected))
    probe = NativeDaqp(lib)
    read = probe._work_view.settings
    if not read or any(getattr(read.contents, k) != getattr(expected, k) for k in _SETTING_NAMES):
        return False
    rng = np.random.default_rng(7)
    n, sizes = 5, (3, 2, 2)
    A = rng.standard_normal((sum(sizes), n))
    bl = np.concatenate((-0.3 * np.ones(n), rng.standard_normal(sum(sizes))))
    bu = bl.copy()
    bu[:n] = 0.3
    bp = np.cumsum((n, *sizes)).astype(np.intc)
    H, f = np.diag(np.linspace(1.0, 2.0, n)), np.zeros(n)
    sense = np.zeros(n + sum(sizes), dtype=np.intc)
    answers = []
    for model in (probe, daqp.Model()):
        model.setup(H, f, A, bu.copy(), bl.copy(), sense.copy(), break_points=bp)
        settings = model.settings
        settings["rho_soft"] = 1e-8
        model.settings = settings
        x, _, flag, _ = model.solve()
        answers.append((flag, x))
    (f1, x1), (f2, x2) = answers
    return bool(f1 == f2 and f1 in (1, 2) and np.array_equal(x1, x2))


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

    Arrays passed to :meth:`setup` are used in place when they are C-contiguous of the right
    type (float64, or C int for ``sense`` and ``break_points``): after writing new values into
    them, :meth:`refresh` hands them to DAQP. Results are written into :attr:`x`.

    Args:
        lib: The loaded library (default: DAQP's extension); for the start-up check only.

    Attributes:
        x: Primal solution of the latest solve (a reused buffer).
        solve_time: DAQP's own solve time of the latest solve [s].
        iterations: Iterations of the latest solve.
    """

    def __init__(self, lib: Any = None) -> None:
        self._lib = lib if lib is not None else _library()
        self._work: Any = C.create_string_buffer(_WORK_BYTES)
        self._work_view = _Workspace.from_buffer(self._work)
        self._lib.allocate_daqp_settings(self._work)
        self._qp = _Problem()
        self._qp_ref = C.byref(self._qp)
        self._held: tuple[np.ndarray, ...] = ()
        self._sense = np.zeros(0, dtype=np.intc)
        self._has_model = False
        self._has_solved = False
        self.x = np.zeros(0)
        self._lam = np.zeros(0)
        self._res = _Result()
        self._res_ref = C.byref(self._res)
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
            settings = self._work_view.settings
            if settings:
                _libc_free(C.cast(settings, _VP))
        self._work = None

    # ------------------------------------------------------------------------------ set-up
    def setup(self, H: Any, f: Any, A: Any, bupper: Any, blower: Any, sense: Any,
              break_points: Any) -> tuple[int, float]:
        """Set the problem up (``daqp.Model.setup`` semantics); returns ``(flag, setup_time)``.

        Args:
            H: Hessian (n, n).
            f: Linear cost (n,).
            A: General rows (m - n, n).
            bupper: Upper sides (m,): the n simple bounds, then the rows.
            blower: Lower sides (m,).
            sense: Constraint flags (m,) (C int).
            break_points: Hierarchy break points (C int).
        """
        H, f, A = _contiguous(H, np.float64), _contiguous(f, np.float64), _contiguous(A, np.float64)
        bu, bl = _contiguous(bupper, np.float64), _contiguous(blower, np.float64)
        sense = _contiguous(sense, np.intc)
        bp = _contiguous(break_points, np.intc)
        n, m = f.shape[0], bu.shape[0]
        lib, work, view = self._lib, self._work, self._work_view
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
        setup_time = C.c_double(0.0)
        flag = int(lib.setup_daqp_main(self._qp_ref, work, C.byref(setup_time), 0))
        if flag < 0:  # DAQP freed the workspace and its settings
            self._reset_workspace(saved)
            return flag, float(setup_time.value)
        self._has_model, self._has_solved = True, False
        self.x = np.zeros(n)
        self._lam = np.zeros(m)
        self._res.x, self._res.lam = _ptr(self.x), _ptr(self._lam)
        return flag, float(setup_time.value)

    def _reset_workspace(self, settings: _Settings) -> None:
        """Zero the (freed) workspace and give it fresh settings equal to ``settings``."""
        C.memset(self._work, 0, _WORK_BYTES)
        self._lib.allocate_daqp_settings(self._work)
        self._work_view.settings[0] = settings

    # ------------------------------------------------------------------------------ settings
    @property
    def settings(self) -> dict[str, Any]:
        """Current settings as a dict (``daqp.Model.settings``); assign a dict to change some."""
        s = self._work_view.settings.contents
        return {k: getattr(s, k) for k in _SETTING_NAMES}

    @settings.setter
    def settings(self, new: dict[str, Any]) -> None:
        s = self._work_view.settings.contents
        old = (s.rho_soft, s.w_soft)
        for key, value in new.items():
            if key in _SETTING_NAMES:
                setattr(s, key, value)
        if self._has_model and (s.rho_soft, s.w_soft) != old:
            self._lib.daqp_refresh_soft_weights(self._work)

    # ------------------------------------------------------------------------------ per call
    def update(self, A: Any = None, bupper: Any = None, blower: Any = None,
               sense: Any = None) -> int:
        """``daqp.Model.update`` for the rows, sides and sense; returns DAQP's exit flag.

        Arrays that are not the ones given at set-up are copied into those (same shapes).
        Without ``sense``, a change of the rows keeps the working set of the previous solve
        (warm start); an explicit ``sense`` replaces it (e.g. a cold start).
        """
        _, _, A0, bu, bl, s0, _ = self._held
        mask = 0
        if A is not None:
            if A is not A0:
                A0[...] = A
            mask |= UPDATE_M
        if bupper is not None:
            if bupper is not bu:
                bu[...] = bupper
            mask |= UPDATE_D
        if blower is not None:
            if blower is not bl:
                bl[...] = blower
            mask |= UPDATE_D
        qp = self._qp
        if sense is not None:
            s0[...] = sense
            qp.sense = _ptr(s0, _IP)
            mask |= UPDATE_SENSE
        elif mask & UPDATE_M:
            qp.sense = self._work_view.sense if self._has_solved else _ptr(s0, _IP)
            mask |= UPDATE_SENSE
        return int(self._lib.daqp_update_ldp(mask, self._work, self._qp_ref))

    def soft_weights(self, rho_l: Any = None, rho_u: Any = None) -> None:
        """Per-constraint reciprocal quadratic soft weights (``daqp.Model.soft_weights``).

        One entry per constraint (simple bounds first), in the scale of the original problem;
        0 selects ``rho_soft``. The values are copied into the workspace.

        Raises:
            ValueError: an array of the wrong length.
            RuntimeError: a DAQP build without per-constraint soft weights.
        """
        m = self._qp.m
        kept: list[np.ndarray] = []  # alive until the C call has copied the values
        ptrs: list[Any] = []
        for value in (rho_l, rho_u):
            if value is None:
                ptrs.append(None)
                continue
            arr = _contiguous(value, np.float64)
            if arr.shape != (m,):
                raise ValueError(f"soft weights: expected {m} entries, got {arr.shape}")
            kept.append(arr)
            ptrs.append(_ptr(arr))
        lo, hi = ptrs
        if not self._lib.daqp_set_soft_weights(self._work, lo, hi, None, None):
            raise RuntimeError("daqp was built without per-constraint soft weights")

    def soft_weight_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The workspace's own per-constraint ``rho`` arrays (lower, upper sides) as numpy views.

        Values written into them take effect at the next :meth:`refresh` or :meth:`update`
        (which rebuild the factorisation with them), without a call of their own. The views
        are valid until the next :meth:`setup`.

        Raises:
            RuntimeError: no model is set up, or a DAQP build without per-constraint weights.
        """
        if not self._has_model:
            raise RuntimeError("soft_weight_arrays: set a problem up first")
        if not self._lib.daqp_allocate_soft_weights(self._work):
            raise RuntimeError("daqp was built without per-constraint soft weights")
        m = self._qp.m
        view = self._work_view
        return (np.ctypeslib.as_array(view.rho_ls, shape=(m,)),
                np.ctypeslib.as_array(view.rho_us, shape=(m,)))

    def soft_weights_in_place(self, rho: np.ndarray) -> None:
        """:meth:`soft_weights` with the same ``rho`` on both sides, no checks (hot path).

        ``rho`` must be a C-contiguous float64 array of one entry per constraint.
        """
        ptr = _ptr(rho)
        self._lib.daqp_set_soft_weights(self._work, ptr, ptr, None, None)

    def refresh(self) -> int:
        """Hand the set-up arrays (rows and sides written in place) to DAQP; warm start kept."""
        self._qp.sense = self._work_view.sense if self._has_solved else _ptr(self._sense, _IP)
        return int(self._lib.daqp_update_ldp(UPDATE_M | UPDATE_D | UPDATE_SENSE, self._work,
                                             self._qp_ref))

    def solve_in_place(self) -> int:
        """Solve and return DAQP's exit flag (1 optimal, 2 soft optimal, negative on failure).

        Sets ``x`` (a reused buffer), ``solve_time`` and ``iterations``.
        """
        res = self._res
        self._lib.daqp_solve(self._res_ref, self._work)
        self._has_solved = True
        self.solve_time = res.solve_time
        self.iterations = res.iter
        return int(res.exitflag)

    def solve(self) -> tuple[FloatArray, float, int, dict[str, Any]]:
        """``daqp.Model.solve``: ``(x, fval, exitflag, info)`` with fresh arrays."""
        flag = self.solve_in_place()
        info = {"solve_time": self.solve_time, "setup_time": 0.0,
                "iterations": self.iterations, "nodes": self._res.nodes,
                "lam": self._lam.copy()}
        return self.x.copy(), float(self._res.fval), flag, info
