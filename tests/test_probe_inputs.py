"""Malformed input at the public boundaries raises the library's own errors, naming the culprit.

Each case here used to escape as a raw Python/numpy error, or to be accepted and give a wrong
answer (``Rows`` built directly with sides of the wrong length solved as "optimal").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import uvms_qp.analytic as analytic
from uvms_qp import Model, load_model, solve_hierarchy
from uvms_qp.errors import (
    ConfigError,
    InputError,
    NonFiniteError,
    ShapeError,
    UnknownFrameError,
    UvmsQpError,
)
from uvms_qp.hqp import HierarchySolver, Rows
from uvms_qp.sim import load_scenario

SOLVERS = ["daqp", "nullspace", "cascade:quadprog"]
BOX = (-np.ones(2), np.ones(2))


@pytest.fixture(scope="module")
def model() -> Model:
    return load_model("bluerov2_heavy_alpha5")


# ---------------------------------------------------------------------------- Rows objects


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


# ------------------------------------------------------------------- solver and options


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


# ----------------------------------------------------------------------------- DAQP options


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


# ------------------------------------------------------------------------------------- model


def test_model_bad_inputs(model: Model) -> None:
    q = model.neutral()
    with pytest.raises(UnknownFrameError):
        model.frame_pose(q, ["tool"])  # type: ignore[arg-type]
    state = model.state(q)
    with pytest.raises(UnknownFrameError):
        state.jacobian(["tool"])  # type: ignore[arg-type]
    with pytest.raises(UnknownFrameError):
        state.arm_jacobian(["tool"])  # type: ignore[arg-type]
    for bad in (-1.0, float("nan"), "x"):
        with pytest.raises(InputError, match="position"):
            model.random_configuration(0, position=bad)  # type: ignore[arg-type]
    with pytest.raises(InputError, match="rng"):
        model.random_configuration("seed")  # type: ignore[arg-type]


def test_from_dh_joint_names_must_be_strings() -> None:
    row = {"a": 1.0, "alpha": 0.0, "d": 0.0, "theta": 0.0}
    with pytest.raises(InputError, match=r"joint_names\[0\]"):
        Model.from_dh([row], vehicle="planar", joint_names=[1])  # type: ignore[list-item]
    with pytest.raises(InputError, match="joint_names"):
        Model.from_dh([row], vehicle="planar", joint_names="j1")


def test_integrate_overflow_is_an_error(model: Model) -> None:
    q = model.neutral()
    with pytest.raises(NonFiniteError, match="overflow"):
        model.integrate(q, np.full(model.nv, 1e154), 1.0)
    # an ordinary step is unaffected
    zeta = np.zeros(model.nv)
    zeta[0] = 0.5
    q1 = model.integrate(q, zeta, 2.0)
    assert np.isfinite(q1).all()
    assert model.state(q1).position("vehicle")[0] == pytest.approx(1.0)


# ---------------------------------------------------------------------------------- scenario


def test_scenario_source_and_encoding(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="scenario"):
        load_scenario(None)  # type: ignore[arg-type]
    path = tmp_path / "latin1.toml"
    path.write_bytes(b"name = '\xe9'\n")
    with pytest.raises(ConfigError, match=r"latin1\.toml.*UTF-8"):
        load_scenario(path)


# ---------------------------------------------------------------------------------- analytic


def test_analytic_sequences() -> None:
    with pytest.raises(InputError, match="tasks"):
        analytic.recursive_task_priority(None)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"tasks\[0\]"):
        analytic.recursive_task_priority([None])  # type: ignore[list-item]
    N = np.array([[1.0, 2.0]])
    with pytest.raises(InputError, match=r"primary\[0\]"):
        analytic.davies_solve(N, ["a"], [1.0])  # type: ignore[list-item]
    # Psi_1 = -N_1^{-1} N_0 Psi_0 = -(1 / 2) * 1
    np.testing.assert_allclose(analytic.davies_solve(N, [0], [1.0]), [1.0, -0.5])
