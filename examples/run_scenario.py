"""Load a scenario file (here the bundled demo), run it, and read its metrics per phase.

    python examples/run_scenario.py [SCENARIO]

The same as ``uvms-qp run SCENARIO --out DIR`` without writing files, to show the Python API:
:func:`uvms_qp.sim.load_scenario` validates the file, :func:`uvms_qp.sim.simulate` runs it.
"""

from __future__ import annotations

import sys

from uvms_qp.sim import load_scenario, simulate


def main(argv: list[str] | None = None) -> dict:
    args = sys.argv[1:] if argv is None else argv
    scenario = load_scenario(args[0] if args else "bluerov2_demo")
    print(f"{scenario.name}: {scenario.model.name}, {len(scenario.task_names)} levels, "
          f"{scenario.steps} steps of {scenario.dt} s, solver {scenario.solver}")
    for k, names in enumerate(scenario.task_names, start=1):
        print(f"  level {k}: " + ", ".join(names))
    result = simulate(scenario)
    phases = result.phase_metrics()
    for name, metrics in phases.items():
        print(f"  {name:>14}: tool error max {metrics['ee_error_max'] * 1e3:6.3f} mm, "
              f"vehicle moved {metrics['vehicle_displacement_max']:.3f} m")
    metrics = result.metrics()
    print(f"  bound violation max {metrics['bound_violation_max']:.2e}, "
          f"NaN steps {metrics['nan_steps']}")
    return metrics


if __name__ == "__main__":
    main()
