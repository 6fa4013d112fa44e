"""Static typing of modules whose hot paths narrow optional attributes by hand."""

from pathlib import Path

import pytest

mypy_api = pytest.importorskip("mypy.api")

ROOT = Path(__file__).resolve().parents[2]


def test_current_alignment_type_checks(tmp_path):
    # The fill fast path reads the optional heading; mypy must see it narrowed to float.
    out, err, status = mypy_api.run([
        "--config-file", str(ROOT / "pyproject.toml"), "--cache-dir", str(tmp_path),
        str(ROOT / "uvms_qp" / "tasks" / "current_alignment.py"),
    ])
    assert status == 0, out + err
