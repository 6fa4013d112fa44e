"""The solver registry: ordered data with capability flags and per-back-end tolerances.

Availability is checked with :func:`importlib.util.find_spec`, without importing the back-end.
Adding a back-end is a data change here plus (for a new kind) one module in ``backends/``; see
``docs/solver.md``, "Adding a back-end".
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from ..errors import UnknownSolverError
from .tolerances import HARD_TOL, LEVEL_TOL


@dataclass(frozen=True)
class SolverSpec:
    """Description of one solver choice.

    Attributes:
        name: Public name (``"daqp"``, ``"nullspace"``, ``"cascade:<qpsolvers name>"``).
        kind: Implementation family: ``"daqp"``, ``"nullspace"`` or ``"cascade"``.
        modules: Python modules that must be importable for the solver to be available.
        pip: pip package(s) that provide the modules.
        inequality_levels: Can solve levels with inequality rows.
        bounds: Enforces the hard box and hard rows (otherwise only checks them).
        exact: Active-set / direct method: results agree to round-off.
        agreement_tol: Maximum difference ``|x - x_nullspace|_inf`` on well-posed equality
            problems (relative to ``max(1, |x|_inf)``), as tested.
        level_tol: Relative tolerance deciding that a level is met.
        hard_tol: Relative tolerance on the hard box and rows before a result is rejected.
        freeze_margin: Absolute margin added to frozen inequality slacks of higher levels.
        settings: Keyword settings passed to the back-end (qpsolvers or DAQP).
        sparse: The back-end takes sparse (CSC) matrices only; the cascade converts for it.
        reg: Relative Tikhonov term ``rho`` a cascade adds to each level's Hessian (0 for
            back-ends that accept positive semi-definite Hessians).
        retries: Alternative back-end settings tried, in order, when a QP fails (e.g. looser
            tolerances for an interior-point method that calls a thin feasible set infeasible).
        certify: Every QP answer is sharpened on its active set and accepted only with a KKT
            certificate (:mod:`uvms_qp.hqp.kkt`); an answer that cannot be
            certified fails the QP (retries, then a truthful non-ok status). For back-ends whose
            own "solved" is not accurate enough to trust.
        prox_steps: Most proximal refinements ``min f + rho/2 |y - y_j|^2`` after the first QP
            of a level, each shrinking the bias of ``rho`` along a direction of curvature
            ``sigma^2`` by ``rho / (rho + sigma^2)``; they stop once the answer no longer moves
            or converges slowly, and the answer's active set is then solved exactly on the QP
            without ``rho`` (:func:`uvms_qp.hqp.kkt.certified_point`).
        time_setting: Name of the back-end's own time-limit setting [s] (empty: none); a cascade
            hands it the time left under its cap.
    """

    name: str
    kind: str
    modules: tuple[str, ...]
    pip: str
    inequality_levels: bool = True
    bounds: bool = True
    exact: bool = True
    agreement_tol: float = 1e-8
    level_tol: float = LEVEL_TOL
    hard_tol: float = HARD_TOL
    freeze_margin: float = 1e-9
    settings: MappingProxyType[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    sparse: bool = False
    reg: float = 0.0
    prox_steps: int = 0
    certify: bool = False
    retries: tuple[MappingProxyType[str, Any], ...] = ()
    time_setting: str = ""

    @property
    def qp_name(self) -> str:
        """Name of the qpsolvers back-end for a cascade (empty otherwise)."""
        return self.name.split(":", 1)[1] if self.kind == "cascade" else ""

    @property
    def available(self) -> bool:
        """True when every required module can be imported (checked without importing)."""
        return all(importlib.util.find_spec(m) is not None for m in self.modules)


def _cascade(name: str, module: str, pip: str, *, exact: bool, agreement_tol: float,
             freeze_margin: float, sparse: bool = False, reg: float = 0.0,
             prox_steps: int = 0, retries: tuple[dict[str, Any], ...] = (),
             certify: bool = False, time_setting: str = "", **settings: Any) -> SolverSpec:
    return SolverSpec(
        name=f"cascade:{name}",
        kind="cascade",
        modules=("qpsolvers", module),
        pip=f"qpsolvers {pip}",
        exact=exact,
        agreement_tol=agreement_tol,
        freeze_margin=freeze_margin,
        settings=MappingProxyType({"verbose": False, **settings}),
        sparse=sparse,
        reg=reg,
        prox_steps=prox_steps,
        certify=certify,
        retries=tuple(MappingProxyType(r) for r in retries),
        time_setting=time_setting,
    )


#: Every solver uvms-qp knows, in order of preference.
SOLVERS: tuple[SolverSpec, ...] = (
    SolverSpec(
        name="daqp",
        kind="daqp",
        modules=("daqp",),
        pip="daqp",
        exact=False,  # the soft-row regularisation rho_soft leaves errors of about 1e-9..1e-7
        agreement_tol=1e-6,
        settings=MappingProxyType({"rho_soft": 1e-8, "primal_tol": 1e-10,
                                   "rho_ladder": (1e-10, 1e-6, 1e-9, 1e-7, 1e-11)}),
    ),
    SolverSpec(
        name="nullspace",
        kind="nullspace",
        modules=("numpy",),
        pip="numpy",
        inequality_levels=False,
        bounds=False,
        agreement_tol=1e-10,
    ),
    # quadprog needs a positive definite Hessian: regularise, refine proximally while that
    # converges, then solve the active set of the answer exactly on the unregularised QP
    _cascade("quadprog", "quadprog", "quadprog", exact=True, agreement_tol=1e-8,
             freeze_margin=1e-10, reg=1e-7, prox_steps=4),
    _cascade("daqp", "daqp", "daqp", exact=True, agreement_tol=1e-8, freeze_margin=1e-10,
             reg=1e-7, prox_steps=4, time_setting="time_limit", primal_tol=1e-10, eps_prox=0.0),
    # inexact back-ends (interior-point, ADMM): every answer is sharpened on its active set and
    # kept only with a KKT certificate, so frozen slacks need a round-off margin only.
    # ProxQP's max_iter counts outer (proximal) iterations, each running up to 1500 inner ones:
    # solved QPs of the test suite need at most 17, while a badly scaled level (a target 1e6 m
    # away) ran 10 000 outer / 7e6 inner iterations (20 s per QP). 50 outer iterations bound
    # one QP to about 0.15 s on 10 variables; a capped QP is a failed QP (exact rescue, then a
    # truthful backend_error), never an optimum.
    _cascade("proxqp", "proxsuite", "proxsuite", exact=False, agreement_tol=1e-6,
             freeze_margin=1e-10, certify=True, eps_abs=1e-10, eps_rel=0.0, max_iter=50,
             retries=({"primal_infeasibility_solving": True},
                      {"eps_abs": 1e-8, "primal_infeasibility_solving": True},
                      {"eps_abs": 1e-7, "primal_infeasibility_solving": True})),
    _cascade("piqp", "piqp", "piqp", exact=False, agreement_tol=1e-6, freeze_margin=1e-10,
             certify=True, eps_abs=1e-10, eps_rel=1e-12,
             retries=({"eps_abs": 1e-9}, {"eps_abs": 1e-8})),
    _cascade("clarabel", "clarabel", "clarabel", exact=False, agreement_tol=1e-6,
             freeze_margin=1e-10, sparse=True, certify=True, time_setting="time_limit",
             tol_gap_abs=1e-10, tol_gap_rel=1e-10,
             tol_feas=1e-10),
    # HiGHS and OSQP stop at tolerances their own "solved" does not guarantee (110 and 233 of
    # 1000 failures before certification); time_limit [s] bounds one HiGHS QP (an exhausted
    # limit is rescued like any failed QP)
    _cascade("highs", "highspy", "highspy", exact=False, agreement_tol=1e-6, freeze_margin=1e-10,
             sparse=True, certify=True, time_setting="time_limit", qp_regularization_value=1e-11,
             primal_feasibility_tolerance=1e-10, dual_feasibility_tolerance=1e-10,
             time_limit=1.0, qp_iteration_limit=10_000),
    _cascade("osqp", "osqp", "osqp", exact=False, agreement_tol=1e-6, freeze_margin=1e-10,
             sparse=True, certify=True, time_setting="time_limit",
             eps_abs=1e-8, eps_rel=1e-8, max_iter=20_000,
             polishing=False),  # the certificate sharpens instead (and OSQP stays quiet)
)

_BY_NAME = {spec.name: spec for spec in SOLVERS}


def available_solvers() -> list[str]:
    """Names of the solvers whose back-ends are installed, in order of preference."""
    return [spec.name for spec in SOLVERS if spec.available]


def get_spec(name: str) -> SolverSpec:
    """Return the spec of an installed solver.

    Raises:
        UnknownSolverError: the name is unknown, or its back-end is not installed (the message
            lists the installed solvers and the pip package to install).
    """
    spec = _BY_NAME.get(name) if isinstance(name, str) else None
    if spec is None:
        raise UnknownSolverError(name, available_solvers(), _unknown_hint(name))
    if not spec.available:
        raise UnknownSolverError(
            name, available_solvers(), f"{name} is not installed; install it with "
            f"`pip install {spec.pip}`")
    return spec


def _unknown_hint(name: object) -> str:
    """What to add to the list of installed solvers when ``name`` is not a solver at all.

    The installed solvers are listed by the error itself; the hint only adds what that list
    does not say: the intended cascade for a bare qpsolvers name, the back-ends a cascade can
    use, and the known solvers whose back-end is not installed.
    """
    cascades = {s.qp_name: s for s in SOLVERS if s.kind == "cascade"}
    if isinstance(name, str) and name in cascades:
        return f"did you mean 'cascade:{name}'?"
    if isinstance(name, str) and name.startswith("cascade:"):
        return "cascades exist for the qpsolvers back-ends " + ", ".join(cascades)
    missing = [s.name for s in SOLVERS if not s.available]
    return "also known but not installed: " + ", ".join(missing) if missing else ""
