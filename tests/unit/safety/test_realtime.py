"""Preparing the host process for wall-clock deadlines: priority and frozen collector, undone."""

from __future__ import annotations

import gc
import os
import sys

import pytest

from uvms_qp.errors import InputError
from uvms_qp.safety import RealtimePermissionError, prepare_realtime

linux_only = pytest.mark.skipif(not hasattr(os, "sched_setscheduler"),
                                reason="scheduling policies are a Linux facility")


@pytest.fixture(autouse=True)
def _clean_collector() -> object:
    gc.unfreeze()
    yield
    gc.unfreeze()


def test_the_collector_is_frozen_then_released() -> None:
    assert gc.get_freeze_count() == 0
    settings = prepare_realtime()
    assert settings.frozen_objects == gc.get_freeze_count() > 1000  # the imports' objects
    assert settings.priority is None
    settings.restore()
    assert gc.get_freeze_count() == 0


def test_without_freezing_nothing_is_frozen() -> None:
    settings = prepare_realtime(freeze_collector=False)
    assert settings.frozen_objects == 0 == gc.get_freeze_count()


@linux_only
@pytest.mark.parametrize("priority", [0, 100, -1, 1.5, True, "50"])
def test_a_priority_outside_the_policys_range_is_refused(priority: object) -> None:
    before = os.sched_getscheduler(0)
    with pytest.raises(InputError, match="priority must be an integer in \\[1, 99\\]"):
        prepare_realtime(priority)  # type: ignore[arg-type]
    assert os.sched_getscheduler(0) == before
    assert gc.get_freeze_count() == 0  # nothing changed on refusal


@linux_only
def test_a_refused_policy_says_what_grants_it(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*args: object) -> None:
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(os, "sched_setscheduler", refuse)
    with pytest.raises(RealtimePermissionError, match="CAP_SYS_NICE") as info:
        prepare_realtime(10)
    assert isinstance(info.value, PermissionError)
    assert "priority 10" in str(info.value)


@linux_only
def test_the_priority_is_set_and_restored() -> None:
    before = os.sched_getscheduler(0), os.sched_getparam(0).sched_priority
    try:
        settings = prepare_realtime(5, freeze_collector=False)
    except RealtimePermissionError:
        pytest.skip("this user may not set a real-time policy")
    try:
        assert os.sched_getscheduler(0) == os.SCHED_FIFO
        assert os.sched_getparam(0).sched_priority == 5
        assert (settings.previous_policy, settings.previous_priority) == before
    finally:
        settings.restore()
    assert (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority) == before


@pytest.mark.skipif(hasattr(os, "sched_setscheduler"), reason="the policy exists here")
def test_a_priority_without_scheduling_policies_is_not_implemented() -> None:
    with pytest.raises(NotImplementedError, match="Linux"):
        prepare_realtime(10)
    assert sys.platform != "linux"
