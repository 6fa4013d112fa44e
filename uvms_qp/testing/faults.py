"""Fault injection for tests: a back-end, or DAQP's binding below it, that misbehaves on command.

:func:`inject` installs an :class:`Injector` on the primary solver of a
:class:`~uvms_qp.hqp.HierarchySolver`, :class:`~uvms_qp.safety.SafeSolver` or
:class:`~uvms_qp.controller.Controller`:

* ``at="backend"`` wraps the back-end object: its :class:`~uvms_qp.hqp.backends.Answer` is
  replaced (any back-end family);
* ``at="binding"`` goes below the DAQP back-end: every DAQP binding it opens from now on
  (:attr:`~uvms_qp.hqp.backends.daqp.DaqpBackend.open_binding`) has its ``solve`` faulted, so the
  back-end's own acceptance and ``rho_soft`` ladder see the fault, as with a misbehaving C
  library.

Arming: ``calls`` (indices of the injector's calls that fail, counted from 0), ``count`` (the next
``count`` calls fail), or the ``armed`` flag set by hand (every call fails while True).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from enum import StrEnum
from typing import Any

import numpy as np

from ..errors import SolverError
from ..hqp import HierarchySolver, Problem, Status
from ..hqp.backends import Answer
from ..hqp.backends.daqp import DaqpBackend


class Fault(StrEnum):
    """Failure modes of a back-end.

    Members:
        RAISE_OWN: raises :class:`~uvms_qp.errors.SolverError`.
        RAISE_FOREIGN: raises a foreign exception (``RuntimeError``, as a native binding might).
        MEMORY: raises ``MemoryError``.
        NONE: claims success without an ``x`` (None).
        WRONG_LENGTH: claims success with an ``x`` one entry too long.
        NAN_SUCCESS: claims success with a NaN ``x``.
        BOUND_VIOLATION: claims success with an ``x`` 0.1 beyond a finite bound.
        FEASIBLE_WRONG: claims success with a feasible but wrong ``x`` (zero clipped into the
            box), which only an optimality certificate can tell from an optimum.
        WILD_FAILURE: reports failure with a wild ``x`` (1e12 everywhere).
        SLEEP: answers correctly, then sleeps ``sleep`` seconds (a solve-time spike).
    """

    RAISE_OWN = "raise_own"
    RAISE_FOREIGN = "raise_foreign"
    MEMORY = "memory"
    NONE = "none"
    WRONG_LENGTH = "wrong_length"
    NAN_SUCCESS = "nan_success"
    BOUND_VIOLATION = "bound_violation"
    FEASIBLE_WRONG = "feasible_wrong"
    WILD_FAILURE = "wild_failure"
    SLEEP = "sleep"


_RAISES = {Fault.RAISE_OWN: lambda: SolverError("injected back-end failure"),
           Fault.RAISE_FOREIGN: lambda: RuntimeError("injected foreign exception"),
           Fault.MEMORY: lambda: MemoryError("injected out-of-memory")}


class Injector:
    """The schedule of one injection and what it did.

    Args:
        fault: Failure mode.
        calls: Indices of the calls that fail (0 = first call seen by the injector).
        count: Alternatively, fail the next ``count`` calls.
        sleep: Sleep time of :attr:`Fault.SLEEP` [s].

    Attributes:
        armed: Every call fails while True (set by hand).
        remaining: Calls still to fail (``count``).
        n_calls: Calls seen so far.
        n_faults: Faults injected so far.
        sleeper: How :attr:`Fault.SLEEP` waits (``time.sleep``; a test may advance a fake clock
            instead, so that slowness does not depend on the machine).
    """

    def __init__(self, fault: Fault | str, *, calls: Iterable[int] = (), count: int = 0,
                 sleep: float = 0.05) -> None:
        self.fault = Fault(fault)
        self.calls = set(calls)
        self.remaining = int(count)
        self.sleep = float(sleep)
        self.armed = False
        self.n_calls = 0
        self.n_faults = 0
        self.sleeper: Callable[[float], None] = time.sleep

    def fires(self) -> bool:
        """Count one call; True when it must fail."""
        index = self.n_calls
        self.n_calls += 1
        fire = self.armed or index in self.calls
        if not fire and self.remaining > 0:
            self.remaining -= 1
            fire = True
        if fire:
            self.n_faults += 1
        return fire

    def wrong_x(self, n: int, x: np.ndarray | None, lower: np.ndarray,
                upper: np.ndarray) -> np.ndarray | None:
        """The ``x`` of a claimed success under this fault (after raising the raising ones)."""
        fault = self.fault
        if fault in _RAISES:
            raise _RAISES[fault]()
        if fault is Fault.NONE:
            return None
        if fault is Fault.WRONG_LENGTH:
            return np.zeros(n + 1)
        if fault is Fault.NAN_SUCCESS:
            return np.full(n, np.nan)
        if fault is Fault.FEASIBLE_WRONG:
            return np.minimum(np.maximum(np.zeros(n), lower), upper)
        if fault is Fault.WILD_FAILURE:
            return np.full(n, 1e12)
        # BOUND_VIOLATION: push the first finitely bounded variable 0.1 beyond its bound
        out = np.zeros(n) if x is None else np.array(x, dtype=np.float64)
        finite_hi, finite_lo = np.flatnonzero(np.isfinite(upper)), np.flatnonzero(
            np.isfinite(lower))
        if finite_hi.size:
            out[finite_hi[0]] = upper[finite_hi[0]] + 0.1
        elif finite_lo.size:
            out[finite_lo[0]] = lower[finite_lo[0]] - 0.1
        else:
            out[:] = np.nan
        return out


class FaultyBackend:
    """A back-end wrapper whose answers the injector replaces on its schedule."""

    def __init__(self, inner: Any, injector: Injector) -> None:
        self.inner = inner
        self.injector = injector
        self.spec = inner.spec

    @property
    def end(self) -> float:
        """The wrapped back-end's end of the current solve [s on its clock]."""
        return float(self.inner.end)

    @end.setter
    def end(self, value: float) -> None:
        self.inner.end = value

    @property
    def clock(self) -> Callable[[], float]:
        """The wrapped back-end's clock."""
        return self.inner.clock  # type: ignore[no-any-return]

    @clock.setter
    def clock(self, clock: Callable[[], float]) -> None:
        self.inner.clock = clock

    def reset(self) -> None:
        """Cold-start the wrapped back-end (the schedule is kept)."""
        self.inner.reset()

    def reduce(self, problem: Problem) -> bool:
        """The wrapped back-end's reduction (faults touch answers only)."""
        return bool(self.inner.reduce(problem))

    def solve(self, problem: Problem) -> Answer:
        """Solve through the wrapped back-end, or fail as scheduled."""
        injector = self.injector
        if not injector.fires():
            return self.inner.solve(problem)  # type: ignore[no-any-return]
        if injector.fault is Fault.SLEEP:
            answer = self.inner.solve(problem)
            injector.sleeper(injector.sleep)
            return answer  # type: ignore[no-any-return]
        x = None
        if injector.fault is Fault.BOUND_VIOLATION:
            x = self.inner.solve(problem).x
        wrong = injector.wrong_x(problem.n, x, problem.lower, problem.upper)
        failed = injector.fault is Fault.WILD_FAILURE
        return Answer(wrong, Status.BACKEND_ERROR if failed else Status.OPTIMAL,
                      "injected failure" if failed else "")


class FaultyBinding:
    """A DAQP binding whose ``solve`` the injector fails on its schedule (else forwarded)."""

    def __init__(self, inner: Any, injector: Injector) -> None:
        self._inner = inner
        self._injector = injector
        self._sides: tuple[np.ndarray, np.ndarray] | None = None
        self.x = inner.x
        self.solve_time = 0.0
        self.iterations = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    @property
    def settings(self) -> dict[str, Any]:
        """The wrapped binding's settings."""
        return self._inner.settings  # type: ignore[no-any-return]

    @settings.setter
    def settings(self, new: dict[str, Any]) -> None:
        self._inner.settings = new

    def setup(self, H: Any, f: Any, A: Any, bupper: Any, blower: Any, sense: Any,
              break_points: Any) -> tuple[int, float]:
        """Forwarded; the sides are kept to place the faulted ``x``."""
        self._sides = (blower, bupper)
        out = self._inner.setup(H, f, A, bupper, blower, sense, break_points)
        self.x = self._inner.x
        return out  # type: ignore[no-any-return]

    def solve(self) -> int:
        """DAQP's solve, or the scheduled fault (a claimed success, or flag -4 for a wild x)."""
        injector = self._injector
        fired = injector.fires()
        if not fired or injector.fault is Fault.SLEEP:
            flag = int(self._inner.solve())
            if fired:
                injector.sleeper(injector.sleep)
            self.x = self._inner.x
            self.solve_time, self.iterations = self._inner.solve_time, self._inner.iterations
            return flag
        lower, upper = self._sides  # type: ignore[misc]
        n = len(self._inner.x)
        x = None
        if injector.fault is Fault.BOUND_VIOLATION:
            self._inner.solve()
            x = self._inner.x
        self.x = injector.wrong_x(n, x, lower[:n], upper[:n])  # type: ignore[assignment]
        return -4 if injector.fault is Fault.WILD_FAILURE else 1


def _solver(target: Any) -> HierarchySolver:
    """The primary hierarchy solver of a Controller, SafeSolver or HierarchySolver."""
    safe = getattr(target, "safe", None)
    target = safe if safe is not None else target
    primary = getattr(target, "primary", None)
    return primary if primary is not None else target  # type: ignore[no-any-return]


def inject(target: Any, fault: Fault | str, *, at: str = "backend", **schedule: Any) -> Injector:
    """Fault the primary solver of ``target``; returns the injector (its schedule and counts).

    Args:
        target: A Controller, SafeSolver or HierarchySolver (its primary is faulted), or a
            SafeSolver's ``alternate``.
        fault: Failure mode.
        at: ``"backend"`` (wrap the back-end object) or ``"binding"`` (below the DAQP back-end,
            at its C binding; DAQP only).
        **schedule: ``calls``, ``count``, ``sleep`` (see :class:`Injector`).

    Raises:
        ValueError: ``at="binding"`` on a back-end that is not DAQP's, or an unknown ``at``.
    """
    solver = _solver(target)
    injector = schedule.pop("injector", None) or Injector(fault, **schedule)
    if at == "backend":
        solver.backend = FaultyBackend(solver.backend, injector)
    elif at == "binding":
        backend = solver.backend
        if not isinstance(backend, DaqpBackend):
            raise ValueError(f"at='binding' needs the DAQP back-end, got {solver.name!r}")
        opener = backend.open_binding
        backend.open_binding = lambda: FaultyBinding(opener(), injector)
        backend.reset()
    else:
        raise ValueError(f"at: expected 'backend' or 'binding', got {at!r}")
    return injector


class RandomInjector(Injector):
    """Fails a random share of calls with a random :class:`Fault` (for soaks).

    Args:
        rate: Probability that a call fails, ``0 <= rate <= 1``.
        rng: Random generator (seeded by the caller for reproducible soaks).
        faults: Failure modes drawn from (default: all).
        sleep: Sleep time of :attr:`Fault.SLEEP` [s].

    Attributes:
        by_kind: Faults injected so far, by kind.
    """

    def __init__(self, rate: float, rng: np.random.Generator,
                 faults: Iterable[Fault | str] = tuple(Fault), sleep: float = 0.05) -> None:
        kinds = tuple(Fault(f) for f in faults)
        super().__init__(kinds[0], sleep=sleep)
        self.kinds = kinds
        self.rate = float(rate)
        self.rng = rng
        self.by_kind: dict[Fault, int] = dict.fromkeys(kinds, 0)

    def fires(self) -> bool:
        """Count one call; True (with a new random fault) at the configured rate."""
        self.n_calls += 1
        if self.rng.uniform() >= self.rate:
            return False
        self.fault = self.kinds[int(self.rng.integers(len(self.kinds)))]
        self.by_kind[self.fault] += 1
        self.n_faults += 1
        return True


def inject_random(target: Any, rate: float, rng: np.random.Generator, *,
                  at: str = "backend", **kwargs: Any) -> RandomInjector:
    """:func:`inject` with a :class:`RandomInjector` (``faults``, ``sleep`` as keywords)."""
    injector = RandomInjector(rate, rng, **kwargs)
    inject(target, injector.fault, at=at, injector=injector)
    return injector
