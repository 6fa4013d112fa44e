"""A back-end forced to fail is a counted, attributed failure, never a crash or a silent drop."""

from __future__ import annotations

import json

import numpy as np
import pytest

from uvms_qp.bench import runners
from uvms_qp.bench.runners import HqpRunner
from uvms_qp.cli import main
from uvms_qp.hqp import HierarchySolver

TINY = ["--scenarios", "paper001_circle", "--max-steps", "3", "--random-count", "2",
        "--raw-count", "1", "--repetitions", "2", "--no-progress"]


class _Broken:
    """Wraps a real solver and corrupts its answers in one of three ways."""

    def __init__(self, mode):
        self.inner = HierarchySolver("daqp")
        self.mode = mode
        self.name = "broken"

    def solve(self, levels, lower=None, upper=None, hard=None):
        if self.mode == "raise":
            raise RuntimeError("back-end exploded")
        result = self.inner.solve(levels, lower, upper, hard)
        if self.mode == "nan":
            result.x = np.full_like(result.x, np.nan)
        elif self.mode == "lie":  # claims success, breaks the box
            result.x = result.x + 10.0 * (np.abs(upper) + 1.0)
        return result


class BrokenRunner(HqpRunner):
    def __init__(self, mode):
        super().__init__("daqp")
        self.name = f"broken-{mode}"
        self.mode = mode

    def _raw_solver(self, problem):
        return _Broken(self.mode)

    def _uvms_controller(self, draw):
        if self.mode == "raise":
            raise RuntimeError("controller set-up exploded")
        return super()._uvms_controller(draw)

    def _scenario_controller(self, scenario, stack):
        raise RuntimeError("no scenario for you")


@pytest.mark.parametrize("mode,reason", [("raise", "exception:RuntimeError"), ("nan", "nan"),
                                         ("lie", "hard_violation")])
def test_failing_backend_is_counted_and_attributed(monkeypatch, tmp_path, capsys, mode, reason):
    monkeypatch.setitem(runners.EXTRA_RUNNERS, f"broken-{mode}", lambda: BrokenRunner(mode))
    js = tmp_path / "b.json"
    code = main(["bench", *TINY, "--sets", "raw", "scenarios", "--solvers", "daqp",
                 f"broken-{mode}", "--json", str(js)])
    assert code == 0
    records = json.loads(js.read_text())["records"]
    raw = [r for r in records if r["solver"] == f"broken-{mode}" and r["set"] == "raw"]
    assert len(raw) == 9  # 3 sizes x 3 bound kinds x 1
    for r in raw:
        assert r["trials"] == 2 and r["successes"] == 0 and r["failures"] == {reason: 2}
    if mode == "nan":
        assert all(r["nan_count"] == 2 for r in raw)
    if mode == "lie":
        assert all(r["claimed_violation"] > 1.0 for r in raw)
    # the scenario set-up failure counts every planned step
    scen = [r for r in records if r["solver"] == f"broken-{mode}" and r["set"] == "scenarios"]
    assert scen[0]["trials"] == 3 and scen[0]["failures"] == {"exception:RuntimeError": 3}
    assert "no scenario for you" in scen[0]["note"]
    # the healthy solver in the same run is untouched
    daqp = [r for r in records if r["solver"] == "daqp"]
    assert all(r["successes"] == r["trials"] > 0 for r in daqp)
    out = capsys.readouterr().out
    assert f"broken-{mode}" in out and reason in out and "failed of" in out
