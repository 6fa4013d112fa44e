"""Where runs execute: a local process pool, or a Dask cluster, through one interface.

Both are :class:`concurrent.futures.Executor` objects:

- **local** (default): a :class:`~concurrent.futures.ProcessPoolExecutor` of ``workers``
  processes, forked from a server process that imported the library once (the ``forkserver``
  start method: a new worker costs a fork, not an import of Pinocchio, and no thread of the
  parent is copied into it);
- **Dask** (``scheduler="tcp://host:8786"``): the executor of a ``dask.distributed.Client``
  connected to that scheduler (``Client(address).get_executor()``), whose workers may be on
  other machines. Dask is an optional dependency (``pip install 'uvms-qp[cluster]'``).

A :class:`Pool` holds the executor and rebuilds it: a process pool whose worker dies is broken
for good (every pending future fails with ``BrokenProcessPool``), so the engine asks for a new
one and submits again what was in flight. The scheduler is reached when the pool is opened, so
an unreachable address is an error before any run starts.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Any

from ..errors import ConfigError

#: Seconds to wait for a Dask scheduler to answer before the address is declared unreachable.
CONNECT_TIMEOUT = 10.0
#: Modules the local workers' server process imports once, so each worker starts warm.
PRELOAD = ["uvms_qp.sweep.records"]
INSTALL_HINT = "pip install 'uvms-qp[cluster]'"


def usable_cpus() -> int:
    """The CPUs this process may run on (the default number of local workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def check_workers(workers: Any, path: str = "--workers") -> int:
    """A positive number of local worker processes.

    Raises:
        ConfigError: not a positive integer, at ``path``.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"expected a positive integer, got {workers!r}", path)
    return workers


class Pool:
    """An executor that can be rebuilt, with the number of runs it may hold at once.

    Args:
        workers: Local worker processes (default: the usable CPUs); ignored with ``scheduler``.
        scheduler: Address of a Dask scheduler (``tcp://host:port``), or None for local.
        timeout: Seconds to wait for the scheduler [s] (default :data:`CONNECT_TIMEOUT`).

    Raises:
        ConfigError: a bad ``workers``; with ``scheduler``, dask.distributed missing or the
            scheduler unreachable (path ``--scheduler``).
    """

    def __init__(self, workers: int | None = None, scheduler: str | None = None,
                 timeout: float | None = None) -> None:
        self.scheduler = scheduler
        self.workers = usable_cpus() if workers is None else check_workers(workers)
        self._client: Any = None
        self.executor: Executor = self._open(CONNECT_TIMEOUT if timeout is None else timeout)

    @property
    def kind(self) -> str:
        """``"local"`` or ``"dask"``."""
        return "local" if self.scheduler is None else "dask"

    @property
    def capacity(self) -> int:
        """Runs that execute at once: the local workers, or the cluster's worker threads."""
        if self._client is None:
            return self.workers
        return max(1, sum(self._client.nthreads().values()))

    @property
    def window(self) -> int:
        """Runs to keep submitted at once.

        Locally, one per worker: a dead worker then breaks only the runs the workers held (a
        process pool fails every queued run with the pool). A Dask cluster reschedules the
        tasks of a dead worker itself, so it gets two per worker thread to stay busy.
        """
        return self.capacity if self._client is None else 2 * self.capacity

    def _open(self, timeout: float) -> Executor:
        if self.scheduler is None:
            context = multiprocessing.get_context("forkserver")
            context.set_forkserver_preload(PRELOAD)
            return ProcessPoolExecutor(max_workers=self.workers, mp_context=context)
        return self._connect(self.scheduler, timeout)

    def _connect(self, address: str, timeout: float) -> Executor:
        if not isinstance(address, str) or not address.strip():
            raise ConfigError(f"expected a scheduler address such as tcp://host:8786, got "
                              f"{address!r}", "--scheduler")
        try:
            from distributed import Client  # optional dependency
        except ImportError:
            raise ConfigError(f"a Dask cluster needs dask.distributed: {INSTALL_HINT}",
                              "--scheduler") from None
        try:
            self._client = Client(address, timeout=timeout, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ConfigError(f"cannot reach the Dask scheduler at {address!r}: {reason}",
                              "--scheduler") from None
        return self._client.get_executor(pure=False)

    def submit(self, fn: Any, *args: Any) -> Future[Any]:
        """``executor.submit(fn, *args)``."""
        return self.executor.submit(fn, *args)

    def rebuild(self) -> None:
        """Replace a broken local pool by a new one (the Dask executor is kept)."""
        if self._client is not None:
            return
        self.executor.shutdown(wait=False, cancel_futures=True)
        self.executor = self._open(CONNECT_TIMEOUT)

    def close(self) -> None:
        """Shut the executor down (cancelling what has not started) and disconnect."""
        if self._client is not None:
            self.executor.shutdown(wait=False)
            self._client.close()
            self._client = None
        else:
            self.executor.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> Pool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def describe(self) -> str:
        """``2 local workers`` or ``Dask at tcp://...: 8 worker threads``."""
        if self._client is None:
            return f"{self.workers} local worker{'s' if self.workers != 1 else ''}"
        return f"Dask at {self.scheduler}: {self.capacity} worker threads"
