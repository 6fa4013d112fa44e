"""Sweep texts for the tests: a tiny sweep of the bundled demo (a few runs of five steps)."""

from __future__ import annotations

import textwrap
from pathlib import Path

TINY = """
scenario = "bluerov2_demo"
runs = {runs}
seed = 11
duration = 0.25

[current]
direction = {{ uniform = [-0.5, 0.5] }}
drift = {{ uniform = [0.0, 0.5] }}
speed = 0.2

[sensors]
position_noise = {{ uniform = [0.0, 0.01] }}
delay = {{ choice = [0.0, 0.05] }}

[initial]
joints = {{ normal = [0.0, 0.02], within = [-0.05, 0.05] }}

[payload]
mass = {{ uniform = [0.0, 3.0] }}

[success]
ee_error_max = {{ max = 0.01 }}
"level_met_share.0" = {{ min = 0.99 }}
"""


def write_sweep(folder: Path, runs: int = 6, text: str = TINY, name: str = "tiny.toml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text.format(runs=runs)))
    return path


DYNAMIC = """
scenario = "bluerov2_demo"
plant = "dynamic"
runs = {runs}
seed = 5
duration = 0.5

[plant_parameters]
set = {{ choice = ["bluerov2_heavy_von_benzon_2022", "bluerov2_wu_2018"] }}
"vehicle.added_mass" = {{ uniform = [-0.5, 0.5] }}
"links.mass" = {{ uniform = [-0.2, 0.2] }}

[sensors]
position_noise = 0.01
linear_rate_noise = {{ uniform = [0.0, 0.02] }}

[payload]
mass = {{ uniform = [1.0, 4.0] }}
volume = 0.0005

[success]
pitch_max = {{ max = 0.1 }}
"""
