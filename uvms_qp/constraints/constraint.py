"""Abstract hard constraint: box bounds on zeta and/or hard inequality rows, never relaxed.

Every constraint is built from keyword arguments, bound to a model once (:meth:`Constraint.bind`)
and evaluated every control tick with the control period ``dt`` [s]. Box constraints intersect
their bounds into the controller's box (:meth:`Constraint.fill_box`); row constraints write hard
rows ``lower <= A zeta <= upper`` (:meth:`Constraint.fill_rows`). Both hold at every level of the
hierarchy and with every back-end.

A constraint with memory (the command-rate bounds) keeps it in a memory object
(:meth:`Constraint.memory`): each controller makes its own and passes it to
:meth:`Constraint.fill_box`, :meth:`Constraint.command_sent` (the command the controller sent) and
:meth:`Constraint.reset`; without one, the constraint uses its own (a run that tells it the
commands itself, :func:`uvms_qp.sim.simulate`). The constraint is a description, so any number of
controllers may share it. A box that
:attr:`Constraint.yields` is intersected after the others and clipped into them
(:func:`intersect_boxes`): it never empties the box.
"""

from __future__ import annotations

from abc import ABC
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ..rows import Rows

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class Constraint(ABC):  # noqa: B024 - a constraint overrides fill_box and/or fill_rows
    """Base class of hard constraints.

    Subclasses set ``type_name`` (scenario registry key) and ``unit``, implement :meth:`_bind`
    and override :meth:`fill_box` (box constraints) and/or :meth:`fill_rows` (row constraints).

    Attributes:
        name: Name used in diagnostics.
        model: Bound model or None.
        rows_dim: Number of hard rows (0 for a pure box constraint).
    """

    type_name: ClassVar[str] = "constraint"
    unit: ClassVar[str] = "m/s, rad/s"
    has_box: ClassVar[bool] = False
    is_static: ClassVar[bool] = False
    """True when the box does not depend on the state (the controller then merges it once)."""
    yields: ClassVar[bool] = False
    """True for a box that gives way to the others: filled after them and clipped into their
    intersection (position safety first), so it never empties the box."""

    def __init__(self, *, name: str | None = None) -> None:
        if name is not None and (not isinstance(name, str) or not name.strip()):
            raise InputError(f"name: expected a non-empty string, got {name!r}")
        self.name = name or self.type_name
        self.model: Model | None = None
        self.rows_dim = 0

    def bind(self, model: Model) -> Constraint:
        """Validate against ``model`` and size the rows (raises on unknown joints/dimensions)."""
        self.rows_dim = int(self._bind(model))
        self.model = model
        return self

    def _bind(self, model: Model) -> int:
        """Validate against ``model``; return the number of hard rows."""
        return 0

    def _require_bound(self) -> Model:
        if self.model is None:
            raise InputError(f"constraint {self.name!r} is not bound; call bind(model) first")
        return self.model

    # ------------------------------------------------------- in place (the controller, every step)
    def fill_box(  # noqa: B027 - overridden by box constraints
        self, state: State, dt: float, lower: FloatArray, upper: FloatArray
    ) -> None:
        """Intersect this constraint's bounds into ``lower``/``upper`` (nv,) in place."""

    def fill_rows(  # noqa: B027 - overridden by row constraints
        self, state: State, dt: float, A: FloatArray, lower: FloatArray, upper: FloatArray
    ) -> None:
        """Write the hard rows into ``A`` (rows_dim, nv), ``lower``, ``upper``."""

    # ------------------------------------------------------------------------------ run-time hooks
    def memory(self) -> Any:
        """A new run-time memory for one controller, or None for a constraint without memory."""
        return None

    def command_sent(self, zeta: FloatArray, memory: Any = None) -> None:  # noqa: B027
        """The command ``zeta`` (nv,) the controller returned this period (called every step).

        Constraints with memory (the command-rate bounds) keep it in ``memory`` (default their
        own); the others ignore it.
        """

    def reset(self, memory: Any = None) -> None:  # noqa: B027 - optional hook
        """Forget run-time memory: ``memory`` (default the constraint's own)."""

    # ----------------------------------------------------------------------------------- user API
    def box(self, state: State, dt: float) -> tuple[FloatArray, FloatArray]:
        """Bounds ``(lower, upper)`` (nv,) on zeta at ``state`` for period ``dt`` [s].

        Unconstrained components are ``-inf`` / ``+inf``.
        """
        model = self._require_bound()
        dt = as_scalar(dt, "dt", positive=True)
        lower = np.full(model.nv, -np.inf)
        upper = np.full(model.nv, np.inf)
        self.fill_box(state, dt, lower, upper)
        return lower, upper

    def rows(self, state: State, dt: float) -> Rows | None:
        """Hard rows at ``state`` (None for a pure box constraint)."""
        model = self._require_bound()
        if self.rows_dim == 0:
            return None
        A = np.zeros((self.rows_dim, model.nv))
        lower = np.zeros(self.rows_dim)
        upper = np.zeros(self.rows_dim)
        self.fill_rows(state, dt, A, lower, upper)
        return Rows(A, lower, upper, None, self.name)

    def update(self, **params: Any) -> None:
        """Change parameters at run time; the default accepts none."""
        if params:
            raise InputError(f"{self.name}.update: unknown parameter(s) {', '.join(params)}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"


class SymmetricRateBox(Constraint):
    """A static box ``-limit <= zeta[cols] <= limit`` on some columns of zeta.

    Subclasses compute, in :meth:`_bind`, the columns ``_cols`` (int array) and the finite limits
    ``_lim`` (same length, > 0) they bound; this class intersects them into the box.
    """

    has_box = True
    is_static = True
    _cols: NDArray[np.intp]
    _lim: FloatArray

    def _set_limits(self, cols: NDArray[np.intp], lim: FloatArray) -> None:
        """Keep the columns whose limit is finite (an infinite limit leaves a column free)."""
        finite = np.isfinite(lim)
        self._cols = cols[finite]
        self._lim = lim[finite]

    def fill_box(self, state: State, dt: float, lower: FloatArray, upper: FloatArray) -> None:
        """Intersect ``[-limit, limit]`` into the box."""
        cols = self._cols
        lower[cols] = np.maximum(lower[cols], -self._lim)
        upper[cols] = np.minimum(upper[cols], self._lim)



def intersect_boxes(constraints: Iterable[Constraint], state: State, dt: float,
                    lower: FloatArray, upper: FloatArray) -> None:
    """Intersect the boxes of ``constraints`` into ``lower``/``upper`` (nv,) in place.

    Boxes that :attr:`Constraint.yields` come last, each clipped into what the others left.
    """
    boxes = [c for c in constraints if c.has_box]
    for c in boxes:
        if not c.yields:
            c.fill_box(state, dt, lower, upper)
    for c in boxes:
        if c.yields:
            c.fill_box(state, dt, lower, upper)
