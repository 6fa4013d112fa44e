"""The solve path's guarded calls into compiled linear algebra (``uvms_qp.hqp.linalg``)."""

import math
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import nnls as scipy_nnls
from threadpoolctl import ThreadpoolController

from uvms_qp.hqp import linalg
from uvms_qp.hqp.linalg import OneBlasThread, nnls, one_blas_thread, single_threaded


def blas_threads():
    return [lib.get_num_threads() for lib in ThreadpoolController().lib_controllers
            if lib.user_api == "blas"]


def test_nnls_without_columns_is_the_residual_of_zero():
    c, r = nnls(np.zeros((3, 0)), np.array([3.0, 0.0, 4.0]))
    assert c.shape == (0,) and r == pytest.approx(5.0)


def test_nnls_without_rows_is_zero():
    c, r = nnls(np.zeros((0, 2)), np.zeros(0))
    assert c.tolist() == [0.0, 0.0] and r == 0.0


def test_nnls_refuses_non_finite_input_with_zero_multipliers():
    A = np.array([[1.0, np.nan], [0.0, 1.0]])
    c, r = nnls(A, np.array([1.0, 1.0]))
    assert c.tolist() == [0.0, 0.0] and r == pytest.approx(math.sqrt(2.0))
    c, r = nnls(np.eye(2), np.array([np.inf, 1.0]))
    assert c.tolist() == [0.0, 0.0] and r == math.inf


def test_nnls_agrees_with_scipy_on_ordinary_input():
    rng = np.random.default_rng(3)
    A, b = rng.standard_normal((6, 4)), rng.standard_normal(6)
    c, r = nnls(A, b)
    c0, r0 = scipy_nnls(A, b)
    np.testing.assert_allclose(c, c0, atol=1e-12)
    assert r == pytest.approx(r0)


def test_one_blas_thread_inside_the_context_and_the_user_setting_after():
    controller = ThreadpoolController()
    with controller.limit(limits=2, user_api="blas"):
        before = blas_threads()
        with one_blas_thread:
            assert set(blas_threads()) <= {1}
            with one_blas_thread:  # nested: still one, and the outer exit restores
                assert set(blas_threads()) <= {1}
            assert set(blas_threads()) <= {1}
        assert blas_threads() == before


def test_one_blas_thread_holds_in_a_thread_of_its_own():
    limiter = OneBlasThread()
    seen = []

    def other():
        with limiter:
            seen.append(blas_threads())
            with limiter:
                seen.append(blas_threads())
        seen.append(blas_threads())

    before = blas_threads()
    worker = threading.Thread(target=other)
    worker.start()
    worker.join(10.0)
    assert [set(counts) <= {1} for counts in seen[:2]] == [True, True]
    assert seen[2] == before
    assert blas_threads() == before


# ---- the kernels the layer's hot loops take from here, against the plain numpy forms


def test_the_bound_reductions_are_numpy_max_and_min():
    rng = np.random.default_rng(4)
    a = rng.standard_normal((5, 7))
    assert linalg.max_of(a, axis=None) == np.max(a)
    assert linalg.min_of(a, axis=None) == np.min(a)
    np.testing.assert_array_equal(linalg.max_of(a, axis=1), np.max(a, axis=1))
    assert linalg.max_of(np.zeros(0), initial=-1.0) == -1.0
    finite = np.isfinite(np.array([1.0, np.inf, -3.0]))
    assert linalg.max_of(np.abs([1.0, np.inf, -3.0]), axis=None, where=finite, initial=0.0) == 3.0


def test_segment_max_is_the_largest_entry_of_each_segment():
    a = np.array([3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0])
    starts = np.array([0, 2, 3])
    expected = [max(a[0:2]), max(a[2:3]), max(a[3:])]
    np.testing.assert_array_equal(linalg.segment_max(a, starts), expected)


def test_the_bound_ufuncs_compute_what_numpy_computes():
    rng = np.random.default_rng(5)
    x, y = rng.standard_normal(9), rng.standard_normal(9)
    z = np.where(x > 0.5, np.inf, np.where(x < -0.5, np.nan, x))
    pairs = {"absolute": (np.abs(x), (x,)), "sqrt": (np.sqrt(np.abs(x)), (np.abs(x),)),
             "square": (x * x, (x,)), "add": (x + y, (x, y)), "subtract": (x - y, (x, y)),
             "multiply": (x * y, (x, y)), "divide": (x / y, (x, y)),
             "maximum": (np.where(x > y, x, y), (x, y)), "minimum": (np.where(x < y, x, y), (x, y)),
             "greater_equal": (x >= y, (x, y)), "less_equal": (x <= y, (x, y)),
             "logical_or": ((x > 0) | (y > 0), (x > 0, y > 0)), "dot": (float(x @ y), (x, y)),
             "isfinite": ([math.isfinite(v) for v in z], (z,))}
    for name, (expected, args) in pairs.items():
        np.testing.assert_array_equal(getattr(linalg, name)(*args), expected, err_msg=name)


def test_concatenate_and_vdot_compute_what_numpy_computes():
    rng = np.random.default_rng(9)
    a, b = rng.standard_normal((3, 4)), rng.standard_normal((2, 4))
    out = np.empty((5, 4))
    assert linalg.concatenate((a, b), out=out) is out
    np.testing.assert_array_equal(out, np.concatenate((a, b)))
    np.testing.assert_array_equal(linalg.concatenate([a[0], b[1]]), np.concatenate([a[0], b[1]]))
    sides = np.array([[1.0, -np.inf], [2.0, np.inf]])
    signs = np.array([[1.0, 1.0], [-1.0, -1.0]])
    assert linalg.vdot(a, a) == np.vdot(a, a)
    assert linalg.vdot(sides, signs) == np.vdot(sides, signs) == -math.inf


def test_count_nonzero_counts_what_numpy_counts():
    rng = np.random.default_rng(10)
    a = rng.standard_normal((3, 5))
    assert linalg.count_nonzero(a > 0.0) == np.count_nonzero(a > 0.0) == int((a > 0.0).sum())
    assert linalg.count_nonzero(np.zeros(0, dtype=bool)) == 0
    assert linalg.count_nonzero(np.isfinite(np.array([1.0, np.inf, np.nan]))) == 1


def test_gesdd_gives_numpys_singular_decomposition():
    rng = np.random.default_rng(6)
    M = rng.standard_normal((6, 4))
    u, s, vt, info = linalg.gesdd(M, compute_uv=1, full_matrices=1)
    assert info == 0
    np.testing.assert_allclose(s, np.linalg.svd(M, compute_uv=False), rtol=1e-13)
    sigma = np.zeros((6, 4))
    sigma[:4, :4] = np.diag(s)
    np.testing.assert_allclose(u @ sigma @ vt, M, atol=1e-13)
    np.testing.assert_allclose(linalg.gesdd(M, compute_uv=0)[1], s, rtol=1e-15)


def test_potrf_succeeds_exactly_where_numpys_cholesky_does():
    rng = np.random.default_rng(7)
    B = rng.standard_normal((4, 4))
    spd = B @ B.T + 0.1 * np.eye(4)
    L, info = linalg.potrf(spd.copy(), 1)  # lower
    assert info == 0
    np.testing.assert_allclose(np.tril(L), np.linalg.cholesky(spd), rtol=1e-12)
    indefinite = np.diag([1.0, -1.0, 2.0, 3.0])
    assert linalg.potrf(indefinite.copy(), 0, 0, 1)[1] != 0  # as the damping screen calls it
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.cholesky(indefinite)


# ---- the size below which a solve runs without the limit


def _worker_cpu_ticks() -> int:
    """CPU time [clock ticks] of every thread of the process but this one (OpenBLAS' workers)."""
    me = threading.get_native_id()
    total = 0
    for tid in os.listdir("/proc/self/task"):
        if int(tid) != me:
            try:
                stat = Path(f"/proc/self/task/{tid}/stat").read_text()
            except OSError:  # a thread that ended meanwhile
                continue
            fields = stat.rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])  # utime, stime
    return total


def _hierarchy_at_the_limit(rng: np.random.Generator, n: int, sizes: list[int]) -> list:
    """Levels of random rows (equalities and two-sided rows), more rows than freedom."""
    levels = []
    for k, m in enumerate(sizes):
        A = rng.standard_normal((m, n))
        b = rng.standard_normal(m)
        levels.append([(A, b)] if k % 2 == 0 else [(A, b - 0.1, b + 0.1)])
    return levels


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="needs Linux's /proc")
def test_a_solve_of_a_single_threaded_size_gives_openblas_threads_no_work():
    from uvms_qp.hqp import HierarchySolver, solve_hierarchy
    from uvms_qp.safety import SafeSolver

    rng = np.random.default_rng(8)
    cases = [(16, [16, 16, 16]), (25, [10, 10, 6]), (4, [40, 40, 44])]  # M * M * n <= 65536
    with ThreadpoolController().limit(limits=2, user_api="blas"):
        big = rng.standard_normal((300, 300))
        before = _worker_cpu_ticks()
        for _ in range(30):
            big.dot(big)
        if _worker_cpu_ticks() == before:
            pytest.skip("OpenBLAS runs no second thread on this machine")
        time.sleep(0.5)  # OpenBLAS' threads spin a while after work before they sleep
        before = _worker_cpu_ticks()
        time.sleep(0.2)
        if _worker_cpu_ticks() != before:
            pytest.skip("other threads of the process are busy")
        for n, sizes in cases:
            levels = _hierarchy_at_the_limit(rng, n, sizes)
            box = np.full(n, 0.5)
            solver = HierarchySolver("daqp")
            problem = solver._validate(levels, -box, box)
            assert problem.single_threaded
            assert not single_threaded(problem.M + 1, n)  # the case is at the limit
            safe = SafeSolver("daqp")
            before = _worker_cpu_ticks()
            for _ in range(100):
                result = solve_hierarchy(levels, -box, box)
                safe.solve(problem)
            assert result.status.value in ("optimal", "unproven")
            assert _worker_cpu_ticks() == before, (n, sizes)
