"""One DAQP hierarchical model set up on the buffers of a :class:`~uvms_qp.hqp.workspace.Workspace`.

The layout every ``"daqp"`` solve in the library uses (the back-end's general path and the
controller's in-place path alike):

* ``H = diag(W)``, ``f = 0``: the final regularisation is exactly ``min x' W x``;
* DAQP's simple bounds are the box, its general rows ``ws.A[n:]`` (hard rows, then levels), its
  sides DAQP's clamped copies ``ws.bl`` / ``ws.bu``;
* break points: the hard group (box and hard rows), then one group per level; hard equality rows
  start active and immutable;
* per-row soft weights (:mod:`uvms_qp.hqp.daqp_weights`), so every level minimises its weighted
  violation; with direct calls they are written straight into DAQP's arrays before each update.

The model comes from :func:`new_daqp_model` (direct C calls of
:class:`~uvms_qp.hqp.daqp_native.NativeDaqp` where available, else ``daqp.Model``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import FloatArray
from .daqp_native import NativeDaqp, native_available
from .daqp_weights import SoftWeights, soft_weights_supported
from .workspace import Workspace


def new_daqp_model() -> Any:
    """A DAQP model: :class:`NativeDaqp` when it is available, else ``daqp.Model``."""
    if native_available():
        return NativeDaqp()
    import daqp

    return daqp.Model()


class HierarchyModel:
    """A DAQP model set up for ``ws`` (see the module docstring).

    Args:
        ws: The workspace whose buffers DAQP reads (kept: rows and sides are refilled in place).
        W: Diagonal metric (n,), positive.
        hard_eq: Which hard rows are equalities (``ws.mh``,) bool.
        settings: DAQP settings applied after the set-up (``rho_soft``, ``primal_tol``, ...).

    Attributes:
        flag: DAQP's set-up exit flag (negative: the set-up failed and nothing else may be
            called).
        setup_time: DAQP's set-up time [s].
        model: The DAQP model.
        rho_soft: The settings' ``rho_soft``.
    """

    def __init__(self, ws: Workspace, W: FloatArray, hard_eq: np.ndarray,
                 settings: dict[str, Any]) -> None:
        self.ws = ws
        n = ws.n
        self._sense0 = np.zeros(ws.M, dtype=np.intc)  # the cold-start working set
        self._sense0[n: ws.head][hard_eq] = 5  # hard equality rows: active and immutable
        bp = np.unique(np.cumsum((ws.head, *ws.sizes))).astype(np.intc)
        H, f = np.diag(W), np.zeros(n)
        self._held = (H, f, bp)  # arrays handed to DAQP stay alive with the model
        self.model = model = new_daqp_model()
        self.native = isinstance(model, NativeDaqp)
        flag, setup_time = model.setup(H, f, ws.daqp_A, ws.bu, ws.bl, self._sense0.copy(),
                                       break_points=bp)
        self.flag, self.setup_time = int(flag), float(setup_time)
        self.rho_soft = float(settings.get("rho_soft", 1e-8))
        self._rows = ws.A[ws.head:]
        self._soft = SoftWeights(ws.head, ws.sizes, W)
        self._soft_ok = False
        self._rho_levels: tuple[np.ndarray, np.ndarray] | None = None
        if self.flag < 0:
            return
        current = model.settings
        current.update(settings)
        model.settings = current
        self._soft_ok = soft_weights_supported(model)
        if self._soft_ok and self.native:
            lower, upper = model.soft_weight_arrays()
            self._rho_levels = (lower[ws.head:], upper[ws.head:])

    def load(self, w: FloatArray, first: bool = False) -> None:
        """Hand the rows, sides and per-row weights in the workspace to DAQP (warm start).

        Args:
            w: Level row weights (``ws.ml``,), positive.
            first: The model was just set up (its rows are loaded; only the weights are set).
        """
        if first:
            self.set_weights(w, self.rho_soft)
        elif self._rho_levels is not None:  # straight into DAQP's arrays, taken by the update
            lower, upper = self._rho_levels
            self._soft.compute_levels(self._rows, w, self.rho_soft, lower)
            upper[:] = lower
            self.model.refresh()
        else:
            ws = self.ws
            self.model.update(A=ws.daqp_A, bupper=ws.bu, blower=ws.bl)
            self.set_weights(w, self.rho_soft)

    def set_weights(self, w: FloatArray, rho_soft: float) -> None:
        """Set the per-row soft weights for ``rho_soft`` (nothing on a daqp without them)."""
        if not self._soft_ok:
            return
        rho = self._soft.compute(self._rows, w, rho_soft)
        if self.native:
            self.model.soft_weights_in_place(rho)
        else:
            self.model.soft_weights(rho_l=rho, rho_u=rho)

    def cold(self, w: FloatArray, rho_soft: float) -> None:
        """Prepare a cold-started retry with another ``rho_soft`` (settings and weights)."""
        self._set_rho(rho_soft)
        self.set_weights(w, rho_soft)
        self.model.update(sense=self._sense0.copy())

    def restore(self) -> None:
        """Back to the settings' ``rho_soft`` after retries (the next load sets the weights)."""
        self._set_rho(self.rho_soft)

    def _set_rho(self, rho_soft: float) -> None:
        settings = self.model.settings
        settings["rho_soft"] = rho_soft
        self.model.settings = settings

    def solve(self) -> tuple[FloatArray, int, float, int]:
        """Solve: ``(x, exit flag, DAQP's solve time [s], iterations)``.

        With direct calls ``x`` is the model's reused buffer (copy it to keep it).
        """
        model = self.model
        if self.native:
            flag = model.solve_in_place()
            return model.x, flag, model.solve_time, model.iterations
        x, _, flag, info = model.solve()
        return x, int(flag), float(info["solve_time"]), int(info["iterations"])
