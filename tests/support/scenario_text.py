"""Scenario-file text shared by the simulation tests: the BlueROV2 tool-reaching core."""

from __future__ import annotations

TOOL_CORE = """
[initial]
joints = [3.14159, 1.2, 1.7, 3.14159]

[[constraints]]
type = "joint_velocity_bounds"

[[constraints]]
type = "vehicle_rate_bounds"
linear = 0.2
angular = 0.2

[[levels]]
[[levels.tasks]]
type = "end_effector"
name = "tool"
position = [0.4911, 0.0990, -0.1675]
"""


def bluerov_scenario(header: str, tail: str) -> str:
    """``bluerov2_heavy_alpha5`` at dt 0.1 s: ``header`` (more top-level keys), the tool level
    of :data:`TOOL_CORE`, then ``tail`` (more levels, events, phases)."""
    return ('model = "bluerov2_heavy_alpha5"\ndt = 0.1\n' + header.strip() + "\n"
            + TOOL_CORE + tail)
