"""Faults of a sweep's workers, for tests: a run whose worker process dies, for real.

:class:`KillOnce` wraps the function a sweep's workers execute: on the run of a chosen index it
kills its own worker process with ``SIGKILL`` (no Python clean-up, as the kernel's out-of-memory
killer or a lost machine would), the first time only: a marker file records that it happened, so
the retried run completes. :class:`AlwaysKill` kills the worker on every attempt of that run.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..sweep.records import RunTask, run_one


@dataclass(frozen=True)
class KillOnce:
    """Kill the worker on the first attempt of run ``index`` (a module-level, picklable callable).

    Attributes:
        index: The run whose worker dies.
        marker: A file created just before the kill (its existence means "already killed").
        execute: What the worker runs otherwise.
    """

    index: int
    marker: str
    execute: Callable[[RunTask], dict[str, Any]] = run_one

    def __call__(self, task: RunTask) -> dict[str, Any]:
        """Run ``task``, or die on the first attempt of run :attr:`index`."""
        if task.index == self.index and not Path(self.marker).exists():
            Path(self.marker).write_text(str(os.getpid()))
            os.kill(os.getpid(), signal.SIGKILL)
        return self.execute(task)


@dataclass(frozen=True)
class AlwaysKill:
    """Kill the worker on every attempt of run ``index``."""

    index: int
    execute: Callable[[RunTask], dict[str, Any]] = run_one

    def __call__(self, task: RunTask) -> dict[str, Any]:
        """Run ``task``, or die on run :attr:`index`."""
        if task.index == self.index:
            os.kill(os.getpid(), signal.SIGKILL)
        return self.execute(task)
