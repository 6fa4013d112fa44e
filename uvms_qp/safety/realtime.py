"""Preparing a control process for wall-clock deadlines: a real-time priority, a quiet collector.

A step's deadline (:mod:`uvms_qp.safety.deadline`) bounds the time the step *computes*. Two
things outside the step decide whether it also ends on time in wall time:

* **The scheduler.** A thread that waits for a core ends late by the wait. On a loaded machine
  a normal-priority control loop is preempted often (on a 2-core machine with both cores busy,
  half of the demo's steps were preempted and some ended 20-45 ms late). A real-time policy
  (``SCHED_FIFO``) lets the control thread take a core the moment it is ready.
* **Python's cyclic garbage collector.** A full collection scans every tracked object of the
  process. After the imports and the set-up of a model and a controller that is some 90,000
  objects, and one such collection takes about 40 ms, inside whichever step happens to trigger
  it. Freezing the collector after set-up (:func:`gc.freeze`) moves the objects alive then
  into a permanent generation that collections no longer scan; later collections scan only
  what the loop itself keeps.

Both are decisions of the host process, so nothing here runs unless called:
:func:`prepare_realtime` once, after set-up and before the control loop;
:meth:`RealtimeSettings.restore` to undo it. ``benchmarks/bench_deadline.py --realtime``
measures the step times with and without it (table in ``docs/reliability.md``).
"""

from __future__ import annotations

import gc
import os
from dataclasses import dataclass

from ..errors import InputError


class RealtimePermissionError(PermissionError):
    """The operating system refused a real-time scheduling policy for this process."""


@dataclass(frozen=True)
class RealtimeSettings:
    """What :func:`prepare_realtime` changed, and how to undo it.

    Attributes:
        frozen_objects: Objects moved to the collector's permanent generation.
        priority: The ``SCHED_FIFO`` priority set, or None when the policy was left as it was.
        previous_policy: The scheduling policy before (``os.SCHED_*``), or None.
        previous_priority: Its priority before, or None.
    """

    frozen_objects: int
    priority: int | None
    previous_policy: int | None
    previous_priority: int | None

    def restore(self) -> None:
        """Unfreeze the collector and put the calling thread's scheduling policy back."""
        if self.frozen_objects:
            gc.unfreeze()
        if self.priority is not None and self.previous_policy is not None:
            os.sched_setscheduler(0, self.previous_policy,
                                  os.sched_param(self.previous_priority or 0))


def prepare_realtime(priority: int | None = None, *, freeze_collector: bool = True
                     ) -> RealtimeSettings:
    """Prepare the calling process for a periodic control loop with wall-clock deadlines.

    Call once, after the model, the controller and its first step (which sets the back-ends
    up) and before the loop; the loop should sleep until its next period between steps (a
    real-time thread that never sleeps is throttled by the kernel, 50 ms per second by default
    on Linux).

    Args:
        priority: ``SCHED_FIFO`` priority for the calling thread (1-99; Linux, needs root or
            ``CAP_SYS_NICE``, the same as ``chrt -f <priority>``), or None to leave the
            scheduling policy as it is.
        freeze_collector: Run a full collection, then :func:`gc.freeze` the objects alive
            now, so that no later collection spends tens of milliseconds scanning them.

    Returns:
        What was changed (:meth:`RealtimeSettings.restore` undoes it).

    Raises:
        InputError: ``priority`` is not an integer in the policy's range.
        RealtimePermissionError: the operating system refused the policy (the message says
            what grants it).
        NotImplementedError: a priority was asked for on a platform without
            ``os.sched_setscheduler`` (not Linux).
    """
    previous_policy = previous_priority = None
    if priority is not None:
        if not hasattr(os, "sched_setscheduler"):
            raise NotImplementedError(
                "prepare_realtime: a real-time priority needs os.sched_setscheduler (Linux)")
        low = os.sched_get_priority_min(os.SCHED_FIFO)
        high = os.sched_get_priority_max(os.SCHED_FIFO)
        if isinstance(priority, bool) or not isinstance(priority, int) or not (
                low <= priority <= high):
            raise InputError(f"prepare_realtime: priority must be an integer in [{low}, {high}]"
                             f" (SCHED_FIFO), got {priority!r}")
        previous_policy = os.sched_getscheduler(0)
        previous_priority = os.sched_getparam(0).sched_priority
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        except PermissionError as exc:
            raise RealtimePermissionError(
                f"prepare_realtime: the system refused SCHED_FIFO priority {priority} ({exc}); "
                "run as root, grant CAP_SYS_NICE, or raise the 'rtprio' limit "
                "(/etc/security/limits.conf)") from exc
    frozen = 0
    if freeze_collector:
        gc.collect()
        gc.freeze()
        frozen = gc.get_freeze_count()
    return RealtimeSettings(frozen, priority, previous_policy, previous_priority)
