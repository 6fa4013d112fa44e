"""Scenario files: every invalid field is a ConfigError whose message starts with its path.

Also the command line: an invalid file exits non-zero with that message, no traceback, and no
results file. And a property: any single-field corruption of a valid scenario either loads (and
then runs safely) or raises ConfigError; no other exception escapes the loader.
"""

from __future__ import annotations

import copy
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.unit.tasks.test_validation import SPATIAL_MESSAGE
from uvms_qp.cli import main
from uvms_qp.errors import ConfigError, ScenarioWarning
from uvms_qp.schemes import build_scheme
from uvms_qp.sim.config import Table
from uvms_qp.sim.runner import simulate
from uvms_qp.sim.scenario import load_scenario, scenario_from_dict
from uvms_qp.tasks import TASK_TYPES

BASE = """
model = "bluerov2_heavy_alpha5"
dt = 0.1
duration = 1.0

[initial]
joints = [3.14159, 1.2, 1.7, 3.14159]

[current]
direction = 0.2

[trajectories.path]
type = "quintic"
start = [0.49, 0.10, -0.17]
goal = [0.45, 0.15, -0.14]
duration = 1.0

[[constraints]]
type = "joint_velocity_bounds"

[[levels]]
[[levels.tasks]]
type = "end_effector"
name = "tool"
trajectory = "path"
gain = 1.0

[[levels]]
[[levels.tasks]]
type = "manipulability"
mode = "floor"
minimum = 0.001
gain = 1.0

[[levels.tasks]]
type = "payload_moment"
name = "payload"
mode = "bound"
maximum = 0.5

[[levels.tasks]]
type = "current_alignment"
heading = "current"

[[events]]
time = 0.5
task = "payload"
update = { force = 10.0 }
"""


def load_text(text: str):
    return scenario_from_dict(tomllib.loads(text))


def test_the_base_scenario_is_valid():
    scenario = load_text(BASE)
    assert scenario.steps == 10
    assert scenario.tracking == "tool"
    assert scenario.events[0].update == {"force": 10.0}
    assert scenario.build_stack().task("current_alignment").heading == pytest.approx(0.2)


# (old text, new text, expected path, fragment of the message)
CASES = [
    # unknown keys
    ("dt = 0.1", "dt = 0.1\ndtt = 0.2", "dtt", "unknown key 'dtt'"),
    ("gain = 1.0\n\n[[levels]]", "gian = 1.0\n\n[[levels]]", "levels[0].tasks[0].gian",
     "unknown key 'gian' for task type 'end_effector'; known keys:"),
    ("direction = 0.2", "direction = 0.2\nspeeed = 1", "current.speeed", "unknown key"),
    ('type = "joint_velocity_bounds"', 'type = "joint_velocity_bounds"\nfoo = 1',
     "constraints[0].foo", "unknown key 'foo'"),
    ("duration = 1.0\n\n[[constraints]]", "duration = 1.0\nspeed = 2\n\n[[constraints]]",
     "trajectories.path.speed", "unknown key 'speed'"),
    ("update = { force = 10.0 }", "update = { mass = 10.0 }", "events[0].update.mass",
     "unknown parameter 'mass' of task 'payload'"),
    # unknown names
    ('type = "end_effector"', 'type = "end_efector"', "levels[0].tasks[0].type",
     "unknown task type 'end_efector'; known task types: " + ", ".join(sorted(TASK_TYPES))),
    ('type = "joint_velocity_bounds"', 'type = "joint_speed"', "constraints[0].type",
     "unknown constraint type 'joint_speed'; known constraint types:"),
    ('type = "quintic"', 'type = "spline"', "trajectories.path.type",
     "unknown trajectory type 'spline'; known trajectory types: circle, fixed, line, quintic"),
    ('trajectory = "path"', 'trajectory = "paht"', "levels[0].tasks[0].trajectory",
     "unknown trajectory 'paht'; known trajectories: path"),
    ('name = "tool"', 'name = "tool"\nframe = "ee2"', "levels[0].tasks[0].frame",
     "unknown frame 'ee2'; known frames: world, vehicle, arm_base, tool"),
    ('model = "bluerov2_heavy_alpha5"', 'model = "bluerov3"', "model",
     "unknown model 'bluerov3'; bundled models:"),
    ("dt = 0.1", 'dt = 0.1\nsolver = "gurobi"', "solver", "unknown or unavailable solver"),
    ('task = "payload"', 'task = "cargo"', "events[0].task", "unknown task 'cargo'"),
    # missing fields
    ('model = "bluerov2_heavy_alpha5"', "", "model", "missing required field 'model'"),
    ("duration = 1.0\n\n[initial]", "\n[initial]", "duration", "missing required field"),
    ('type = "end_effector"\n', "", "levels[0].tasks[0]", "missing required field 'type'"),
    ("goal = [0.45, 0.15, -0.14]\n", "", "trajectories.path", "missing required field 'goal'"),
    ("minimum = 0.001\n", "", "levels[1].tasks[0].minimum", "required in mode 'floor'"),
    ("update = { force = 10.0 }", "", "events[0]", "missing required field 'update'"),
    ('trajectory = "path"\n', "", "levels[0].tasks[0]", "task 'tool' has no target"),
    # wrong types
    ("dt = 0.1", 'dt = "fast"', "dt", "expected a positive number, got a string"),
    ("gain = 1.0\n\n[[levels]]", 'gain = "high"\n\n[[levels]]', "levels[0].tasks[0].gain",
     "expected"),
    ('mode = "floor"', "mode = 3", "levels[1].tasks[0].mode",
     "expected one of 'ascend', 'floor', 'shaping', got 3"),
    ("goal = [0.45, 0.15, -0.14]", 'goal = [0.45, "x", -0.14]', "trajectories.path.goal[1]",
     "expected a number, got a string"),
    ("joints = [3.14159, 1.2, 1.7, 3.14159]", "joints = 3.0", "initial.joints",
     "expected an array of numbers"),
    ("update = { force = 10.0 }", 'update = { force = "heavy" }', "events[0].update.force",
     "expected a number"),
    # out-of-range values
    ("dt = 0.1", "dt = 0.0", "dt", "expected a positive number, got 0.0"),
    ("duration = 1.0\n\n[initial]", "duration = -1.0\n\n[initial]", "duration",
     "expected a positive number"),
    ("minimum = 0.001\ngain = 1.0", "minimum = 0.001\ngain = -1.0", "levels[1].tasks[0].gain",
     "expected a positive number, got -1.0"),
    ("joints = [3.14159, 1.2, 1.7, 3.14159]", "joints = [3.14159, 1.2, 4.0, 3.14159]",
     "initial.joints[2]", "joint 'axis_c' = 4 is outside its limits"),
    ("joints = [3.14159, 1.2, 1.7, 3.14159]", "joints = [3.14159, 1.2, 1.7]", "initial.joints",
     "expected 4 numbers, got 3"),
    ("direction = 0.2", "direction = 0.2\ndrift = 1.5", "current.drift",
     "expected a value <= 1, got 1.5"),
    ("time = 0.5", "time = 5.0", "events[0].time", "expected a value <= 1, got 5.0"),
    ("update = { force = 10.0 }", "update = { force = -10.0 }", "events[0].update.force",
     "expected a non-negative number"),
    ("dt = 0.1", "dt = 0.1\nmetric = [1, 1, 1, 1, 1, 1, 1, 1, 1, 0]", "metric[9]",
     "expected a positive weight"),
    ("dt = 0.1", "dt = 0.1\nmetric = [1, 1]", "metric", "expected 10 numbers, got 2"),
    ("dt = 0.1\nduration = 1.0", "dt = 1e-6\nduration = 1e6", "duration", "steps; at most"),
    ("duration = 1.0\n\n[[constraints]]", "duration = 0.0\n\n[[constraints]]",
     "trajectories.path.duration", "expected a positive number"),
    ('heading = "current"\n', 'heading = "current"\n\n[[levels.tasks]]\ntype = "posture"\n'
     'posture = [10.0, 1.0, 1.0, 1.0]\n', "levels[1].tasks[3].posture",
     "joint 'axis_e' = 10 is outside its limits [0, 6.3]"),
    ('heading = "current"\n', 'heading = "current"\n\n[[levels.tasks]]\ntype = "posture"\n'
     'posture = [1.0, 1.0, 1.0, 1.0]\n\n[[events]]\ntime = 0.2\ntask = "posture"\n'
     'update = { posture = [1.0, 1.0, 1.0, -2.0] }\n', "events[0].update.posture",
     "joint 'axis_b' = -2 is outside its limits [0, 6.2]"),
    ("direction = 0.2", 'direction = 0.2\n\n[passive]\nmode = "restore"', "passive",
     "model 'bluerov2_heavy_alpha5' has no passive roll or pitch (its vehicle actuates roll and "
     "pitch, p and q), so [passive] would have no effect"),
    # structure
    ('name = "payload"', 'name = "tool"', "levels[1].tasks[1].name", "duplicate task name 'tool'"),
]


@pytest.mark.parametrize(("old", "new", "path", "fragment"), CASES)
def test_invalid_field_is_reported_with_its_path(old, new, path, fragment):
    assert old in BASE, old
    text = BASE.replace(old, new, 1)
    with pytest.raises(ConfigError) as info:
        load_text(text)
    assert info.value.path == path, str(info.value)
    assert str(info.value).startswith(f"{path}: ")
    assert fragment in str(info.value)


@pytest.mark.parametrize(
    ("edit", "path", "fragment"),
    [
        (lambda d: d.__setitem__("levels", 3), "levels", "expected an array of tables"),
        (lambda d: d.__setitem__("levels", []), "levels", "expected at least one level"),
        (lambda d: d["levels"][1].__setitem__("tasks", []), "levels[1].tasks",
         "expected at least one task"),
        (lambda d: d["levels"][0].__setitem__("weight", 2.0), "levels[0].weight",
         "unknown key 'weight'"),
        (lambda d: d.__setitem__("initial", [1, 2]), "initial", "expected a table"),
    ],
)
def test_invalid_structure(edit, path, fragment):
    data = tomllib.loads(BASE)
    edit(data)
    with pytest.raises(ConfigError) as info:
        scenario_from_dict(data)
    assert info.value.path == path, str(info.value)
    assert fragment in str(info.value)


def test_task_that_cannot_be_evaluated_is_caught_at_load_time():
    # a current-alignment task with neither a heading nor a direction
    text = BASE.replace('heading = "current"\n', "")
    with pytest.raises(ConfigError, match=r"^levels\[1\]\.tasks\[2\]: .*heading never set"):
        load_text(text)


CONTRADICTION = """
[[constraints]]
type = "linear_inequality"
A = [[1, 0, 0, 0, 0, 0, 0, 0, 0, 0]]
lower = [LOWER]
upper = [6.0]

[[constraints]]
type = "vehicle_rate_bounds"
linear = 0.3
angular = 0.3
"""


def test_hard_constraints_that_admit_no_command_are_refused_at_load_time():
    """A hard row ``u >= 5`` m/s against a surge bound of 0.3 m/s: every step would end
    ``hard_infeasible``; the loader says so, naming the two in conflict (not the joint rate
    bounds, which have nothing to do with it). ``u >= 0.2`` loads."""
    with pytest.raises(ConfigError, match=r"^constraints: the hard constraints "
                                          r"linear_inequality, vehicle_rate_bounds admit no "
                                          r"command together"):
        load_text(BASE + CONTRADICTION.replace("LOWER", "5.0"))
    load_text(BASE + CONTRADICTION.replace("LOWER", "0.2"))


def test_heading_from_current_needs_a_current():
    text = BASE.replace("[current]\ndirection = 0.2\n", "")
    with pytest.raises(ConfigError, match=r"^levels\[1\]\.tasks\[2\]\.heading: 'current' needs"):
        load_text(text)


def test_malformed_toml_names_file_line_and_column(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(BASE.replace("dt = 0.1", "dt = "))
    with pytest.raises(ConfigError, match=r"bad\.toml: malformed TOML: .*line 3"):
        load_scenario(bad)


def test_missing_file_and_unknown_bundled_name(tmp_path):
    with pytest.raises(ConfigError, match="scenario file not found"):
        load_scenario(tmp_path / "nothing.toml")
    with pytest.raises(ConfigError, match=r"bundled scenarios: .*bluerov2_demo"):
        load_scenario("no_such_scenario")


@pytest.fixture
def bad_file(tmp_path) -> Path:
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace("minimum = 0.001\ngain = 1.0", "minimum = 0.001\ngain = -1.0"))
    return path


def test_cli_rejects_invalid_scenario_without_writing(bad_file, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", str(bad_file), "--out", str(out)])
    captured = capsys.readouterr()
    assert code != 0
    assert "levels[1].tasks[0].gain: expected a positive number" in captured.err
    assert "Traceback" not in captured.err + captured.out
    assert not (out / "results.json").exists()


@pytest.mark.parametrize(
    ("options", "fragment"),
    [(["--solver", "gurobi"], "unknown solver 'gurobi'"),
     (["--duration", "-2"], "--duration: expected a positive number of seconds")],
)
def test_cli_rejects_bad_options_without_writing(options, fragment, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", "bluerov2_demo", "--out", str(out), "--quiet", *options])
    err = capsys.readouterr().err
    assert code == 2
    assert fragment in err and "Traceback" not in err
    assert not (out / "results.json").exists()


def test_cli_subprocess_exit_status_and_no_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("model = [")
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "uvms_qp", "run", str(bad), "--out", str(out)],
        capture_output=True, text=True, timeout=120, check=False,
    )
    assert proc.returncode == 2
    assert "malformed TOML" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (out / "results.json").exists()


# ---- property: corrupt one field at a time

DATA = tomllib.loads(BASE)


def _leaves(node, path=()):
    if isinstance(node, dict):
        for key, value in node.items():
            yield (*path, key)
            yield from _leaves(value, (*path, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield (*path, i)
            yield from _leaves(value, (*path, i))


PATHS = list(_leaves(DATA))
BAD_VALUES = st.sampled_from(
    ["x", "", -1, 0, -1.5, 1e9, math.nan, math.inf, -math.inf, True, [], [1, "a"], [[1.0]],
     {}, {"a": 1}, [0.1, 0.2, 0.3], "current", "tool", "DELETE"]
)


@settings(max_examples=150)
@given(st.sampled_from(PATHS), BAD_VALUES)
@pytest.mark.filterwarnings("ignore::uvms_qp.errors.ScenarioWarning")  # a moved start may load
def test_corrupted_field_loads_or_raises_config_error(path, value):
    data = copy.deepcopy(DATA)
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    if value == "DELETE":
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    try:
        scenario = scenario_from_dict(data)
    except ConfigError:
        return
    result = simulate(scenario, duration=3 * scenario.dt)
    metrics = result.metrics()
    assert metrics["nan_steps"] == 0
    assert metrics["bound_violation_max"] <= 1e-7


# ---- ranges: step count, control period, initial pose, file size and nesting


@pytest.mark.parametrize(("old", "new", "path", "fragment"), [
    ("dt = 0.1", "dt = 5e-324", "dt", "expected a control period in [1e-06, 10] s"),
    ("dt = 0.1", "dt = 11.0", "dt", "expected a control period in [1e-06, 10] s, got 11"),
    ("duration = 1.0\n\n[initial]", "duration = 1e308\n\n[initial]", "duration",
     "1e+308 s at dt = 0.1 s is over 1e308 steps; at most 2000000 are allowed"),
    ("duration = 1.0\n\n[initial]", "duration = 0.04\n\n[initial]", "duration",
     "0.04 s is shorter than one control period (dt = 0.1 s)"),
    ("joints = [3.14159", "eta = [1e300, 0, 0, 0, 0, 0]\njoints = [3.14159", "initial.eta[0]",
     "expected a magnitude <= 1e+06 [m or rad], got 1e+300"),
    ("joints = [3.14159", "eta = [0, 0, 0, 0, -2e6, 0]\njoints = [3.14159", "initial.eta[4]",
     "expected a magnitude <= 1e+06"),
])
def test_values_outside_the_documented_ranges_are_one_line_errors(old, new, path, fragment):
    with pytest.raises(ConfigError) as info:
        load_text(BASE.replace(old, new, 1))
    assert info.value.path == path, str(info.value)
    assert str(info.value).startswith(f"{path}: ") and fragment in str(info.value)


@pytest.mark.parametrize("value", [
    "[" * 1000 + "]" * 1000,                        # the parser would recurse past Python's limit
    "{ a = " * 400 + "1" + " }" * 400,
    "[" * 33 + "]" * 33,                            # parses, but deeper than documented
], ids=["arrays_1000", "inline_tables_400", "arrays_33"])
def test_deeply_nested_values_are_rejected_as_config_errors(tmp_path, value):
    path = tmp_path / "deep.toml"
    path.write_text(f"deep = {value}\n" + BASE)
    with pytest.raises(ConfigError, match=r"deep\.toml: arrays and tables nested more than 32"):
        load_scenario(path)


def test_nesting_up_to_the_limit_is_only_an_unknown_key(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("deep = " + "[" * 32 + "]" * 32 + "\n" + BASE)
    with pytest.raises(ConfigError, match=r"^deep: unknown key 'deep'"):
        load_scenario(path)


def test_a_file_larger_than_the_limit_is_rejected_before_parsing(tmp_path):
    path = tmp_path / "big.toml"
    path.write_text(BASE + "# " + "x" * (4 * 1024 * 1024) + "\n")
    with pytest.raises(ConfigError, match=r"big\.toml: larger than 4 MiB"):
        load_scenario(path)


def test_scenario_source_and_encoding(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="scenario"):
        load_scenario(None)  # type: ignore[arg-type]
    path = tmp_path / "latin1.toml"
    path.write_bytes(b"name = '\xe9'\n")
    with pytest.raises(ConfigError, match=r"latin1\.toml.*UTF-8"):
        load_scenario(path)


def test_scheme_for_the_wrong_model_kind_is_named_once():
    scenario = load_scenario("bluerov2_demo")
    with pytest.raises(ConfigError) as info:
        build_scheme("soylu_dexterous", scenario, "schemes[1]")
    message = str(info.value)
    assert message.count("soylu_dexterous") == 1, message
    assert message.startswith("schemes[1]: scheme 'soylu_dexterous': ")
    assert "'planar'" in message and "'spatial'" in message


@pytest.mark.parametrize(("listed", "index"), [
    (["soylu_sr_task_priority"], 0),
    (["soylu_sr_task_priority", "hqp"], 0),
    (["hqp", "soylu_sr_task_priority"], 1),
])
def test_a_scheme_s_error_names_its_place_in_the_file_s_list(tmp_path, listed, index):
    # hqp, compared even when not listed, does not count toward the index
    demo = Path(load_scenario("bluerov2_demo").source).read_text()
    path = tmp_path / "s.toml"
    path.write_text(demo.replace("[initial]", f"schemes = {listed!r}\n\n[initial]", 1)
                    .replace("'", '"'))
    with pytest.raises(ConfigError) as info:
        load_scenario(path)
    assert str(info.value).split(": ")[0] == f"schemes[{index}]", str(info.value)
    assert "needs a model with vehicle kind 'planar'" in str(info.value)


# ------------------------------------------ unknown before missing keys, helpful messages
def replaced(old: str, new: str) -> str:
    assert old in BASE, old
    return BASE.replace(old, new)


@pytest.mark.parametrize(
    ("start", "goal", "path"),
    [
        ("[0.4911, 0.0990]", "[0.45, 0.15, -0.14]", "trajectories.path.goal"),
        ("[0.4911, 0.0990]", "[0.45, 0.15]", "levels[0].tasks[0].trajectory"),
    ],
)
def test_scenario_with_a_two_coordinate_trajectory_is_rejected(start, goal, path):
    text = replaced("start = [0.49, 0.10, -0.17]\ngoal = [0.45, 0.15, -0.14]",
                    f"start = {start}\ngoal = {goal}")
    with pytest.raises(ConfigError) as info:
        load_text(text)
    assert info.value.path == path, str(info.value)
    assert str(info.value).startswith(path + ": ")


@pytest.mark.parametrize(
    ("old", "new", "path", "fragment"),
    [
        ("duration = 1.0\n\n[initial]", "durration = 1.0\n\n[initial]", "durration",
         "unknown key 'durration' (did you mean 'duration'?); known keys: constraints,"),
        ("duration = 1.0\n\n[initial]", "length = 1.0\n\n[initial]", "length",
         "unknown key 'length'; known keys:"),
        ('model = "bluerov2_heavy_alpha5"', 'modle = "bluerov2_heavy_alpha5"', "modle",
         "unknown key 'modle' (did you mean 'model'?)"),
        ("time = 0.5", "tiem = 0.5", "events[0].tiem",
         "unknown key 'tiem' (did you mean 'time'?); known keys: task, time, update"),
        ("direction = 0.2", "directon = 0.2", "current.directon",
         "unknown key 'directon' (did you mean 'direction'?)"),
        ('type = "end_effector"', 'tpye = "end_effector"', "levels[0].tasks[0].tpye",
         "unknown key 'tpye' (did you mean 'type'?)"),
        ("goal = [0.45, 0.15, -0.14]", "gaol = [0.45, 0.15, -0.14]", "trajectories.path.gaol",
         "unknown key 'gaol' for trajectory type 'quintic'"),
    ],
)
def test_a_misspelt_required_key_is_named_as_unknown(old, new, path, fragment):
    with pytest.raises(ConfigError) as info:
        load_text(replaced(old, new))
    assert info.value.path == path, str(info.value)
    assert fragment in str(info.value)


def test_a_truly_missing_key_is_still_reported_as_missing():
    with pytest.raises(ConfigError, match=r"^duration: missing required field 'duration'"):
        load_text(replaced("duration = 1.0\n\n[initial]", "\n[initial]"))
    # an unrelated unread key of an undeclared table is not mistaken for the missing one
    table = Table({"colour": 1}, "thing")
    with pytest.raises(ConfigError, match=r"^thing: missing required field 'size'"):
        table.take_number("size", required=True)
    declared = Table({"colour": 1}, "thing", keys=("size",))
    with pytest.raises(ConfigError, match=r"^thing\.colour: unknown key 'colour'; known keys: s"):
        declared.take_number("size", required=True)


def test_heading_string_other_than_current_says_what_is_allowed():
    with pytest.raises(ConfigError) as info:
        load_text(replaced('heading = "current"', 'heading = "curent"'))
    assert info.value.path == "levels[1].tasks[2].heading"
    assert "expected a number [rad] or the string 'current'" in str(info.value)
    assert "got 'curent'" in str(info.value)


EVENT = '\n\n[[events]]\ntime = 0.5\ntask = "tool"\nupdate = {{ {} }}'


@pytest.mark.parametrize(
    ("update", "path"),
    [
        ("position = [0.5, 0.1]", "events[1].update.position"),
        ("trajectory = { type = 'line', start = [0.5, 0.1], goal = [0.5, 0.2], duration = 1.0 }",
         "events[1].update.trajectory"),
    ],
)
def test_event_update_needing_the_model_carries_the_event_path(update, path):
    text = replaced("update = { force = 10.0 }",
                    "update = { force = 10.0 }" + EVENT.format(update))
    with pytest.raises(ConfigError) as info:
        load_text(text)
    assert info.value.path == path, str(info.value)
    assert str(info.value).startswith(f"{path}: {SPATIAL_MESSAGE}")


def test_event_update_with_three_coordinates_loads():
    text = replaced("update = { force = 10.0 }",
                    "update = { force = 10.0 }" + EVENT.format("position = [0.5, 0.1, 0.2]"))
    scenario = load_text(text)
    assert scenario.events[1].update == {"position": [0.5, 0.1, 0.2]}


def test_a_mistyped_bundled_scenario_name_suggests_the_close_one():
    with pytest.raises(ConfigError, match=r"unknown scenario 'bluerov_demo' \(did you mean "
                                          r"'bluerov2_demo'\?\)"):
        load_scenario("bluerov_demo")


def test_a_scenario_without_initial_starts_at_the_models_home():
    """Not at zero joint angles clipped into the limits (a singular arm for some models)."""
    data = tomllib.loads(BASE)
    del data["initial"]
    # the tool path was written to start at [initial]'s tool: loading says so
    with pytest.warns(ScenarioWarning, match="its trajectory starts 0.114 m from the frame"):
        scenario = scenario_from_dict(data)
    np.testing.assert_array_equal(scenario.q0, scenario.model.home())
    assert not np.array_equal(scenario.q0, scenario.model.neutral())


def test_a_task_key_of_another_mode_names_the_keys_of_this_mode():
    data = tomllib.loads(BASE)
    data["levels"][1]["tasks"][1]["normalize"] = True  # a key of the "reduce" payload task
    with pytest.raises(ConfigError, match=r"levels\[1\]\.tasks\[1\]\.normalize: unknown key "
                                          r"'normalize'.*maximum"):
        scenario_from_dict(data)
