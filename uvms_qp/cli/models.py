"""``uvms-qp models [NAME]``: list the models with their DOFs, or describe one.

Without a name, a row per model: name, size of ``zeta`` (vehicle + joints), vehicle kind with
its actuated rates, and what the model is (wrapped to the width of a terminal). The list holds
the bundled models, the models of the ``--model-path`` files and those that installed packages
declare (``uvms_qp.models`` entry points). With a name: source, frames, mount, joint limits,
rate limits, the home joint angles and the tool's pose at home (vehicle at the origin): where a
scenario without ``[initial]`` starts, so where a tool trajectory should start.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from ._common import add_model_path, plain, print_table, register_model_paths


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``models`` sub-command to the ``uvms-qp`` parser."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "models",
        help="list the models with their DOFs (or describe one)",
        description=plain(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("name", nargs="?", help="model to describe in detail")
    add_model_path(parser)
    parser.set_defaults(func=run)
    return parser


def _vehicle(model: Any) -> str:
    if model.vehicle_kind == "fixed":
        return "fixed base"
    text = f"{model.vehicle_kind} [{','.join(model.actuated)}]"
    if model.passive:
        text += f" passive [{','.join(model.passive)}]"
    return text


def _fmt(values: Any) -> str:
    return np.array2string(np.asarray(values), precision=4, separator=", ")


def _list(values: Any) -> str:
    """Values as a list to paste into a scenario file (4 decimals)."""
    texts = (f"{float(v):.4f}" for v in values)
    return "[" + ", ".join("0.0000" if t == "-0.0000" else t for t in texts) + "]"


def _describe(name: str) -> str:
    from ..model import load_model
    from ..model.transforms import rotation_to_rpy

    model = load_model(name)
    mount = model.mount
    tool = model.frame_pose(model.home(), "tool")
    lines = [
        model.summary(),
        f"  source:        {model.source}",
        f"  nq / nv:       {model.nq} / {model.nv}",
        f"  zeta:          [{', '.join(model.zeta_names)}]",
        f"  frames:        {', '.join(model.frames)}",
        f"  mount xyz [m]: {_fmt(mount[:3, 3])}",
        f"  mount R:       {_fmt(mount[:3, :3].ravel())} (row-major)",
        f"  joint lower:   {_fmt(model.joint_lower)} [rad]",
        f"  joint upper:   {_fmt(model.joint_upper)} [rad]",
        f"  joint rate:    {_fmt(model.joint_rate_limit)} [rad/s]",
    ]
    if model.n_vehicle:
        lines.append(f"  vehicle rate:  {_fmt(model.vehicle_rate_limit)} [m/s, rad/s]")
    lines += [
        f"  home joints:   {_list(model.split(model.home())[1])} [rad] (vehicle at the origin: "
        "where a scenario without [initial] starts)",
        f"  tool at home:  xyz {_list(tool[:3, 3])} [m], "
        f"rpy {_list(rotation_to_rpy(tool[:3, :3].ravel().tolist()))} [rad] (world)",
    ]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Print the table of models, or the details of ``args.name``."""
    from ..model import load_model, model_names
    from ..model.registry import model_entry

    register_model_paths(args)
    if args.name:
        print(_describe(args.name))  # unknown name -> UnknownModelError listing the models
        return 0
    rows = []
    for name in model_names():
        model = load_model(name)
        dofs = f"{model.nv} = {model.n_vehicle} + {model.n_joints}"
        entry = model_entry(name)
        summary = entry.summary
        if entry.origin != "bundled":
            summary = f"{summary} ({entry.origin})"
        rows.append((name, dofs, _vehicle(model), summary.strip()))
    print_table(("model", "DOF (veh + arm)", "vehicle", "description"), rows)
    return 0
