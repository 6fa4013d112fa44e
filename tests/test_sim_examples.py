"""Every example runs headless; the scenarios and Python code of the docs load and run."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from uvms_qp.model import unregister_model
from uvms_qp.sim.scenario import scenario_from_dict

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
DOC = ROOT / "docs" / "scenarios.md"


@pytest.mark.parametrize("example", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_headless(example, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, str(example)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip()


def test_there_are_examples():
    assert EXAMPLES


def _toml_blocks() -> list[str]:
    return re.findall(r"```toml\n(.*?)```", DOC.read_text(), flags=re.DOTALL)


def test_documented_scenarios_load():
    blocks = [b for b in _toml_blocks() if "model =" in b or "[model]" in b]
    assert len(blocks) >= 2
    for block in blocks:
        scenario = scenario_from_dict(tomllib.loads(block), source=DOC)  # paths from docs/
        assert scenario.steps > 0


@pytest.mark.parametrize("page", ["scenarios.md", "models.md"])
def test_documented_python_runs(page, monkeypatch):
    monkeypatch.chdir(ROOT)  # the examples name files of the repository
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / page).read_text(),
                        flags=re.DOTALL)
    assert blocks
    try:
        for block in blocks:
            exec(compile(block, page, "exec"), {"__name__": f"docs_{page}"})
    finally:
        for name in ("my_rov", "holdout_rov"):  # the names the pages register
            unregister_model(name)
