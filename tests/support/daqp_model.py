"""DAQP's binding interface through ``daqp.Model``: the oracle of the package's C binding.

``uvms_qp.hqp.backends.daqp_binding.NativeDaqp`` calls DAQP's C entry points on the caller's
arrays; this class does the same through DAQP's own Python API, one ``update`` and one
``soft_weights`` call per refresh. ``tests/unit/hqp/test_daqp.py`` checks that the two give the
same answers, iterations and working sets bit for bit, and runs the back-end on this one.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from uvms_qp._validation import FloatArray


class ModelDaqp:
    """The binding's interface through ``daqp.Model``: slow, obviously right (the oracle)."""

    def __init__(self) -> None:
        import daqp

        self._model = daqp.Model()
        self._held: tuple[np.ndarray, ...] = ()
        self._rho: tuple[FloatArray, FloatArray] | None = None
        self._empty = np.zeros(0, dtype=np.intc)
        self._f = np.zeros(0)
        self.x = np.zeros(0)
        self.lam = np.zeros(0)
        self.solve_time = 0.0
        self.iterations = 0

    def setup(self, H: FloatArray, f: FloatArray, A: FloatArray, bupper: FloatArray,
              blower: FloatArray, sense: np.ndarray, break_points: np.ndarray
              ) -> tuple[int, float]:
        """``daqp.Model.setup``; the arrays are kept and handed over again by :meth:`refresh`."""
        self._held = (A, bupper, blower)
        self._f = f
        m = bupper.shape[0]
        self._empty = np.zeros(m, dtype=np.intc)
        self._rho = None
        flag, setup_time = self._model.setup(H, f, A, bupper, blower, sense,
                                             break_points=break_points)
        if flag >= 0 and self._supports_soft_weights():
            self._rho = (np.zeros(m), np.zeros(m))
        return int(flag), float(setup_time)

    def _supports_soft_weights(self) -> bool:
        """The binding has ``soft_weights`` and DAQP was built with them (checked once)."""
        setter = getattr(self._model, "soft_weights", None)
        if setter is None:
            return False
        try:
            setter()  # no arrays: changes nothing, refused by a build without them
        except RuntimeError:
            return False
        return True

    @property
    def settings(self) -> dict[str, Any]:
        """``daqp.Model.settings``."""
        return dict(self._model.settings)

    @settings.setter
    def settings(self, new: dict[str, Any]) -> None:
        current = self._model.settings
        current.update(new)
        self._model.settings = current

    def soft_weights(self, rho: FloatArray) -> bool:
        """``daqp.Model.soft_weights`` with ``rho`` on both sides; False if unsupported."""
        if self._rho is None:
            return False
        self._rho[0][:] = rho  # kept: the next refresh hands them over again
        self._rho[1][:] = rho
        self._model.soft_weights(rho_l=rho, rho_u=rho)
        return True

    def soft_weight_views(self) -> tuple[FloatArray, FloatArray] | None:
        """Own arrays of soft weights, handed to DAQP by :meth:`refresh`."""
        return self._rho

    def refresh(self) -> int:
        """``daqp.Model.update`` of rows and sides, then the soft weights."""
        A, bu, bl = self._held
        flag = int(self._model.update(A=A, bupper=bu, blower=bl))
        if self._rho is not None:
            self._model.soft_weights(rho_l=self._rho[0], rho_u=self._rho[1])
        return flag

    def restart(self, sense: np.ndarray) -> int:
        """``daqp.Model.update(sense=...)``: the next solve starts cold."""
        return int(self._model.update(sense=sense))

    def solve(self) -> int:
        """``daqp.Model.solve``: sets ``x`` (fresh), time and iterations; returns the flag."""
        x, _, flag, info = self._model.solve()
        self.x = x
        self.lam = np.asarray(info["lam"], dtype=np.float64)
        self.solve_time = float(info["solve_time"])
        self.iterations = int(info["iterations"])
        return int(flag)

    def solve_ldp(self, rows: bool, warm: bool) -> int:
        """``daqp.Model.update`` of ``f``, sides (and rows), empty working set; then solve.

        Always from an empty working set (``warm`` is ignored: the fallback binding of a DAQP
        whose C API is not reachable).
        """
        A, bu, bl = self._held
        if rows:
            self._model.update(f=self._f, A=A, bupper=bu, blower=bl, sense=self._empty)
        else:
            self._model.update(f=self._f, bupper=bu, blower=bl, sense=self._empty)
        return self.solve()
