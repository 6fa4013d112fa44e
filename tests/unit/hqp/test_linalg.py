"""The solve path's guarded calls into compiled linear algebra (``uvms_qp.hqp.linalg``)."""

import math
import threading

import numpy as np
import pytest
from scipy.optimize import nnls as scipy_nnls
from threadpoolctl import ThreadpoolController

from uvms_qp.hqp.linalg import OneBlasThread, nnls, one_blas_thread


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
