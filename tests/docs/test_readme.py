"""The README's Python example runs as written and does what it says."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_python_example_tracks_the_goal_within_bounds(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "the README has a Python example"
    namespace: dict = {}
    exec(compile(blocks[0], "README.md", "exec"), namespace)
    model, q, goal, result = (namespace[k] for k in ("model", "q", "goal", "result"))
    assert np.all(np.isfinite(result.zeta))
    assert np.linalg.norm(model.frame_pose(q, "tool")[:3, 3] - goal) < 5e-3
    joints = model.split(q)[1]
    assert np.all(joints >= model.joint_lower - 1e-9) and np.all(joints <= model.joint_upper + 1e-9)
    assert "level 0" in capsys.readouterr().out


def _status_line(summary: str) -> str:
    return summary.splitlines()[0]


def test_readme_stack_reads_as_proven_from_its_first_step():
    """The README's stack, stopped after its first step: the printed summary says the command
    is proven (optimal or damped, each level met or unmet, proven), not a failure."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    namespace: dict = {}
    exec(compile(blocks[0].replace("range(100)", "range(1)"), "README.md", "exec"), namespace)
    result = namespace["result"]
    line = _status_line(result.summary())
    assert result.ok and result.stage == "primary", result.summary()
    assert re.search(r": (optimal|damped) \((every level met|levels? [0-9, ]+ unmet, proven "
                     r"optimal)\)", line), line
    for word in ("unproven", "backend_error", "fallback", "infeasible"):
        assert word not in line
    # the README says which entry starts on its bound, and why: the others are inside
    on_bound = np.flatnonzero((result.zeta <= result.lower) | (result.zeta >= result.upper))
    names = [namespace["model"].zeta_names[i] for i in on_bound]
    assert names == ["axis_c"], names
    assert "`axis_c`" in README.read_text()


def test_demo_summary_reads_as_success(tmp_path, capsys):
    """The README's first command prints the run's summary: every step proven optimal (the
    lower levels unmet by design), the statuses counted under one word, none that reads like
    a failure."""
    from uvms_qp.cli import main

    assert main(["run", "bluerov2_demo", "--out", str(tmp_path), "--no-plots"]) in (0, None)
    out = capsys.readouterr().out
    counts = [line for line in out.splitlines() if line.strip().startswith("status_counts")]
    assert counts, out
    statuses = dict(re.findall(r"([a-z_]+) (\d+)", counts[0].split("status_counts", 1)[1]))
    assert set(statuses) == {"optimal"}, counts[0]
    stages = [line for line in out.splitlines() if line.strip().startswith("stage_counts")]
    assert stages and "primary" in stages[0] and "zero" not in stages[0], stages


#: How far the README's test count may lag the collected count before this test asks for the
#: new number (tests added by later changes move it a little; a stale paragraph moves it more).
COUNT_TOLERANCE = 0.03


def test_readme_states_the_collected_number_of_tests():
    """The README says how many tests the suite has: the number ``pytest --collect-only``
    collects (within a few percent, so that adding a test does not fail the suite)."""
    stated = re.findall(r"The suite has (\d+)\s+tests", README.read_text())
    assert len(stated) == 1, "the README states the number of tests once"
    proc = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q",
                           "-p", "no:cacheprovider"], cwd=README.parent, capture_output=True,
                          text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stdout[-2000:]
    last = proc.stdout.strip().splitlines()[-1]
    collected = int(re.fullmatch(r"(\d+) tests collected.*", last).group(1))  # type: ignore[union-attr]
    assert abs(int(stated[0]) - collected) <= COUNT_TOLERANCE * collected, (
        f"the README says {stated[0]} tests, the suite collects {collected}: update the README "
        "with the last line of `python -m pytest --collect-only -q`")
