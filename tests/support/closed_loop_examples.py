"""Closed-loop examples whose command a vehicle and an arm must be able to follow.

The README's stack, and two arms (one built from a DH table, one from a URDF) with a goal 2 %
beyond their reach, whose elbows end at the stretched-arm singularity. They use only the
library's long-standing interface (model, stack, controller, integration), so that
``benchmarks/closed_loop_table.py`` can run them on an earlier version of the library too.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

import uvms_qp
from uvms_qp import Controller, Level, Model, Stack
from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.model import DHRow, Vehicle
from uvms_qp.tasks import EndEffectorTask, ManipulabilityTask, StationKeepingTask

#: Control period of the examples [s] (the README's).
DT = 0.05
URDF = Path(__file__).resolve().parent.parent / "data" / "three_joint_arm.urdf"
#: The README's rate bounds: vehicle linear [m/s] and angular [rad/s].
README_LINEAR, README_ANGULAR = 0.5, 0.3


def readme_model() -> Model:
    """The README's model."""
    return uvms_qp.load_model("bluerov2_heavy_alpha5")


def readme_goal(model: Model) -> np.ndarray:
    """The README's goal: 0.3 m ahead and 0.1 m to the side of the tool at home [m, world]."""
    return model.frame_pose(model.home(), "tool")[:3, 3] + [0.3, 0.1, 0.0]


def readme_stack(goal: np.ndarray, station: StationKeepingTask | None = None) -> Stack:
    """The README's stack, unchanged (``station`` replaces its station-keeping task)."""
    return Stack(
        constraints=[JointPositionBounds(), JointVelocityBounds(),
                     VehicleRateBounds(linear=README_LINEAR, angular=README_ANGULAR)],
        levels=[
            Level(EndEffectorTask("tool", position=goal, gain=2.0)),
            Level(ManipulabilityTask(mode="floor", minimum=0.001)),
            Level(station or StationKeepingTask(gain=1.0)),
        ],
    )


def readme_bounds(model: Model) -> np.ndarray:
    """The README stack's rate bound of each entry of zeta [m/s, rad/s] (the reversal scale)."""
    return np.array([README_LINEAR] * 3 + [README_ANGULAR] * 3 + list(model.joint_rate_limit))


def dh_arm() -> Model:
    """A three-joint arm from a standard DH table on a fixed base, elbow bent at home."""
    return Model.from_dh(
        [DHRow(a=0.0, alpha=math.pi / 2, d=0.1, lower=-2.0, upper=2.0, rate_limit=1.0),
         DHRow(a=0.3, lower=-1.5, upper=1.5, rate_limit=1.0),
         DHRow(a=0.25, lower=-2.0, upper=2.0, rate_limit=1.0)],
        vehicle=Vehicle("fixed"), mount={"xyz": [0.3, 0.0, 0.2]}, tool={"xyz": [0.05, 0.0, 0.0]},
        home=[0.3, 0.6, -1.0], name="dh_arm")


def urdf_arm() -> Model:
    """The three-joint arm of ``tests/data/three_joint_arm.urdf`` on a fixed base."""
    return Model.from_urdf(URDF, tool="gripper", vehicle=Vehicle("fixed"),
                           mount={"xyz": [0.3, 0.0, 0.2]}, home=[0.3, 0.6, 1.2], name="urdf_arm")


#: The near-singular examples: name -> (model builder, the frame at the shoulder).
ARMS = {"dh_arm": (dh_arm, "link1"), "urdf_arm": (urdf_arm, "upper_arm")}


def beyond_reach(model: Model, shoulder: str, factor: float = 1.02) -> tuple[np.ndarray, float]:
    """A goal ``factor`` times the arm's reach from its shoulder, off the arm's direction.

    Returns:
        The goal [m, world] and the reach [m] (shoulder to tool, last joint straight).
    """
    state = model.state(model.home())
    stretched = np.array(state.joints)
    stretched[-1] = 0.0
    extended = model.state(model.configuration(state.eta, stretched))
    reach = float(np.linalg.norm(extended.position("tool") - extended.position(shoulder)))
    direction = np.array([1.0, 0.3, -0.4]) / np.linalg.norm([1.0, 0.3, -0.4])
    return state.position(shoulder) + factor * reach * direction, reach


def arm_stack(goal: np.ndarray) -> Stack:
    """The tool task alone under the arm's position and rate bounds."""
    return Stack(constraints=[JointPositionBounds(), JointVelocityBounds()],
                 levels=[Level(EndEffectorTask("tool", position=goal, gain=2.0))])


def run(model: Model, stack: Stack, q: np.ndarray, steps: int, **options):
    """``steps`` closed-loop steps of the DAQP controller from ``q`` (kinematic integration).

    An offline run: no deadline unless ``options`` give one (the controller's default, the
    period, would let the machine's load decide which optional solves a step makes).

    Returns:
        ``(commands (steps, nv), step results, final configuration)``.
    """
    options.setdefault("deadline", None)
    controller = Controller(model, stack, solver="daqp", dt=DT, **options)
    commands, results = [], []
    for k in range(steps):
        result = controller.step(model.state(q), t=k * DT)
        commands.append(np.array(result.zeta, dtype=float))
        results.append(result)
        q = model.integrate(q, result.zeta, DT)
    return np.array(commands), results, q


def measured(example: str) -> dict:
    """Run one example (``"readme"`` or a name of :data:`ARMS`) for the benchmark's tables.

    Returns:
        JSON-ready: the commands sent (steps, nv), ``dt``, the names of zeta, the bound of each
        entry (the reversal scale), the final distance of the tool to the goal [m], the count of
        each step status, and the final roll and pitch [rad] (README) or the arm's reach [m].
    """
    if example == "readme":
        model = readme_model()
        goal = readme_goal(model)
        commands, results, q = run(model, readme_stack(goal), model.home(), 200)
        state = model.state(q)
        extra = {"bounds": readme_bounds(model).tolist(),
                 "roll": float(state.eta[3]), "pitch": float(state.eta[4])}
    else:
        make, shoulder = ARMS[example]
        model = make()
        goal, reach = beyond_reach(model, shoulder)
        commands, results, q = run(model, arm_stack(goal), model.home(), 200)
        state = model.state(q)
        extra = {"bounds": np.asarray(model.joint_rate_limit, dtype=float).tolist(),
                 "reach": reach}
    statuses: dict[str, int] = {}
    for result in results:
        statuses[str(result.status)] = statuses.get(str(result.status), 0) + 1
    return {"commands": commands.tolist(), "dt": DT, "names": list(model.zeta_names),
            "distance": float(np.linalg.norm(state.position("tool") - goal)),
            "statuses": statuses, **extra}


if __name__ == "__main__":  # python tests/closed_loop_examples.py EXAMPLE: its figures as JSON
    json.dump(measured(sys.argv[1]), sys.stdout)
