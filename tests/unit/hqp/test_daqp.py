"""The DAQP back-end: its C binding, the per-row soft weights and the accept/retry ladder.

* The ctypes binding must be a pure speed-up of ``daqp.Model``: bit-identical answers through the
  one binding interface on the same set-ups, warm-started refreshes, cold starts and settings.
* Per-row soft weights make DAQP minimise each level's weighted violation: without them DAQP
  scales every row to unit norm and minimises ``sum (s_i / |a_i|)^2`` on a level it cannot meet
  (on the sweep below it then differed from the weighted optimum on about 80 % of the problems,
  by up to 26x in the level's violation). With them it agrees with a certified cascade.
* The rho_soft ladder answers what DAQP stops early on; round-off outside the box is clipped.
"""

from __future__ import annotations

import re
from pathlib import Path

import daqp
import numpy as np
import pytest

from tests.regressions.corpus import load_problem
from tests.support.daqp_model import ModelDaqp
from tests.unit.hqp.test_lexicographic import ill_posed, random_mixed_inputs
from uvms_qp.hqp import HierarchySolver, Problem, Rows, normalize_problem
from uvms_qp.hqp.backends.daqp import _Setup
from uvms_qp.hqp.backends.daqp_binding import SUPPORTED_VERSIONS, NativeDaqp, open_daqp

RHO_LADDER = Path(__file__).parents[2] / "regressions" / "demo_daqp_rho_ladder.npz"


def _hierarchy(rng: np.random.Generator, n: int, sizes: tuple[int, ...], box: float):
    m = sum(sizes)
    A = rng.standard_normal((m, n))
    bl = np.concatenate((-box * np.ones(n), rng.standard_normal(m)))
    bu = bl.copy()
    bu[:n] = box
    ineq = rng.uniform(size=m) < 0.3  # a few one-sided rows among the equalities
    bu[n:][ineq] = 1e30
    bp = np.cumsum((n, *sizes)).astype(np.intc)
    H = np.diag(rng.uniform(0.5, 3.0, n))
    return H, np.zeros(n), A, bu, bl, np.zeros(n + m, dtype=np.intc), bp


def _pair(problem, rho_soft=1e-8):
    """A native and a ``daqp.Model`` binding set up on their own copies of ``problem``."""
    H, f, A, bu, bl, sense, bp = problem
    out = []
    for binding in (NativeDaqp(), ModelDaqp()):
        arrays = (A.copy(), bu.copy(), bl.copy())
        assert binding.setup(H, f, *arrays, sense.copy(), bp)[0] >= 0
        binding.settings = {"rho_soft": rho_soft}
        out.append((binding, arrays))
    return out


# ------------------------------------------------------------------------------- binding
def test_the_native_binding_is_the_one_binding():
    assert isinstance(open_daqp(), NativeDaqp)


def test_a_daqp_whose_structures_are_not_mirrored_is_refused(monkeypatch):
    import uvms_qp.hqp.backends.daqp_binding as binding

    monkeypatch.setattr(binding, "_daqp_version", lambda: "0.0.1")
    with pytest.raises(ImportError, match=re.escape(f"daqp=={SUPPORTED_VERSIONS[-1]}")):
        binding.NativeDaqp()
    with pytest.raises(ImportError, match=re.escape("0.0.1")):
        HierarchySolver("daqp")


@pytest.mark.parametrize("seed", range(12))
def test_warm_started_sequence_is_bit_identical(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 14))
    sizes = tuple(int(v) for v in rng.integers(1, 6, size=int(rng.integers(1, 5))))
    problem = _hierarchy(rng, n, sizes, float(rng.choice([0.05, 0.5, 10.0])))
    pair = _pair(problem)
    m = problem[2].shape[0]
    for k in range(25):
        dA = 0.05 * rng.standard_normal((m, n))
        db = 0.05 * rng.standard_normal(m)
        answers = []
        for binding, (A, bu, bl) in pair:
            if k:  # a drifting problem written in place, as in a control loop
                A += dA
                bl[n:] += db
                bu[n:] = np.where(bu[n:] >= 1e30, 1e30, bl[n:])
                binding.refresh()
            flag = binding.solve()
            answers.append((flag, binding.x.copy(), binding.iterations))
        (f1, x1, i1), (f2, x2, i2) = answers
        assert f1 == f2 and i1 == i2 and np.array_equal(x1, x2)


def test_cold_start_settings_and_new_structure():
    rng = np.random.default_rng(5)
    problem = _hierarchy(rng, 6, (3, 2), 0.4)
    pair = _pair(problem, rho_soft=1e-6)
    (native, _), (model, _) = pair
    assert native.settings["rho_soft"] == 1e-6 and native.settings == model.settings
    for binding, _ in pair:
        binding.solve()
        binding.settings = {"rho_soft": 1e-9, "iter_limit": 500}
        binding.restart(problem[5].copy())  # cold start
    assert native.solve() == model.solve() and np.array_equal(native.x, model.x)
    assert native.settings["iter_limit"] == 500
    # a new structure on the same object keeps the settings
    H, f, A, bu, bl, sense, bp = _hierarchy(rng, 4, (2,), 1.0)
    assert native.setup(H, f, A, bu, bl, sense, bp)[0] >= 0
    assert native.settings["rho_soft"] == 1e-9
    model.setup(H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(), bp)
    assert native.solve() == model.solve() and np.array_equal(native.x, model.x)


def test_failed_setup_keeps_a_usable_object():
    rng = np.random.default_rng(9)
    H, f, A, bu, bl, sense, bp = _hierarchy(rng, 4, (2,), 1.0)
    native = NativeDaqp()
    native.settings = {"rho_soft": 1e-7}
    bad_H = -np.eye(4)  # not positive definite: DAQP refuses the set-up
    flag, _ = native.setup(bad_H, f, A, bu, bl, sense, bp)
    model_flag = daqp.Model().setup(bad_H, f, A.copy(), bu.copy(), bl.copy(), sense.copy(),
                                    break_points=bp)[0]
    assert flag == model_flag < 0
    assert native.settings["rho_soft"] == 1e-7
    assert native.setup(H, f, A, bu, bl, sense, bp)[0] >= 0
    assert native.solve() in (1, 2) and np.all(np.isfinite(native.x))


def test_soft_weights_set_or_written_in_place_match_daqp_model():
    rng = np.random.default_rng(17)
    problem = _hierarchy(rng, 6, (3, 3), 0.4)
    pair = _pair(problem)
    assert NativeDaqp().soft_weight_views() is None  # nothing set up yet
    m = problem[3].shape[0]
    for step in range(6):
        rho = np.where(np.arange(m) < 6, 0.0, 10.0 ** rng.uniform(-9, -6, m))
        dA = rng.standard_normal(problem[2].shape)
        xs = []
        for binding, (A, _, _) in pair:
            A[...] = dA
            if step % 2:  # copied in by a call
                binding.soft_weights(rho)
                binding.refresh()
            else:  # written into the arrays the next refresh takes over
                lower, upper = binding.soft_weight_views()
                lower[:], upper[:] = rho, rho
                binding.refresh()
            xs.append((binding.solve(), binding.x.copy()))
        assert xs[0][0] == xs[1][0]
        np.testing.assert_allclose(xs[0][1], xs[1][1], atol=1e-12)


# --------------------------------------------------------------------------- soft weights
def _rescaled(rng, levels):
    """Rows scaled by 10^U(-1, 1) (sides with them) and weighted by 10^U(-2, 2)."""
    out = []
    for level in levels:
        items = []
        for item in level:
            A, lo = item[0], item[1]
            hi = lo if len(item) == 2 else item[2]
            s = 10.0 ** rng.uniform(-1.0, 1.0, A.shape[0])
            w = 10.0 ** rng.uniform(-2.0, 2.0, A.shape[0])
            items.append(Rows(A * s[:, None], lo * s, hi * s, w))
        out.append(items)
    return out


def test_daqp_equals_the_weighted_optimum_on_scaled_weighted_levels():
    rng = np.random.default_rng(11)
    daqp_solver, cascade = HierarchySolver("daqp"), HierarchySolver("cascade:quadprog")
    unmet = sensitive = 0
    for i in range(300):
        levels, lower, upper, hard = random_mixed_inputs(rng)
        problem = normalize_problem(_rescaled(rng, levels), lower, upper, None, hard)
        got, ref = daqp_solver.solve_problem(problem), cascade.solve_problem(problem)
        if ill_posed(got) and ill_posed(ref):
            sensitive += 1  # both say the priorities do not fix the level to 1e-6: not "ok"
        else:
            assert got.ok and ref.ok, i
        unmet += ref.infeasible_level is not None
        for k, (r, q) in enumerate(zip(got.level_residuals, ref.level_residuals, strict=True)):
            assert abs(r - q) <= 1e-6 * max(1.0, q), (i, k, r, q)
        assert got.hard_violation <= 1e-9
    assert unmet >= 150  # most problems have a level that cannot be met: weights matter
    assert sensitive <= 5  # weights 10^(+-2), rows 10^(+-1): a few levels 1e-9-sensitive


def test_soft_weights_formula():
    """rho_i = rho_soft max_level(w_j |a_j W^-1/2|^2) / w_i; 0 for all-zero levels."""
    rng = np.random.default_rng(2)
    n, sizes = 4, (3, 0, 2, 2)
    W = rng.uniform(0.5, 2.0, n)
    problem = Problem(n, 1, sizes, W)
    rows = rng.standard_normal((sum(sizes), n))
    rows[5:7] = 0.0  # the last level is all zeros (e.g. a task at a singularity)
    problem.A[problem.head:] = rows
    problem.lo[n:], problem.hi[n:] = -1.0, 1.0
    w = rng.uniform(0.1, 10.0, sum(sizes))
    problem.set_weights(w)
    setup = _Setup(problem, {}, open_daqp())
    rho = np.empty(sum(sizes))
    setup.level_weights(1e-8, rho)
    q = w * np.sum(rows * rows / W, axis=1)
    expected = np.concatenate([1e-8 * q[:3].max() / w[:3], 1e-8 * q[3:5].max() / w[3:5],
                               np.zeros(2)])
    np.testing.assert_allclose(rho, expected, rtol=1e-14)
    # the normalised weights rho_i / |a_i W^-1/2|^2 are never below rho_soft
    norm2 = np.sum(rows[:5] * rows[:5] / W, axis=1)
    assert np.all(rho[:5] / norm2 >= 1e-8 * (1 - 1e-12))


class _ModelWithoutSoftWeights(ModelDaqp):
    """``daqp.Model`` as older daqp releases offer it: no ``soft_weights``."""

    def __init__(self):
        super().__init__()

        class Bare:
            def __init__(self, model):
                self._m = model

            def setup(self, *args, **kwargs):
                return self._m.setup(*args, **kwargs)

            def update(self, **kwargs):
                return self._m.update(**kwargs)

            def solve(self):
                return self._m.solve()

            settings = property(lambda self: self._m.settings,
                                lambda self, v: setattr(self._m, "settings", v))

        self._model = Bare(self._model)


def test_a_daqp_without_soft_weights_still_solves():
    """An older daqp binding (no per-row weights) gives the row-normalised compromise; the
    certificate does not take it for the weighted optimum, which the repair then reaches."""
    solver = HierarchySolver("daqp")
    solver.backend.open_binding = _ModelWithoutSoftWeights
    A = np.array([[1.0, 0.0], [10.0, 0.0]])
    b = np.array([0.0, 10.0])
    for _ in range(2):  # set-up, then a warm refresh
        solver.certify, solver.repair = None, False
        result = solver.solve([[Rows.equality(A, b, weights=[1.0, 7.0])]])
        assert result.x[0] == pytest.approx(0.5, abs=1e-6)  # weights 1/|a_i|^2: DAQP's own
        solver.certify, solver.repair = solver.certifier, True
        result = solver.solve([[Rows.equality(A, b, weights=[1.0, 7.0])]])
        assert result.ok and result.info["repaired_from_level"] == 0
        assert result.x[0] == pytest.approx(700.0 / 701.0, abs=1e-9)  # the weighted optimum


# ------------------------------------------------------------------------------ the ladder
def test_rho_soft_ladder_solves_a_recorded_early_stop():
    """A demo-soak tick where DAQP stops early at rho_soft 1e-8 (exit flag 3): the back-end
    walks its ladder, reports the rho_soft that worked, and starts from 1e-8 again next time."""
    problem, _ = load_problem(RHO_LADDER)
    bare = HierarchySolver("daqp", options={"rho_ladder": []}).solve_problem(problem)
    assert not bare.ok and "DAQP exit flag 3" in bare.message
    solver = HierarchySolver("daqp")
    result = solver.solve_problem(problem)
    assert result.ok and result.info["rho_soft"] != 1e-8
    setup = solver.backend._setups[problem]
    assert setup.binding.settings["rho_soft"] == 1e-8  # restored for the next solve
    again = solver.solve_problem(problem)
    assert again.ok and again.info["rho_soft"] == result.info["rho_soft"]


def test_daqp_model_oracle_gives_the_same_answers():
    """The back-end on the daqp.Model oracle: same answers, same ladder as on the C binding."""
    problem, _ = load_problem(RHO_LADDER)
    native = HierarchySolver("daqp").solve_problem(problem)
    fallback = HierarchySolver("daqp")
    fallback.backend.open_binding = ModelDaqp
    got = fallback.solve_problem(problem)
    assert isinstance(fallback.backend._setups[problem].binding, ModelDaqp)
    assert got.info["rho_soft"] == native.info["rho_soft"] != 1e-8  # walked the ladder
    np.testing.assert_allclose(got.x, native.x, atol=1e-12)
    assert fallback.solve_problem(problem).ok  # a second, warm call takes the refresh path


def test_round_off_outside_the_box_is_clipped_exactly():
    """An answer a hair beyond an active bound is accepted and put onto the bound exactly."""
    problem = normalize_problem([[(np.eye(3), [5.0, -5.0, 0.1])]], -np.ones(3), np.ones(3))
    solver = HierarchySolver("daqp")

    class Hair:
        def __init__(self):
            self.inner = open_daqp()

        def __getattr__(self, name):
            return getattr(self.inner, name)

        def solve(self):
            flag = self.inner.solve()
            self.x = self.inner.x.copy()
            self.x[0] += 3e-12  # above the upper bound 1
            return flag

    solver.backend.open_binding = Hair
    result = solver.solve_problem(problem)
    assert result.ok and result.info["rho_soft"] == 1e-8  # accepted at once
    assert result.x[0] == 1.0 and result.x[1] == -1.0 and result.hard_violation == 0.0


def test_the_binding_refuses_sides_it_would_have_to_copy():
    # a copy made at the set-up would be what every later refresh re-reads
    H, f, A, bu, bl, sense, bp = _hierarchy(np.random.default_rng(3), 4, (2,), 1.0)
    sides = np.asfortranarray(np.vstack((bl, bu)))
    with pytest.raises(ValueError, match="blower"):
        NativeDaqp().setup(H, f, A, bu, sides[0], sense, bp)
    with pytest.raises(ValueError, match="A"):
        NativeDaqp().setup(H, f, np.asfortranarray(A), bu, bl, sense, bp)
