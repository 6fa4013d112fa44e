"""The papers' own figures: one set per bundled paper model, written by every comparison."""

import pytest

from tests.support.paper_scenarios import variant
from uvms_qp.sim.comparison import compare
from uvms_qp.sim.comparison_figures import plot_comparison
from uvms_qp.sim.paper_figures import plot_paper_figures
from uvms_qp.sim.scenario import load_scenario

FILES = {
    "paper000_quintic": ["paper000_configurations.png", "paper000_states.png",
                         "paper000_manipulability.png"],
    "paper001_circle": ["paper001_configurations.png", "paper001_states.png"],
    "paper002_line_constant_arm_angle": ["paper002_end_point.png"],
    "paper003_case3_payload": ["paper003_hqp.png", "paper003_wang_fuzzy_gradient_projection.png",
                               "paper003_wang_fuzzy_gradient_projection_euclidean.png",
                               "paper003_payload.png"],
}


def _short(name, duration):
    return compare(variant(name, duration=duration))


@pytest.mark.parametrize("name", sorted(FILES))
def test_paper_figures_are_written_for_each_paper_model(name, tmp_path):
    scenario = load_scenario(name)
    comparison = _short(name, 20 * scenario.dt)
    paths = plot_paper_figures(comparison, scenario.model, tmp_path)
    assert sorted(p.name for p in paths) == sorted(FILES[name])
    for path in paths:
        assert path.is_file() and path.stat().st_size > 10_000


def test_comparison_figures_include_the_paper_figures(tmp_path):
    scenario = load_scenario("paper002_line_constant_arm_angle")
    paths = plot_comparison(_short(scenario.name, 0.05), scenario.model, tmp_path)
    assert "paper002_end_point.png" in {p.name for p in paths}


def test_other_models_get_no_paper_figure(tmp_path):
    scenario = load_scenario("bluerov2_demo")
    comparison = _short("bluerov2_demo", 2 * scenario.dt)
    assert plot_paper_figures(comparison, scenario.model, tmp_path) == []
