"""The inputs of the lexicographic solver: one place for the bad input of ``solve_hierarchy`` and
``HierarchySolver`` (rows, sides, box, weights, metric, solver names and options).

Every bad input raises an error of the library whose message names the culprit
(``levels[1][0].A: ...``); numbers are real, and finite numbers lie within the accepted
magnitudes of :mod:`uvms_qp.hqp.validate`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from uvms_qp.controller import Controller
from uvms_qp.errors import (
    BoundsError,
    InputError,
    NonFiniteError,
    ShapeError,
    UnknownSolverError,
    UvmsQpError,
)
from uvms_qp.hqp import HierarchySolver, Rows, available_solvers, normalize_problem, solve_hierarchy
from uvms_qp.hqp.registry import SolverSpec, get_spec
from uvms_qp.hqp.validate import MAX_MAGNITUDE, Validator, _one_by_one
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import PostureTask


# ------------------------------------------------------------------ rows and their items
@pytest.mark.parametrize("A", [[["1", "0"]], [[True, 1.0]], [[1j, 0.0]]])
def test_hierarchy_rows_must_be_real(A):
    with pytest.raises(InputError, match=r"levels\[0\]\[0\]\.A: expected real numbers"):
        solve_hierarchy([[(A, [0.0])]], [-1.0, -1.0], [1.0, 1.0])


SOLVERS = ["daqp", "nullspace", "cascade:quadprog"]


BOX = (-np.ones(2), np.ones(2))


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize(
    ("rows", "error", "culprit"),
    [
        (Rows(np.eye(2), np.array([0.5]), np.array([0.5])), ShapeError, "lower"),
        (Rows(np.eye(2) * np.nan, np.zeros(2), np.zeros(2)), NonFiniteError, ".A"),
        (Rows(np.eye(2), np.zeros(2), np.zeros(2), np.array([np.nan, 1.0])), NonFiniteError,
         "weights"),
        (Rows(np.eye(2), np.zeros(2), np.zeros(2), np.array([-1.0, 1.0])), InputError,
         "weights"),
        (Rows(np.eye(2), np.zeros(2), np.zeros(2), np.array([0.0, 1.0])), InputError,
         "weights"),
        (Rows(np.eye(2), np.zeros(2), np.zeros(2), np.ones(3)), ShapeError, "weights"),
        (Rows(np.eye(2), np.ones(2), np.zeros(2)), InputError, "lower > upper"),
    ],
)
def test_unchecked_rows_are_validated(solver: str, rows: Rows, error: type, culprit: str) -> None:
    with pytest.raises(error, match=r"levels\[0\]\[0\]") as info:
        solve_hierarchy([[rows]], *BOX, solver=solver)
    assert culprit in str(info.value)


def test_bad_rows_error_names_the_rows() -> None:
    bad = Rows(np.eye(2), np.array([0.5]), np.array([0.5]), name="tool")
    with pytest.raises(ShapeError, match=r"levels\[1\]\[0\] \(tool\)\.lower"):
        solve_hierarchy([[(np.eye(2), np.zeros(2))], [bad]], *BOX)


@pytest.mark.parametrize("solver", SOLVERS)
def test_rows_of_lists_solve_like_arrays(solver: str) -> None:
    """A ``Rows`` holding lists is converted, and solves to the same answer as arrays."""
    target = [0.25, -0.5]
    listed = HierarchySolver(solver).solve([[Rows([[1.0, 0.0], [0.0, 1.0]], target, target)]],
                                           *BOX)
    assert listed.ok
    np.testing.assert_allclose(listed.x, target, atol=1e-7)


def test_a_level_given_as_one_bare_item_is_the_level_of_that_item() -> None:
    """``[(A, b), (A, lo, hi), Rows]`` as levels equals ``[[(A, b)], [(A, lo, hi)], [Rows]]``."""
    rng = np.random.default_rng(4)
    A0, A1, A2 = (rng.standard_normal((m, 3)) for m in (2, 1, 2))
    b0, lo1, hi1 = rng.standard_normal(2), np.array([-0.1]), np.array([np.inf])
    rows2 = Rows(A2, np.zeros(2), np.zeros(2), np.array([2.0, 3.0]))
    bare = normalize_problem([(A0, b0), (A1, lo1, hi1), rows2], -np.ones(3), np.ones(3))
    listed = normalize_problem([[(A0, b0)], [(A1, lo1, hi1)], [rows2]], -np.ones(3), np.ones(3))
    assert bare.sizes == listed.sizes == (2, 1, 2)
    np.testing.assert_array_equal(bare.A, listed.A)
    np.testing.assert_array_equal(bare.sides, listed.sides)
    np.testing.assert_array_equal(bare.w, listed.w)
    hard = (np.ones((1, 3)), [-1.0], [1.0])  # the hard rows take the same forms
    np.testing.assert_array_equal(normalize_problem([(A0, b0)], hard=hard).A,
                                  normalize_problem([(A0, b0)], hard=[hard]).A)


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
def test_weighted_rows_are_still_used(solver: str) -> None:
    """Valid weights pass the checks and still decide the compromise inside a level.

    Rows ``x0 = 1`` (weight 4) and ``x0 = 0`` (weight 1): the weighted least-squares optimum is
    ``x0 = 4 / 5``.
    """
    A = np.array([[1.0, 0.0], [1.0, 0.0]])
    rows = Rows(A, np.array([1.0, 0.0]), np.array([1.0, 0.0]), np.array([4.0, 1.0]))
    result = HierarchySolver(solver).solve([[rows]], *BOX)
    assert result.ok
    assert result.x[0] == pytest.approx(0.8, abs=1e-6)


def test_zero_column_rows_are_a_shape_error() -> None:
    for solver in SOLVERS:
        with pytest.raises(ShapeError, match="0 columns"):
            solve_hierarchy([[(np.zeros((2, 0)), np.zeros(2))]], solver=solver)


# ------------------------------------------------------------------------ solver and options
@pytest.mark.parametrize(
    ("kwargs", "culprit"),
    [
        ({"solver": ["daqp"]}, "solver"),
        ({"solver": None}, "solver"),
        ({"options": 3}, "options"),
        ({"options": {"bogus": 1}}, "bogus"),
        ({"solver": "nullspace", "options": {"bogus": 1}}, "bogus"),
        ({"solver": "nullspace", "options": {"rcond": "x"}}, "rcond"),
        ({"options": {"rho_soft": "x"}}, "rho_soft"),
        ({"options": {"level_tol": float("nan")}}, "level_tol"),
        ({"options": {"hard_tol": -1.0}}, "hard_tol"),
        ({"solver": "cascade:quadprog", "options": {1: 2}}, "options"),
    ],
)
def test_bad_solver_or_options(kwargs: dict[str, Any], culprit: str) -> None:
    with pytest.raises(UvmsQpError, match=culprit):
        solve_hierarchy([[(np.eye(2), np.zeros(2))]], *BOX, **kwargs)


def test_known_options_are_accepted() -> None:
    for solver, options in [("daqp", {"rho_soft": 1e-8, "time_limit": 1.0, "level_tol": 1e-6}),
                            ("nullspace", {"rcond": 1e-12}),
                            ("cascade:quadprog", {"rank_tol": 1e-10})]:
        result = HierarchySolver(solver, options=options).solve(
            [[(np.eye(2), [0.5, 0.5])]], *BOX)
        np.testing.assert_allclose(result.x, [0.5, 0.5], atol=1e-7)


@pytest.mark.parametrize(
    ("options", "culprit"),
    [
        (3, "options"),
        ({"bogus": 1.0}, "bogus"),
        ({"level_tol": "x"}, "level_tol"),
        ({"hard_tol": float("nan")}, "hard_tol"),
        ({"hard_tol": -1.0}, "hard_tol"),
        ({"level_tol": 0.0}, "level_tol"),
        ({"rho_ladder": "x"}, "rho_ladder"),
        ({"rho_ladder": [-1.0]}, "rho_ladder"),
        ({"primal_tol": "x"}, "primal_tol"),
    ],
)
def test_daqp_rejects_bad_options(options: Any, culprit: str) -> None:
    with pytest.raises(InputError, match=culprit):
        HierarchySolver("daqp", options=options)


# ---- unknown solver names: the list once, the likely intended name
def _count_lists(message: str) -> int:
    return message.count("known solvers:")


def test_bare_backend_name_suggests_the_cascade():
    model = load_model("bluerov2_heavy_alpha5")
    with pytest.raises(UnknownSolverError) as info:
        Controller(model, Stack(levels=[Level(PostureTask())]), solver="osqp")
    message = str(info.value)
    assert _count_lists(message) == 1 and message.count("cascade:osqp") == 2
    assert "did you mean 'cascade:osqp'?" in message
    with pytest.raises(UnknownSolverError) as info:
        solve_hierarchy([[(np.eye(2), [1.0, 1.0])]], solver="quadprog")
    assert _count_lists(str(info.value)) == 1
    assert "did you mean 'cascade:quadprog'?" in str(info.value)


def test_unknown_name_lists_the_solvers_once():
    with pytest.raises(UnknownSolverError) as info:
        solve_hierarchy([[(np.eye(2), [1.0, 1.0])]], solver="foo")
    message = str(info.value)
    assert _count_lists(message) == 1
    assert message.count("nullspace") == 1 and "did you mean" not in message


# ------------------------------------------------------------------ hierarchies
@pytest.mark.parametrize(
    ("levels", "kwargs", "error", "match"),
    [
        ([[(np.eye(2), [1.0])]], {}, ShapeError, r"levels\[0\]\[0\]\.b"),
        ([[(np.eye(2), [1.0, 1.0])], [(np.eye(3), [1.0, 1.0, 1.0])]], {}, ShapeError,
         r"levels\[1\]\[0\]\.A: expected 2 columns"),
        ([[(np.array([[1.0, np.nan]]), [1.0])]], {}, NonFiniteError, "NaN"),
        ([[(np.eye(2), [1.0, np.inf])]], {}, NonFiniteError, "inf"),
        ([[(np.eye(2), [2.0, 0.0], [1.0, 1.0])]], {}, BoundsError, "lower > upper"),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [1.0, 0.0], "upper": [0.0, 1.0]}, BoundsError,
         "bounds"),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [0.0]}, ShapeError, "lower"),
        ([[(np.eye(2), [1.0, 1.0])]], {"weights": [1.0, -1.0]}, InputError, "weights"),
        ([[(np.eye(2), [1.0, 1.0])]], {"weights": [1.0, np.nan]}, NonFiniteError, "weights"),
        ([["not rows"]], {}, InputError, r"levels\[0\]\[0\]"),
        ("nope", {}, InputError, "levels"),
        ([[(np.array([[1.0, np.inf]]), [1.0])]], {}, NonFiniteError, r"levels\[0\]\[0\]\.A"),
        ([[(np.eye(2), [1.0, -np.inf])]], {}, NonFiniteError, r"levels\[0\]\[0\]\.b"),
        ([[(np.eye(2), [np.nan, 0.0], [1.0, 1.0])]], {}, NonFiniteError, "lower"),
        ([[(np.eye(2), [np.inf, 0.0], [np.inf, 1.0])]], {}, InputError, "lower side is"),
        ([[(np.eye(2), [0.0, 0.0], [-np.inf, 1.0])]], {}, InputError, r"levels\[0\]\[0\]"),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [0.0, np.nan]}, NonFiniteError, "lower"),
        ([[(np.eye(2), [1.0, 1.0])]], {"lower": [np.inf, 0.0]}, InputError, "lower bound"),
        ([[(np.eye(2), [1.0, 1.0])]], {"upper": [-np.inf, 0.0]}, InputError, "upper bound"),
        ([[(np.eye(2), [1.0, 1.0])]], {"hard": [(np.ones((1, 2)), [1.0], [0.0])]}, BoundsError,
         "hard"),
        ([[(np.eye(2), [1.0, 1.0])]], {"hard": [(np.ones((1, 3)), [1.0])]}, ShapeError, "hard"),
        ([[(np.eye(2), [1.0, 1.0])]], {"hard": 5}, InputError, "hard: expected a list of rows"),
        ([[(np.eye(2), [1.0, 1.0])]], {"hard": [Rows(np.ones((1, 2)), [0.0], [1.0], [np.nan])]},
         NonFiniteError, r"hard\[0\]\.weights"),
        ([[(np.eye(2), [1.0, 1.0])]], {"weights": [1.0, 0.0]}, InputError, "weights"),
        ([[Rows(np.eye(2), np.ones(2), np.ones(2), np.array([1.0, -1.0]), "t")]], {},
         InputError, r"levels\[0\]\[0\] \(t\)\.weights"),
        # a level given as one bare item, not a list of items
        ([(np.array([[1.0, np.inf]]), [1.0])], {}, NonFiniteError, r"levels\[0\]\[0\]\.A"),
        ([(np.eye(2), [1.0, 1e300])], {}, InputError, r"levels\[0\]\[0\]\.b"),
        ([(np.eye(2), [0.0, 0.0], [-1.0, 1.0])], {}, BoundsError, r"levels\[0\]\[0\]"),
        ([Rows(np.eye(2), np.ones(2), np.ones(2), np.array([1.0, -1.0]), "t")], {},
         InputError, r"levels\[0\]\[0\] \(t\)\.weights"),
    ],
)
@pytest.mark.parametrize("reuse", [False, True])
def test_bad_input(levels, kwargs, error, match, reuse):
    """Every bad input names its culprit, also on a solver whose buffers hold a good problem."""
    if "weights" in kwargs:  # the metric is checked against the problem's size at solve time
        with pytest.raises(error, match=match):
            solve_hierarchy(levels, **kwargs)
        return
    solver = HierarchySolver("daqp")
    if reuse:
        assert solver.solve([[(np.eye(2), [0.5, 0.5])]], -np.ones(2), np.ones(2)).ok
    with pytest.raises(error, match=match):
        solver.solve(levels, **kwargs)
    assert solver.solve([[(np.eye(2), [0.5, 0.5])]], -np.ones(2), np.ones(2)).ok


def test_nullspace_refuses_inequality_levels():
    with pytest.raises(InputError, match=r"levels\[1\].*equality rows only"):
        solve_hierarchy([[(np.eye(2), [1.0, 1.0])], [(np.eye(2), [0.0, 0.0], [1.0, 1.0])]],
                        solver="nullspace")


def test_unknown_solver_lists_installed():
    with pytest.raises(UnknownSolverError) as info:
        solve_hierarchy([[(np.eye(2), [1.0, 1.0])]], solver="gurobi")
    assert "daqp" in str(info.value) and "nullspace" in str(info.value)
    assert isinstance(info.value, LookupError)


def test_unknown_cascade_names_the_choices():
    with pytest.raises(UnknownSolverError, match="cascades exist for the qpsolvers back-ends"):
        HierarchySolver("cascade:cplex")


def test_uninstalled_solver_says_what_to_install(monkeypatch):
    import uvms_qp.hqp.registry as registry

    ghost = SolverSpec(name="cascade:ghost", kind="cascade", modules=("no_such_module_x",),
                       pip="qpsolvers ghostqp")
    monkeypatch.setattr(registry, "_BY_NAME", {**registry._BY_NAME, "cascade:ghost": ghost})
    with pytest.raises(UnknownSolverError, match=r"pip install qpsolvers ghostqp") as info:
        get_spec("cascade:ghost")
    assert "daqp" in str(info.value)


# ------------------------------------------------------------------- accepted magnitudes
_BOX3 = {"lower": -np.ones(3), "upper": np.ones(3)}


_WIDE = 1e150 * np.random.default_rng(0).standard_normal((4, 6))


# (id, levels, keyword arguments, the culprit named by the message)
OUT_OF_RANGE = [
    ("row entry 1e155", [[(np.array([[1e155, 1.0, 0.0]]), [1.0])], [(np.eye(3), [1.0, 2.0, 3.0])]],
     _BOX3, r"levels\[0\]\[0\]\.A: entry 1e\+155 at index \(0, 0\)"),
    ("rows of 1e150 scale", [[(_WIDE, np.ones(4))], [(np.eye(6), np.zeros(6))]],
     {"lower": -np.ones(6), "upper": np.ones(6)}, r"levels\[0\]\[0\]\.A: entry "),
    ("row 1e160 meetable by 1e-160", [[(np.array([[1e160]]), [1.0])]], {},
     r"levels\[0\]\[0\]\.A: entry 1e\+160 at index \(0, 0\)"),
    ("sides of +-1.7e308", [[(np.array([[1.0, 2.0]]), [-1.7e308], [1.7e308])],
                            [(np.eye(2), [1.7e308, -1.7e308])]],
     {"lower": -np.ones(2), "upper": np.ones(2)}, r"levels\[0\]\[0\]\.lower: entry -1\.7e\+308"),
    ("target 1e150", [[(np.eye(2), [1e150, 0.0])]], {}, r"levels\[0\]\[0\]\.b: entry 1e\+150 at"),
    ("upper side 1e300 of a named Rows",
     [[Rows(np.eye(2), np.zeros(2), np.array([1e300, 1.0]), name="tool")]], {},
     r"levels\[0\]\[0\] \(tool\)\.upper: entry 1e\+300 at index 0"),
    ("box bound -1e300", [[(np.eye(2), [0.5, 0.5])]], {"lower": [-1e300, -1.0]},
     r"^lower: entry -1e\+300 at index 0"),
    ("hard row 1e200", [[(np.eye(2), [0.5, 0.5])]], {"hard": [(np.array([[1e200, 1.0]]), [0.0],
                                                                [1.0])]},
     r"hard\[0\]\.A: entry 1e\+200"),
    ("row weight 1e-300", [[Rows(np.eye(2), np.zeros(2), np.zeros(2), np.array([1e-300, 1.0]))]],
     {}, r"levels\[0\]\[0\]\.weights: entry 1e-300 at index 0 .*within \[1e-15, 1e\+15\]"),
    ("metric 1e300", [[(np.eye(2), [0.5, 0.5])]], {"weights": [1e300, 1.0]},
     r"^weights: entry 1e\+300 at index 0"),
]


@pytest.mark.parametrize("solver", available_solvers())
@pytest.mark.parametrize(("levels", "kwargs", "culprit"), [c[1:] for c in OUT_OF_RANGE],
                         ids=[c[0] for c in OUT_OF_RANGE])
def test_numbers_beyond_the_accepted_magnitude_are_refused_naming_them(levels, kwargs, culprit,
                                                                        solver, capfd):
    """Finite but extreme numbers made the back-ends' linear algebra overflow (LinAlgError,
    LAPACK text, or no return at all) or were read as infinite: one typed line instead."""
    with pytest.raises(InputError, match=culprit) as info:
        solve_hierarchy(levels, solver=solver, **kwargs)
    message = str(info.value)
    assert "\n" not in message and "out of range" in message and "scale" in message
    assert capfd.readouterr() == ("", "")


@pytest.mark.parametrize("solver", available_solvers())
def test_numbers_within_the_accepted_magnitude_are_solved_and_measured(solver, capfd):
    """At the limit every back-end answers quietly with a finite x and a status; a reduction that
    only looks out of range (many entries near the limit) is not mistaken for bad input."""
    big = MAX_MAGNITUDE
    A = np.full((4, 4), big)  # vdot(A, A) = 16 * MAX**2: the fast check's false alarm
    cases = [
        ([[(A, np.full(4, big))]], {}),
        ([[(np.eye(3), [big, -big, 1.0])], [(np.ones((1, 3)), [0.0])]], _BOX3),
        ([[(np.array([[1.0, 1.0]]), [-big], [big])]], {"lower": [-big, -1.0], "upper": [big, 1.0]}),
    ]
    for levels, kwargs in cases:
        if solver == "nullspace" and len(levels[0][0]) == 3:
            continue  # equality levels only
        result = solve_hierarchy(levels, solver=solver, **kwargs)
        assert np.all(np.isfinite(result.x)), (solver, result.summary())
    assert capfd.readouterr() == ("", "")


@pytest.mark.parametrize("solver", available_solvers())
def test_tiny_rows_are_accepted(solver):
    """Rows of 1e-301 (the null-space solver used to raise LinAlgError on them) are legal: the
    level is met within its tolerance by x = 0 or exactly by the pseudoinverse."""
    result = solve_hierarchy([[(1e-301 * np.array([[1.0, 2.0]]), [1e-301])]], solver=solver)
    assert result.ok and np.all(np.isfinite(result.x))


# ------------------------------------------------------------------------- cascade options
@pytest.mark.parametrize(
    ("solver", "options", "message"),
    [
        ("cascade:quadprog", {"bogus": 1}, "unknown setting 'bogus' for solver "
                                           "'cascade:quadprog'; known: rank_tol"),
        ("cascade:highs", {"time_limt": 1.0}, "unknown setting 'time_limt' for solver "
                                              "'cascade:highs' (did you mean 'time_limit'?)"),
        ("cascade:osqp", {"eps_abss": 1e-6}, "did you mean 'eps_abs'"),
        ("cascade:proxqp", {"max_iters": 10}, "did you mean 'max_iter'"),
        ("cascade:quadprog", {"rank_tol": "x"}, "options['rank_tol']: expected a number"),
        ("cascade:quadprog", {"reg": None}, "options['reg']: expected a number"),
        ("cascade:quadprog", {"prox_steps": 1.5}, "options['prox_steps']: expected a "
                                                  "non-negative integer"),
        ("cascade:quadprog", {"mult_tol": -1.0}, "options['mult_tol']: expected a positive"),
    ],
)
def test_cascade_options_are_known_settings_with_valid_values(solver, options, message):
    """Unknown settings were handed to qpsolvers and ignored (or made every QP fail)."""
    if solver not in available_solvers():
        pytest.skip(f"{solver} not installed")
    with pytest.raises(InputError) as info:
        HierarchySolver(solver, options=options)
    assert message in str(info.value)


def test_known_cascade_settings_reach_the_back_end():
    for solver, options in [("cascade:osqp", {"eps_abs": 1e-9, "max_iter": 50_000}),
                            ("cascade:highs", {"time_limit": 2.0}),
                            ("cascade:proxqp", {"eps_abs": 1e-9})]:
        if solver in available_solvers():
            result = HierarchySolver(solver, options=options).solve(
                [[(np.eye(2), [0.5, 0.5])]], -np.ones(2), np.ones(2))
            np.testing.assert_allclose(result.x, [0.5, 0.5], atol=1e-6)


def _random_input(rng: np.random.Generator) -> tuple[Any, Any, Any, Any, Any]:
    """Levels, lower, upper, hard and n of a random user problem, often with one fault."""
    n = int(rng.integers(1, 4))

    def item(m: int, cols: int) -> Any:
        A = rng.standard_normal((m, cols))
        b = rng.standard_normal(m)
        kind = rng.integers(3)
        if kind == 0:
            return (A, b)
        if kind == 1:
            return (A, b - 1.0, b + 1.0)
        w = rng.uniform(0.5, 2.0, m) if rng.random() < 0.5 else None
        return Rows(A, b - 0.5, b + 0.5, w)

    def group(cols: int) -> Any:
        items = [item(int(rng.integers(0, 3)), cols) for _ in range(int(rng.integers(1, 3)))]
        return items[0] if len(items) == 1 and rng.random() < 0.5 else items

    levels = [group(n) for _ in range(int(rng.integers(0, 4)))]
    hard = group(n) if rng.random() < 0.3 else None
    lower = -np.ones(n) if rng.random() < 0.7 else None
    upper = np.ones(n) if rng.random() < 0.7 else None
    given = None if rng.random() < 0.7 else int(rng.integers(1, 4))
    fault = rng.integers(8)
    targets = [lv for lv in levels if isinstance(lv, list) and lv]
    if fault == 1 and targets:  # a bad number in a listed level's first item
        first = targets[0][0]
        A = first[0] if isinstance(first, tuple) else first.A
        if A.size:
            A.flat[0] = rng.choice([np.nan, np.inf, 1e20])
    elif fault == 2 and levels:  # a level with another column count
        levels[-1] = (rng.standard_normal((1, n + 1)), np.zeros(1))
    elif fault == 3 and levels:  # lower side above upper side
        levels[0] = (rng.standard_normal((1, n)), np.ones(1), -np.ones(1))
    elif fault == 4 and levels:  # bad weights
        levels[0] = Rows(rng.standard_normal((2, n)), -np.ones(2), np.ones(2),
                         np.array([1.0, rng.choice([-1.0, np.nan, 1e20])]))
    elif fault == 5:  # weighted hard rows, with a bad weight or not
        hard = Rows(rng.standard_normal((1, n)), -np.ones(1), np.ones(1),
                    np.array([rng.choice([1.0, -1.0, np.nan])]))
    elif fault == 6 and lower is not None:
        lower[0] = rng.choice([np.nan, np.inf, 1e20])
    return levels, lower, upper, hard, given


def test_the_validator_agrees_with_the_item_by_item_check_on_random_input() -> None:
    """Whatever path a problem takes, it is the one the item-by-item check describes.

    The fast parse must give the same stacked rows, sides, weights and structure as
    :func:`_one_by_one` (the slow check that names culprits), and reject what it rejects with
    the same error.
    """
    rng = np.random.default_rng(11)
    outcomes = {"solved": 0, "refused": 0}
    for _ in range(600):
        levels, lower, upper, hard, given = _random_input(rng)
        try:
            parsed, lo, hi = _one_by_one(levels, lower, upper, hard, given)
            expected: Any = None
        except UvmsQpError as exc:
            expected = exc
        try:
            problem = Validator()(levels, lower, upper, hard, None, given)
        except UvmsQpError as exc:
            assert expected is not None, f"refused: {exc}"
            assert (type(exc), str(exc)) == (type(expected), str(expected))
            outcomes["refused"] += 1
            continue
        if expected is not None:  # only the stacked check sees lo > hi across the box
            raise AssertionError(f"accepted what the item-by-item check refuses: {expected}")
        As, los, his, ws, n_hard, sizes = parsed
        n = lo.shape[0]
        assert (problem.n, problem.sizes) == (n, tuple(sizes))
        assert problem.mh == sum(A.shape[0] for A in As[:n_hard])
        rows = np.concatenate([np.zeros((0, n)), *As])
        np.testing.assert_array_equal(problem.A[n:], rows)
        np.testing.assert_array_equal(problem.sides, np.vstack((
            np.concatenate((lo, *los)), np.concatenate((hi, *his)))))
        w = [np.ones(A.shape[0]) if v is None else v for A, v in zip(As[n_hard:], ws[n_hard:],
                                                                       strict=True)]
        np.testing.assert_array_equal(problem.w, np.concatenate([np.zeros(0), *w]))
        outcomes["solved"] += 1
    assert min(outcomes.values()) > 100, outcomes


def test_a_problem_refuses_buffers_a_back_end_cannot_read_in_place():
    from uvms_qp.hqp.problem import Problem

    with pytest.raises(InputError, match="sides"):
        Problem(2, 0, (1,), sides=np.asfortranarray(np.zeros((2, 3))))
    with pytest.raises(InputError, match="A: expected a C-contiguous"):
        Problem(2, 0, (1,), A=np.asfortranarray(np.zeros((3, 2))))
