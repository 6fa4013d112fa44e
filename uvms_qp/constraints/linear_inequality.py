"""General hard linear inequality rows over zeta."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._validation import FloatArray, as_matrix, as_vector, check_bounds_order
from ..errors import InputError, UnknownNameError
from .constraint import Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class LinearInequality(Constraint):
    r"""Hard rows ``lower <= A zeta <= upper`` (constant), e.g. a coupled speed limit.

    Args:
        A: Row matrix (m, k): over all of zeta (k = nv) or over the named ``columns``.
        lower: Lower sides (m,) (``-inf`` allowed; default ``-inf``).
        upper: Upper sides (m,) (``+inf`` allowed; default ``+inf``).
        columns: Names of the zeta components the columns of ``A`` refer to (from the model's
            ``zeta_names``); default all, in order.
        name: Name (default ``"linear_inequality"``).
    """

    type_name = "linear_inequality"
    unit = "row units"

    def __init__(self, *, A: list[list[float]], lower: list[float] | None = None,
                 upper: list[float] | None = None, columns: list[str] | None = None,
                 name: str | None = None) -> None:
        super().__init__(name=name)
        self.A = as_matrix(A, f"{self.name}.A")
        m = self.A.shape[0]
        if m == 0:
            raise InputError(f"{self.name}.A: expected at least one row")
        self.lower = (np.full(m, -np.inf) if lower is None
                      else as_vector(lower, f"{self.name}.lower", m, allow_inf=True))
        self.upper = (np.full(m, np.inf) if upper is None
                      else as_vector(upper, f"{self.name}.upper", m, allow_inf=True))
        check_bounds_order(self.lower, self.upper, self.name)
        if np.any(self.lower == np.inf) or np.any(self.upper == -np.inf):
            raise InputError(f"{self.name}: a lower side is +inf or an upper side is -inf")
        if columns is not None and (not isinstance(columns, list | tuple)
                                    or not all(isinstance(c, str) for c in columns)):
            raise InputError(f"{self.name}.columns: expected a list of zeta component names")
        self.columns = None if columns is None else list(columns)
        if self.columns is not None and len(self.columns) != self.A.shape[1]:
            raise InputError(f"{self.name}.columns: {len(self.columns)} names for "
                             f"{self.A.shape[1]} columns of A")
        self._A_full = np.zeros((0, 0))

    def _bind(self, model: Model) -> int:
        names = tuple(model.zeta_names)
        if self.columns is None:
            if self.A.shape[1] != model.nv:
                raise InputError(f"{self.name}.A: expected {model.nv} columns (zeta = "
                                 f"{', '.join(names)}), got {self.A.shape[1]}")
            self._A_full = self.A.copy()
        else:
            full = np.zeros((self.A.shape[0], model.nv))
            for j, c in enumerate(self.columns):
                if c not in names:
                    raise UnknownNameError("zeta component", c, names)
                full[:, names.index(c)] += self.A[:, j]
            self._A_full = full
        return self.A.shape[0]

    def fill_rows(self, state: State, dt: float, A: FloatArray, lower: FloatArray,
                  upper: FloatArray) -> None:
        """Write the constant rows."""
        A[:] = self._A_full
        lower[:] = self.lower
        upper[:] = self.upper
