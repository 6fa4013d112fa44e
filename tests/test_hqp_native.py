"""DAQP's C entry points called directly (uvms_qp.hqp.daqp_native) against ``daqp.Model``.

The direct path must be a pure speed-up: bit-identical answers to DAQP's own Python binding on
the same sequence of set-ups, warm-started updates, cold starts and settings changes.
"""

from __future__ import annotations

import daqp
import numpy as np
import pytest

from uvms_qp.hqp.daqp_model import new_daqp_model
from uvms_qp.hqp.daqp_native import SUPPORTED_VERSIONS, NativeDaqp, native_available

pytestmark = pytest.mark.skipif(not native_available(),
                                reason=f"daqp version not in {SUPPORTED_VERSIONS}")


def _hierarchy(rng: np.random.Generator, n: int, sizes: tuple[int, ...], box: float):
    m = sum(sizes)
    A = rng.standard_normal((m, n))
    bl = np.concatenate((-box * np.ones(n), rng.standard_normal(m)))
    bu = bl.copy()
    bu[:n] = box
    # a few inequality rows (one-sided) among the equalities
    ineq = rng.uniform(size=m) < 0.3
    bu[n:][ineq] = 1e30
    bp = np.cumsum((n, *sizes)).astype(np.intc)
    H = np.diag(rng.uniform(0.5, 3.0, n))
    return H, np.zeros(n), A, bu, bl, np.zeros(n + m, dtype=np.intc), bp


def _pair(problem, rho_soft=1e-8):
    H, f, A, bu, bl, sense, bp = problem
    native, model = NativeDaqp(), daqp.Model()
    for m in (native, model):
        assert m.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), break_points=bp)[0] >= 0
        settings = m.settings
        settings["rho_soft"] = rho_soft
        m.settings = settings
    return native, model


def test_available_and_factory_gives_native():
    assert native_available()
    assert isinstance(new_daqp_model(), NativeDaqp)


@pytest.mark.parametrize("seed", range(12))
def test_warm_started_sequence_is_bit_identical(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 14))
    sizes = tuple(int(v) for v in rng.integers(1, 6, size=int(rng.integers(1, 5))))
    box = float(rng.choice([0.05, 0.5, 10.0]))
    problem = _hierarchy(rng, n, sizes, box)
    native, model = _pair(problem)
    _, _, A, bu, bl, _, _ = problem
    for k in range(25):
        if k:  # a drifting problem, as in a control loop
            A += 0.05 * rng.standard_normal(A.shape)
            bl[n:] += 0.05 * rng.standard_normal(A.shape[0])
            bu[n:] = np.where(bu[n:] >= 1e30, 1e30, bl[n:])
        native.update(A=A, bupper=bu, blower=bl)
        model.update(A=A, bupper=bu, blower=bl)
        x1, f1, flag1, info1 = native.solve()
        x2, f2, flag2, info2 = model.solve()
        assert flag1 == flag2
        assert np.array_equal(x1, x2)
        assert f1 == f2
        assert info1["iterations"] == info2["iterations"]
        assert np.array_equal(info1["lam"], info2["lam"])


def test_in_place_refresh_equals_update_with_arrays():
    rng = np.random.default_rng(3)
    H, f, A, bu, bl, sense, bp = _hierarchy(rng, 8, (4, 3, 2), 0.3)
    native = NativeDaqp()
    native.setup(H, f, A, bu, bl, sense, bp)  # float64, contiguous: used in place
    model = daqp.Model()
    model.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), break_points=bp)
    for _ in range(10):
        A[...] = rng.standard_normal(A.shape)  # written into the arrays given at set-up
        bl[8:] = rng.standard_normal(9)
        bu[8:] = bl[8:]
        native.refresh()
        flag = native.solve_in_place()
        model.update(A=A, bupper=bu, blower=bl)
        x2, _, flag2, info2 = model.solve()
        assert flag == flag2 and np.array_equal(native.x, x2)
        assert native.solve_time > 0.0 and native.iterations == info2["iterations"]


def test_cold_start_settings_and_new_structure():
    rng = np.random.default_rng(5)
    problem = _hierarchy(rng, 6, (3, 2), 0.4)
    native, model = _pair(problem, rho_soft=1e-6)
    assert native.settings["rho_soft"] == 1e-6
    assert native.settings == model.settings
    sense = problem[5]
    for m in (native, model):
        m.solve()
        s = m.settings
        s["rho_soft"] = 1e-9
        s["iter_limit"] = 500
        m.settings = s
        m.update(sense=sense.copy())  # cold start
    x1, _, f1, _ = native.solve()
    x2, _, f2, _ = model.solve()
    assert f1 == f2 and np.array_equal(x1, x2)
    assert native.settings["iter_limit"] == 500
    # a new structure on the same object keeps the settings
    H, f, A, bu, bl, sense, bp = _hierarchy(rng, 4, (2,), 1.0)
    assert native.setup(H, f, A, bu, bl, sense, bp)[0] >= 0
    assert native.settings["rho_soft"] == 1e-9
    model.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), break_points=bp)
    assert np.array_equal(native.solve()[0], model.solve()[0])


def test_failed_setup_keeps_a_usable_object():
    rng = np.random.default_rng(9)
    H, f, A, bu, bl, sense, bp = _hierarchy(rng, 4, (2,), 1.0)
    native = NativeDaqp()
    s = native.settings
    s["rho_soft"] = 1e-7
    native.settings = s
    bad_H = -np.eye(4)  # not positive definite: DAQP refuses the set-up
    flag, _ = native.setup(bad_H, f, A, bu, bl, sense, bp)
    model_flag = daqp.Model().setup(bad_H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(),
                                    break_points=bp)[0]
    assert flag == model_flag < 0
    assert native.settings["rho_soft"] == 1e-7
    assert native.setup(H, f, A, bu, bl, sense, bp)[0] >= 0
    x, _, flag, _ = native.solve()
    assert flag in (1, 2) and np.all(np.isfinite(x))


def test_per_row_soft_weights_match_daqp_model():
    rng = np.random.default_rng(13)
    problem = _hierarchy(rng, 7, (4, 3), 0.3)
    native, model = _pair(problem)
    m = problem[3].shape[0]
    for _ in range(5):
        rho = np.where(np.arange(m) < 7, 0.0, 10.0 ** rng.uniform(-9, -6, m))
        native.soft_weights(rho_l=rho, rho_u=rho)
        model.soft_weights(rho_l=rho, rho_u=rho)
        x1, _, f1, _ = native.solve()
        x2, _, f2, _ = model.solve()
        assert f1 == f2 and np.array_equal(x1, x2)
        native.soft_weights_in_place(rho)  # the unchecked twin sets the same values
        assert np.array_equal(native.solve()[0], x2)
    with pytest.raises(ValueError):
        native.soft_weights(rho_l=np.zeros(m - 1))


def test_soft_weight_arrays_written_before_an_update_take_effect():
    rng = np.random.default_rng(17)
    H, f, A, bu, bl, sense, bp = _hierarchy(rng, 6, (3, 3), 0.4)
    native = NativeDaqp()
    native.setup(H, f, A, bu, bl, sense, bp)
    with pytest.raises(RuntimeError):
        NativeDaqp().soft_weight_arrays()  # nothing set up yet
    lower, upper = native.soft_weight_arrays()
    model = daqp.Model()
    model.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), break_points=bp)
    for m in (native, model):
        settings = m.settings
        settings["rho_soft"] = 1e-8
        m.settings = settings
    m_all = bu.shape[0]
    for _ in range(4):
        A[...] = rng.standard_normal(A.shape)
        rho = np.where(np.arange(m_all) < 6, 0.0, 10.0 ** rng.uniform(-9, -6, m_all))
        lower[:] = rho
        upper[:] = rho
        native.refresh()
        flag = native.solve_in_place()
        model.update(A=A, bupper=bu, blower=bl)
        model.soft_weights(rho_l=rho, rho_u=rho)
        x2, _, flag2, _ = model.solve()
        assert flag == flag2
        np.testing.assert_allclose(native.x, x2, atol=1e-12)
