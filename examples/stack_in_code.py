"""Build a stack in Python (no scenario file) and run it in closed loop.

BlueROV2 Heavy + Reach Alpha 5: the tool draws a 5 cm circle in the horizontal plane while the
vehicle holds station; joint limits and rates, and vehicle rates, are hard bounds.

    python examples/stack_in_code.py [--out DIR]

With ``--out`` it writes ``results.json`` and the figures, like ``uvms-qp run``.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

import uvms_qp
from uvms_qp import Level, Stack
from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds, VehicleRateBounds
from uvms_qp.sim import CircleTrajectory, Scenario, plot_results, simulate, write_results
from uvms_qp.tasks import (
    EndEffectorTask,
    JointLimitTask,
    ManipulabilityTask,
    StationKeepingTask,
    VehicleAttitudeTask,
)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="write results.json and figures here")
    args = parser.parse_args(argv)

    model = uvms_qp.load_model("bluerov2_heavy_alpha5")
    # eta = [x, y, z, phi, theta, psi] [m, rad]; joints [rad]
    q0 = model.configuration(np.zeros(6), [math.pi, 1.2, 1.7, math.pi])
    start = model.frame_pose(q0, "tool")[:3, 3]                            # T_world_tool origin [m]

    radius = 0.05                                                          # [m]
    circle = CircleTrajectory(
        center=start - [radius, 0.0, 0.0], radius=radius, duration=8.0, turns=1.0,
        start_angle=0.0, start_time=1.0,                                  # starts at the tool
    )
    stack = Stack(
        constraints=[JointPositionBounds(gain=0.5), JointVelocityBounds(),
                     VehicleRateBounds(linear=0.3, angular=0.3)],          # [m/s], [rad/s]
        levels=[
            Level(JointLimitTask(mode="margin", margin=0.1),               # [rad]
                  ManipulabilityTask(mode="floor", minimum=0.001)),        # [m^3]
            Level(EndEffectorTask("tool", trajectory=circle, gain=2.0)),   # [1/s]
            Level(VehicleAttitudeTask()),
            Level(StationKeepingTask(gain=0.5)),                           # [1/s]
        ],
    )
    scenario = Scenario.build(
        model, stack, q0, dt=0.05, duration=10.0,                          # [s]
        metric=[10.0] * 6 + [1.0] * 4,   # vehicle rates cost 10x joint rates
        name="stack_in_code",
    )
    result = simulate(scenario)
    metrics = result.metrics()
    print(f"tool error max {metrics['ee_error_max'] * 1e3:.3f} mm, "
          f"vehicle displacement max {metrics['vehicle_displacement_max'] * 1e3:.3f} mm, "
          f"min manipulability {metrics['min_manipulability']:.4g}, "
          f"median step {metrics['step_time_median_us']:.0f} us")
    if args.out:
        print("wrote", write_results(result, args.out))
        plot_results(result, args.out)
    return metrics


if __name__ == "__main__":
    main()
