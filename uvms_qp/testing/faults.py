"""Fault injection for tests: a back-end wrapper that misbehaves on command.

:class:`FaultyBackend` wraps a hierarchy back-end (anything with ``solve(problem) ->
BackendOutput``) and, while armed, replaces its answer by one of the failure modes seen in the
field (:class:`Fault`). :func:`inject` installs it into a :class:`~uvms_qp.hqp.HierarchySolver`.

Arming: ``calls`` (indices of the wrapper's calls that fail, counted from 0), ``count`` (the next
``count`` calls fail), or the ``armed`` flag set by hand (every call fails while True).
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from enum import StrEnum
from typing import Any

import numpy as np

from ..errors import SolverError
from ..hqp import HierarchySolver, Status
from ..hqp.backends import BackendOutput
from ..hqp.problem import Problem
from ..safety.fallback import reset_backend


class Fault(StrEnum):
    """Failure modes of a back-end.

    Members:
        RAISE_OWN: raises :class:`~uvms_qp.errors.SolverError`.
        RAISE_FOREIGN: raises a foreign exception (``RuntimeError``, as a native binding might).
        NAN_SUCCESS: claims success with a NaN ``x``.
        BOUND_VIOLATION: claims success with an ``x`` 0.1 beyond a finite bound.
        WILD_FAILURE: reports failure with a wild ``x`` (1e12 everywhere).
        SLEEP: sleeps ``sleep`` seconds, then answers correctly (a solve-time spike).
    """

    RAISE_OWN = "raise_own"
    RAISE_FOREIGN = "raise_foreign"
    NAN_SUCCESS = "nan_success"
    BOUND_VIOLATION = "bound_violation"
    WILD_FAILURE = "wild_failure"
    SLEEP = "sleep"


class FaultyBackend:
    """A back-end wrapper that injects :class:`Fault` on chosen calls.

    Args:
        inner: The real back-end.
        fault: Failure mode.
        calls: Indices of the calls that fail (0 = first call through this wrapper).
        count: Alternatively, fail the next ``count`` calls.
        sleep: Sleep time of :attr:`Fault.SLEEP` [s].

    Attributes:
        armed: Every call fails while True (set by hand).
        n_calls: Calls so far.
        n_faults: Faults injected so far.
    """

    def __init__(self, inner: Any, fault: Fault | str, *, calls: Iterable[int] = (),
                 count: int = 0, sleep: float = 0.05) -> None:
        self.inner = inner
        self.fault = Fault(fault)
        self.calls = set(calls)
        self.remaining = int(count)
        self.sleep = float(sleep)
        self.armed = False
        self.n_calls = 0
        self.n_faults = 0

    def reset(self) -> None:
        """Cold-start the wrapped back-end (the fault schedule is kept)."""
        reset_backend(self.inner)

    def _fires(self) -> bool:
        index = self.n_calls
        self.n_calls += 1
        if self.armed or index in self.calls:
            return True
        if self.remaining > 0:
            self.remaining -= 1
            return True
        return False

    def solve(self, problem: Problem) -> BackendOutput:
        """Solve through the wrapped back-end, or fail as configured."""
        if not self._fires():
            return self.inner.solve(problem)  # type: ignore[no-any-return]
        self.n_faults += 1
        fault = self.fault
        n = problem.n
        if fault is Fault.RAISE_OWN:
            raise SolverError("injected back-end failure")
        if fault is Fault.RAISE_FOREIGN:
            raise RuntimeError("injected foreign exception from a native back-end")
        if fault is Fault.NAN_SUCCESS:
            return BackendOutput(np.full(n, np.nan), Status.OPTIMAL, "")
        if fault is Fault.WILD_FAILURE:
            return BackendOutput(np.full(n, 1e12), Status.BACKEND_ERROR, "injected failure")
        out = self.inner.solve(problem)
        if fault is Fault.SLEEP:
            time.sleep(self.sleep)
            return out  # type: ignore[no-any-return]
        # BOUND_VIOLATION: push the first finitely bounded variable 0.1 beyond its bound
        x = np.zeros(n) if out.x is None else np.array(out.x, dtype=np.float64)
        finite_hi = np.flatnonzero(np.isfinite(problem.upper))
        finite_lo = np.flatnonzero(np.isfinite(problem.lower))
        if finite_hi.size:
            i = int(finite_hi[0])
            x[i] = problem.upper[i] + 0.1
        elif finite_lo.size:
            i = int(finite_lo[0])
            x[i] = problem.lower[i] - 0.1
        else:
            x[:] = np.nan
        return BackendOutput(x, Status.OPTIMAL, "")


class RandomFaults(FaultyBackend):
    """A back-end that fails on a random share of its calls, with a random :class:`Fault`.

    Args:
        inner: The real back-end.
        rate: Probability that a call fails, ``0 <= rate <= 1``.
        rng: Random generator (seeded by the caller for reproducible soaks).
        faults: Failure modes drawn from (default: all).
        sleep: Sleep time of :attr:`Fault.SLEEP` [s].
    """

    def __init__(self, inner: Any, rate: float, rng: np.random.Generator,
                 faults: Iterable[Fault | str] = tuple(Fault), sleep: float = 0.05) -> None:
        kinds = tuple(Fault(f) for f in faults)
        super().__init__(inner, kinds[0], sleep=sleep)
        self.kinds = kinds
        self.rate = float(rate)
        self.rng = rng
        #: Faults injected so far, by kind.
        self.by_kind: dict[Fault, int] = dict.fromkeys(kinds, 0)

    def _fires(self) -> bool:
        self.n_calls += 1
        if self.rng.uniform() >= self.rate:
            return False
        self.fault = self.kinds[int(self.rng.integers(len(self.kinds)))]
        self.by_kind[self.fault] += 1
        return True


def inject(solver: HierarchySolver, fault: Fault | str, **kwargs: Any) -> FaultyBackend:
    """Wrap the back-end of ``solver`` in a :class:`FaultyBackend` and return the wrapper.

    Args:
        solver: The hierarchy solver (e.g. ``controller.safe.primary``).
        fault: Failure mode.
        **kwargs: ``calls``, ``count``, ``sleep`` (see :class:`FaultyBackend`).
    """
    wrapper = FaultyBackend(solver._backend, fault, **kwargs)
    solver._backend = wrapper
    return wrapper


def inject_random(solver: HierarchySolver, rate: float, rng: np.random.Generator,
                  **kwargs: Any) -> RandomFaults:
    """Wrap the back-end of ``solver`` in a :class:`RandomFaults` and return the wrapper."""
    wrapper = RandomFaults(solver._backend, rate, rng, **kwargs)
    solver._backend = wrapper
    return wrapper
