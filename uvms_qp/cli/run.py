"""``uvms-qp run SCENARIO --out DIR``: run a scenario, write ``results.json`` and figures.

``SCENARIO`` is a TOML file or the name of a bundled scenario (``uvms-qp run bluerov2_demo``;
``uvms-qp scenarios`` lists them). The scenario and the options are fully validated before
anything is written: an invalid file or option exits with status 2 and a one-line message
carrying the field path, without a traceback and without creating ``DIR/results.json``.
``--duration`` obeys the scenario's limits (at least one control period, at most 2 000 000
steps); the run takes ``round(duration / dt)`` steps and says so. ``DIR`` is created before the
simulation starts: an unusable ``--out`` (an existing file, a place that cannot be written)
fails at once the same way.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..errors import ConfigError, UnknownSolverError
from ._common import (
    output_directory,
    print_warnings,
    register_model_paths,
    run_warnings,
    scenario_command,
    writing_output,
)


def _options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--solver", help="override the scenario's solver (e.g. cascade:osqp)")
    parser.add_argument("--duration", type=float,
                        help="override the simulated time [s] (at least one control period)")
    parser.add_argument("--plant", choices=("kinematic", "dynamic"),
                        help="override the scenario's plant: 'dynamic' runs the controller on a "
                             "floating vehicle (thrusters, hydrodynamics, the arm's reaction) "
                             "and reports it next to the kinematic run")
    parser.add_argument("--view", metavar="HTML",
                        help="also write a 3-D animation of the run as one self-contained HTML "
                             "file (needs plotly: pip install 'uvms-qp[view]')")


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``run`` sub-command to the ``uvms-qp`` parser."""
    return scenario_command(
        subparsers, "run",
        help="run a scenario (bundled name or TOML file): results.json + figures",
        description=__doc__, func=run, quiet_help="no progress bar, no summary",
        options=_options,
    )


def _summary(metrics: dict[str, Any]) -> str:
    keys = (
        ("ee_error_max", "m"),
        ("ee_error_rms", "m"),
        ("min_manipulability", ""),
        ("vehicle_displacement_max", "m"),
        ("vehicle_yaw_error_final", "rad"),
        ("joint_limit_violation_max", "rad"),
        ("bound_violation_max", ""),
        ("payload_moment_max", "N m"),
        ("payload_objective_max", "N m^2"),
        ("command_reversals_per_s_max", "1/s"),
        ("step_time_median_us", "us"),
        ("step_time_p99_us", "us"),
        ("nan_steps", ""),
        ("stage_counts", ""),
        ("status_counts", ""),
    )
    lines = []
    for key, unit in keys:
        if key in metrics and metrics[key] is not None:
            value = metrics[key]
            if isinstance(value, dict):  # counts per stage or status
                text = ", ".join(f"{name} {count}" for name, count in value.items())
            else:
                text = f"{value:.4g}" if isinstance(value, float) else str(value)
            worst = metrics.get("command_reversals_worst_axis")
            if key == "command_reversals_per_s_max" and worst is not None:
                text += f" ({worst})"
            lines.append(f"  {key:<28} {text} {unit}".rstrip())
    for unit, value in (metrics.get("command_change_max") or {}).items():
        lines.append(f"  {'command_change_max':<28} {value:.4g} {unit}")
    for task, value in (metrics.get("settling_time") or {}).items():
        text = "not settled" if value is None else f"{value:.4g} s"
        lines.append(f"  {'settling_time ' + task:<28} {text}")
    return "\n".join(lines)


#: Metrics of a dynamic run printed next to the kinematic run's: (key, unit).
DYNAMIC_KEYS = (
    ("ee_error_rms", "m"),
    ("ee_error_max", "m"),
    ("ee_error_final", "m"),
    ("bound_violation_max", ""),
    ("roll_max", "rad"),
    ("pitch_max", "rad"),
    ("saturation_share_max", ""),
    ("energy", "J"),
    ("unmet_force_max", "N"),
    ("unmet_moment_max", "N m"),
    ("payload_mass", "kg"),
    ("payload_rating_share", ""),
)


def plant_line(settings: dict[str, Any]) -> str:
    """One line naming what a dynamic run drove: parameter set, feed-forward, coordination."""
    voltage = settings.get("supply_voltage")
    rates = [f"physics {settings['physics_step']:g} s", f"servos {settings['servo_rate']:g} Hz"]
    if voltage is not None:
        rates.append(f"thrusters at {voltage:g} V")
    return (f"plant: dynamic, parameter set {settings['parameters']}, feed-forward "
            f"{settings['feedforward']}, coordination "
            f"{'on' if settings['coordination'] else 'off'} ({', '.join(rates)})")


def dynamic_summary(dynamic: dict[str, Any], kinematic: dict[str, Any]) -> str:
    """The dynamic run's metrics beside the kinematic run's, then the per-axis and per-part ones."""
    lines = [f"  {'on the floating vehicle':<28} {'dynamic':>12} {'kinematic':>12}"]
    for key, unit in DYNAMIC_KEYS:
        if key not in dynamic and key not in kinematic:
            continue
        cells = []
        for metrics in (dynamic, kinematic):
            value = metrics.get(key)
            cells.append("-" if value is None else f"{value:.4g}")
        lines.append(f"  {key:<28} {cells[0]:>12} {cells[1]:>12} {unit}".rstrip())
    for key, unit in (("velocity_tracking_error_rms", "m/s, rad/s"), ("thrust_max", "N"),
                      ("saturation_share", ""), ("joint_torque_max", "N m")):
        values = dynamic.get(key)
        if values:
            text = ", ".join(f"{name} {value:.3g}" for name, value in values.items())
            lines.append(f"  {key:<28} {text} {unit}".rstrip())
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Load, validate, simulate; write ``results.json`` and the figures into ``args.out``."""
    from ..sim.plots import plot_results
    from ..sim.results import write_results
    from ..sim.runner import simulate
    from ..sim.scenario import load_scenario
    from ..sim.view import INSTALL_HINT, plotly_available, write_view

    register_model_paths(args)
    scenario = load_scenario(args.scenario)
    if args.duration is not None:
        scenario = scenario.with_duration(args.duration, "--duration")
    if args.plant is not None:
        scenario = scenario.with_plant(args.plant, "--plant")
    if args.view and not plotly_available():
        raise ConfigError(f"the 3-D view needs plotly: {INSTALL_HINT}", "--view")
    try:
        scheme = scenario.make_controller(args.solver) if args.solver else None
    except UnknownSolverError as exc:
        raise ConfigError(str(exc), "--solver") from None
    with output_directory(args.out):
        result = simulate(scenario, scheme, progress=not args.quiet)
        if args.solver:
            result.solver = args.solver
        reference = None
        if result.plant == "dynamic":
            kinematic = scenario.with_plant("kinematic")
            reference = simulate(kinematic, kinematic.make_controller(args.solver)
                                 if args.solver else None)
        with writing_output(args.out):
            path = write_results(result, args.out, reference=reference)
            figures = [] if args.no_plots else plot_results(result, args.out,
                                                            progress=not args.quiet,
                                                            reference=reference)
        if args.view:
            try:
                view = write_view(scenario.model, result, args.view)
            except OSError as exc:
                raise ConfigError(f"cannot write {args.view!r}: {exc.strerror or exc}",
                                  "--view") from None
    if result.stopped is not None:
        stop = result.stopped
        print(f"error: the run stopped at t = {stop['time']:g} s: {stop['error']}; "
              f"{path} holds the {result.steps} control steps before it", file=sys.stderr)
        return 1
    if not args.quiet:
        simulated = result.steps * result.dt
        print(f"{scenario.name}: {result.steps} steps of {result.dt:g} s ({simulated:g} s) in "
              f"{result.wall_time:.2f} s -> {path}"
              + (f" and {len(figures)} figures" if figures else "")
              + (f"; 3-D view {view}" if args.view else ""))
        if abs(simulated - scenario.duration) > 1e-9 * scenario.duration:
            print(f"note: {scenario.duration:g} s is not a whole number of control periods; "
                  f"ran the nearest, {simulated:g} s")
        print(_summary(result.metrics()))
        if reference is not None:
            print(plant_line(result.plant_settings))
            print(dynamic_summary(result.metrics(), reference.metrics()))
    print_warnings(run_warnings(result))
    return 0
