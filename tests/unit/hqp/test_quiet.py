"""Back-ends print nothing: HiGHS' first-construction banner must not reach the terminal."""

from __future__ import annotations

import subprocess
import sys

import pytest

from uvms_qp.hqp import available_solvers


@pytest.mark.skipif("cascade:highs" not in available_solvers(), reason="highspy not installed")
def test_highs_cascade_prints_no_banner():
    code = ("import numpy as np\n"
            "from uvms_qp.hqp import solve_hierarchy\n"
            "r = solve_hierarchy([[(np.eye(2), np.ones(2))]], solver='cascade:highs')\n"
            "print('status', r.status.value)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == "status optimal"
    assert "HiGHS" not in out.stderr
