"""The command as a signal in closed loop, before and after: a markdown table per example.

Runs the closed-loop examples of ``tests/support/closed_loop_examples.py`` (the README's stack;
a DH-built and a URDF arm with a goal 2 % beyond reach) and every bundled scenario under every
scheme it names (``uvms-qp compare``), once with the library in this repository and once with
the library in ``--before`` (another checkout), each in a fresh process whose ``PYTHONPATH`` is
that checkout. Every figure is computed here, by this repository's code, from the commands each run
sent, so both sides are measured by the same rule:

- reversals: sign changes between consecutive commands both above 1 % of the entry's bound
  (:func:`uvms_qp.controller.history.command_reversals`); for the README's stack per axis over
  the last 150 of 200 steps, elsewhere per second after the first second (the worst axis);
- command change: the largest ``|zeta_k - zeta_(k-1)| / dt`` after the first second [m/s^2 or
  rad/s^2, the worst entry];
- tracking errors: the scenario's own ``ee_error_*`` and ``vehicle_yaw_error_*`` metrics.

    PYTHONPATH=$PWD python benchmarks/closed_loop_table.py --before ../main [--work DIR]
        [--parts readme arms scenarios] [--scenarios NAME ...]

With ``--work DIR`` the scenario runs are kept there and reused by a later call.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from uvms_qp.controller.history import command_reversals
from uvms_qp.sim.metrics import axis_bounds
from uvms_qp.sim.scenario import bundled_scenarios

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "tests" / "support" / "closed_loop_examples.py"
#: Start-up transient [s] left out of the per-second figures.
TRANSIENT = 1.0
#: Steps counted at the end of the README's run (of 200).
README_COUNTED = 150
#: Tracking-error metrics compared (lower is better), where a scenario reports them.
ERRORS = ("ee_error_max", "ee_error_rms", "ee_error_final", "vehicle_yaw_error_max",
          "vehicle_yaw_error_final")
#: An error "not worse" than before: at most ``before * (1 + REL) + ABS`` (round-off of a run).
REL, ABS = 1e-3, 1e-9


def child(tree: Path, args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    """Run ``python args`` with the library of ``tree`` (and nothing of this checkout)."""
    env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, *args], env=env, cwd=cwd, capture_output=True,
                          text=True, check=False)


def run_example(tree: Path, example: str, cwd: Path) -> dict:
    proc = child(tree, [str(EXAMPLES), example], cwd)
    if proc.returncode != 0:
        raise SystemExit(f"{example} with {tree} failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout)


def per_second(commands: np.ndarray, bounds: np.ndarray, dt: float) -> np.ndarray:
    """Reversals per second of each entry after the first second."""
    late = commands[round(TRANSIENT / dt):]
    return command_reversals(late, bounds) / max(late.shape[0] * dt, dt)


def change_after_transient(commands: np.ndarray, dt: float) -> float:
    """The largest ``|zeta_k - zeta_(k-1)| / dt`` after the first second."""
    late = commands[round(TRANSIENT / dt) - 1:]
    return float(np.abs(np.diff(late, axis=0)).max() / dt) if late.shape[0] > 1 else 0.0


def readme_table(runs: dict[str, dict]) -> list[str]:
    names = runs["after"]["names"]
    lines = ["### The README's stack, 200 steps, dt = 0.05 s",
             "", "| | " + " | ".join(names) + " | tool to goal [mm] | roll [rad] | pitch [rad] "
             "| max change after 1 s [/s^2] | statuses |",
             "|---" * (len(names) + 6) + "|"]
    for side, data in runs.items():
        commands = np.array(data["commands"])
        counts = command_reversals(commands[-README_COUNTED:], np.array(data["bounds"]))
        lines.append(
            f"| {side}: reversals in the last {README_COUNTED} steps | "
            + " | ".join(str(int(c)) for c in counts)
            + f" | {1e3 * data['distance']:.3g} | {data['roll']:+.3f} | {data['pitch']:+.3f} "
            f"| {change_after_transient(commands, data['dt']):.3g} | "
            + ", ".join(f"{k} {v}" for k, v in sorted(data["statuses"].items())) + " |")
    return lines


def arms_table(runs: dict[str, dict[str, dict]]) -> list[str]:
    lines = ["### Arms with a goal 2 % beyond reach (elbow at its singularity), 200 steps",
             "", "| arm | side | max abs(rate) / bound | worst reversals/s after 1 s "
             "| max change after 1 s [rad/s^2] | tool to goal / reach | statuses |",
             "|---|---|---|---|---|---|---|"]
    for arm, sides in runs.items():
        for side, data in sides.items():
            commands, bounds = np.array(data["commands"]), np.array(data["bounds"])
            rates = per_second(commands, bounds, data["dt"])
            worst = int(np.argmax(rates))
            axis = data["names"][worst] if rates[worst] > 0.0 else "-"
            lines.append(
                f"| {arm} | {side} | {np.max(np.abs(commands) / bounds):.3g} "
                f"| {rates[worst]:.3g} ({axis}) "
                f"| {change_after_transient(commands, data['dt']):.3g} "
                f"| {data['distance'] / data['reach']:.4f} | "
                + ", ".join(f"{k} {v}" for k, v in sorted(data["statuses"].items())) + " |")
    return lines


def scenario_runs(tree: Path, name: str, out: Path) -> dict[str, dict]:
    """``uvms-qp compare`` of one scenario with the library of ``tree`` (reused when present)."""
    if not (out / "comparison.json").exists():
        out.parent.mkdir(parents=True, exist_ok=True)
        proc = child(tree, ["-m", "uvms_qp", "compare", name, "--out", str(out), "--no-plots",
                            "--quiet"], out.parent)
        if proc.returncode != 0:
            raise SystemExit(f"{name} with {tree} failed:\n{proc.stderr[-2000:]}")
    schemes = json.loads((out / "comparison.json").read_text())["schemes"]
    return {s: json.loads((out / s / "results.json").read_text()) for s in schemes}


def signal(results: dict) -> tuple[float, str]:
    """Worst-axis reversals per second after the first second, by the series of a run."""
    series = results["series"]

    def floats(key: str) -> np.ndarray:
        return np.array([[np.nan if v is None else v for v in row] for row in series[key]],
                        dtype=float)

    zeta, lower, upper = floats("zeta"), floats("zeta_lower"), floats("zeta_upper")
    lower[np.isnan(lower)], upper[np.isnan(upper)] = -np.inf, np.inf
    dt = float(results["dt"])
    steps = np.arange(zeta.shape[0]) * dt >= TRANSIENT - 1e-9 * dt
    counted = int(steps.sum())
    if counted == 0:
        return 0.0, "-"
    rates = command_reversals(zeta[steps], axis_bounds(zeta, lower, upper)) / (counted * dt)
    worst = int(np.argmax(rates))
    if rates[worst] == 0.0:
        return 0.0, "-"
    names = series.get("zeta_names") or []
    return float(rates[worst]), (names[worst] if worst < len(names) else str(worst))


def scenarios_table(before: Path, after: Path, names: list[str], work: Path) -> list[str]:
    lines = ["### Bundled scenarios, every scheme they name: before -> after",
             "", "| scenario | scheme | worst reversals/s after 1 s | tracking errors | "
             "not worse |", "|---|---|---|---|---|"]
    for name in names:
        runs = {side: scenario_runs(tree, name, work / side / name)
                for side, tree in (("before", before), ("after", after))}
        for scheme, new in runs["after"].items():
            old = runs["before"].get(scheme)
            rev_new, axis = signal(new)
            rev_old = signal(old)[0] if old else float("nan")
            errors, ok = [], True
            for key in ERRORS:
                a = new["metrics"].get(key)
                b = None if old is None else old["metrics"].get(key)
                if a is None and b is None:
                    continue
                worse = a is None or (b is not None and a > b * (1 + REL) + ABS)
                ok = ok and not worse
                errors.append(f"{key} {_fmt(b)} -> {_fmt(a)}{' (worse)' if worse else ''}")
            lines.append(f"| {name} | {scheme} | {rev_old:.3g} -> {rev_new:.3g} ({axis}) | "
                         + "; ".join(errors) + f" | {'yes' if ok else 'NO'} |")
    return lines


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.3g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="checkout of the library to compare with")
    parser.add_argument("--work", type=Path, help="keep (and reuse) the scenario runs here")
    parser.add_argument("--parts", nargs="+", default=["readme", "arms", "scenarios"],
                        choices=["readme", "arms", "scenarios"])
    parser.add_argument("--scenarios", nargs="+", help="bundled scenarios (default: all)")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": ROOT} if args.before else {"after": ROOT}
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)  # not this checkout: ``python -m`` puts the working directory first
        if "readme" in args.parts:
            runs = {side: run_example(tree, "readme", cwd) for side, tree in trees.items()}
            print("\n".join(readme_table(runs)), end="\n\n", flush=True)
        if "arms" in args.parts:
            arms = {arm: {side: run_example(tree, arm, cwd) for side, tree in trees.items()}
                    for arm in ("dh_arm", "urdf_arm")}
            print("\n".join(arms_table(arms)), end="\n\n", flush=True)
        if "scenarios" in args.parts:
            if args.before is None:
                raise SystemExit("--before is needed for the scenario table")
            work = (args.work or cwd).resolve()
            names = args.scenarios or sorted(bundled_scenarios())
            print("\n".join(scenarios_table(trees["before"], ROOT, names, work)), flush=True)


if __name__ == "__main__":
    main()
