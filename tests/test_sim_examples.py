"""Every example runs headless; every TOML block of docs/scenarios.md is a valid scenario."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

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
    blocks = [b for b in _toml_blocks() if "model =" in b]
    assert blocks
    for block in blocks:
        scenario = scenario_from_dict(tomllib.loads(block))
        assert scenario.steps > 0
