"""Tiny sweeps on the bundled demo: a few runs of a few control steps each."""

from __future__ import annotations

import pytest

from tests.support.sweeps import write_sweep
from uvms_qp.sweep import load_sweep


@pytest.fixture
def tiny(tmp_path):
    """The spec of a 6-run sweep of 5 control steps per run."""
    return load_sweep(write_sweep(tmp_path))
