"""The README's Python example runs as written and does what it says."""

import re
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
