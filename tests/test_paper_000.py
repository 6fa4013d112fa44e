"""Paper 000 (Soylu et al.): Eq. (16) falls into the arm singularity, Eq. (21) and HQP do not.

Claims of ``000_7b5f597fe4e36aa4.txt``, Sections 3 and 4.4, as numbers on the bundled scenario
``paper000_quintic`` (set-up and chosen duration: docs/papers/000_soylu.md).
"""

import numpy as np
import pytest

from uvms_qp.sim.comparison import compare

RHO_BAR = 1.3


@pytest.fixture(scope="module")
def comparison():
    return compare("paper000_quintic")


def _first_time_below(run, level):
    rho = run.result.manipulability
    below = np.flatnonzero(rho < level)
    return float(run.result.time_states[below[0]]) if below.size else None


def test_all_schemes_track_the_tool(comparison):
    for run in comparison.runs:
        assert run.metrics["ee_error_max"] < 1e-2, run.name
        assert run.metrics["nan_steps"] == 0


def test_sr_task_priority_falls_near_singular_at_about_5_s(comparison):
    run = comparison.run("soylu_sr_task_priority")
    rho_min = run.metrics["min_manipulability"]
    assert 0.0 < rho_min < 0.1  # "never reaches the zero value ... but very poor"
    t_near = _first_time_below(run, 0.1)
    assert t_near is not None and 4.0 <= t_near <= 6.0
    # the arm ends stretched out: the tool at full reach (3 m) from the arm base
    assert run.metrics["tool_base_radius_max"] > 2.99


def test_dexterous_scheme_stays_above_the_shaping_band(comparison):
    dex = comparison.run("soylu_dexterous")
    srtp = comparison.run("soylu_sr_task_priority")
    assert dex.metrics["min_manipulability"] > RHO_BAR / 2
    assert dex.metrics["min_manipulability"] > 10 * srtp.metrics["min_manipulability"]
    # the shaping function engaged (k > 0) only while rho was below rho_bar
    k = dex.info["k"]
    rho = dex.info["manipulability"]
    assert np.all(k[rho >= RHO_BAR] == 0.0)
    assert k.max() > 0.0


def test_hqp_tracks_and_keeps_its_manipulability_floor(comparison):
    hqp = comparison.run("hqp")
    assert hqp.metrics["ee_error_max"] < 1e-2
    assert hqp.metrics["min_manipulability"] >= RHO_BAR - 1e-3
    assert hqp.metrics["bound_violation_max"] <= 1e-7
