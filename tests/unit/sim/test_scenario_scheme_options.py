"""``[scheme_options.<scheme>]``: keyword arguments of a listed closed-form scheme, checked."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from uvms_qp.errors import ConfigError
from uvms_qp.schemes import build_scheme
from uvms_qp.sim.comparison import compare
from uvms_qp.sim.config import read_toml
from uvms_qp.sim.scenario import resolve_scenario, scenario_from_dict

PAPER002 = read_toml(resolve_scenario("paper002_line_constant_arm_angle"))
PAPER000 = read_toml(resolve_scenario("paper000_quintic"))


def with_options(data: dict, options: str, **top) -> dict:
    return {**data, **top, **tomllib.loads(options)}


def test_options_reach_the_scheme_and_change_its_run():
    plain = scenario_from_dict({**PAPER002, "duration": 0.2})
    flipped = scenario_from_dict(with_options(PAPER002, """
        [scheme_options.nenchev_sc]
        b_ep = -1.0
    """, duration=0.2))
    assert dict(flipped.scheme_options) == {"nenchev_sc": {"b_ep": -1.0}}
    assert build_scheme("nenchev_sc", plain).b_ep == 1.0
    assert build_scheme("nenchev_sc", flipped).b_ep == -1.0
    start = plain.model.frame_pose(plain.q0, "tool")[0, 3]
    x_plain = compare(plain, ["nenchev_sc"]).run("nenchev_sc").result.ee_position[-1, 0]
    x_flipped = compare(flipped, ["nenchev_sc"]).run("nenchev_sc").result.ee_position[-1, 0]
    # the end-point moves along the line in the direction of b_ep: opposite ways
    assert (x_plain - start) * (x_flipped - start) < 0.0


def test_options_override_what_the_scheme_takes_from_the_scenario():
    scenario = scenario_from_dict(with_options(PAPER000, """
        [scheme_options.soylu_dexterous]
        weights = [1.0, 1.0, 1.0, 2.0, 2.0, 2.0]
        rho_bar = 1.5
    """))
    dexterous = build_scheme("soylu_dexterous", scenario)
    np.testing.assert_array_equal(dexterous.weights, [1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
    assert dexterous.rho_bar == 1.5
    # the other scheme still takes the scenario's metric W
    np.testing.assert_array_equal(build_scheme("soylu_sr_task_priority", scenario).weights,
                                  scenario.metric)


@pytest.mark.parametrize(("options", "path", "fragment"), [
    ("[scheme_options.nenchev_sc]\nbep = -1.0", "scheme_options.nenchev_sc.bep",
     "unknown key 'bep' for scheme 'nenchev_sc'; known keys: direction, b_ep"),
    ("[scheme_options.nenchev_sc]\nbep = -1.0", "scheme_options.nenchev_sc.bep",
     "did you mean 'b_ep'?"),
    ('[scheme_options.nenchev_sc]\nb_ep = "minus one"', "scheme_options.nenchev_sc.b_ep",
     "expected a number, got a string"),
    ("[scheme_options.nenchev_sc]\nd3 = -1.0", "scheme_options.nenchev_sc.d3",
     "expected a positive"),
    ("[scheme_options.nenchev_sc]\ndirection = [0.0, 0.0, 0.0]",
     "scheme_options.nenchev_sc.direction", "non-zero vector"),
    ('[scheme_options.nenchev_sc]\nname = "other"', "scheme_options.nenchev_sc.name",
     "unknown key 'name'"),
    ("[scheme_options.nenchev_sc_self_motion]\nb_sm = 1.0",
     "scheme_options.nenchev_sc_self_motion", "which 'schemes' does not list"),
    ("[scheme_options.hqp]\nsolver = 'daqp'", "scheme_options.hqp", "takes no scheme options"),
    ("[scheme_options]\nnenchev_sc = 3", "scheme_options.nenchev_sc", "expected a table"),
    ("scheme_options = 3", "scheme_options", "expected a table"),
])
def test_bad_options_name_their_field(options, path, fragment):
    with pytest.raises(ConfigError) as info:
        scenario_from_dict(with_options(PAPER002, options))
    assert info.value.path == path, str(info.value)
    assert fragment in str(info.value)


def test_unknown_scheme_suggests_a_close_name():
    with pytest.raises(ConfigError, match=r"^schemes\[0\]: unknown scheme 'nenchev'.*"
                                          r"did you mean 'nenchev_sc'\?"):
        scenario_from_dict({**PAPER002, "schemes": ["nenchev"]})
