"""``uvms-qp models [NAME]``: list the bundled models with their DOFs, or describe one.

Without a name, one line per bundled model: name, size of ``zeta`` (vehicle + joints), vehicle
kind with its actuated rates, and what the model is. With a name: source, frames, mount, joint
limits and rate limits.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``models`` sub-command to the ``uvms-qp`` parser."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "models",
        help="list bundled models with their DOFs (or describe one)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("name", nargs="?", help="bundled model to describe in detail")
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


def _describe(name: str) -> str:
    from ..model.bundled import load_model

    model = load_model(name)
    mount = model.mount
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
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Print the table of bundled models, or the details of ``args.name``."""
    from ..model.bundled import bundled_entry, bundled_models, load_model

    if args.name:
        bundled_entry(args.name)  # unknown name -> UnknownModelError listing the models
        print(_describe(args.name))
        return 0
    rows = []
    for name in bundled_models():
        model = load_model(name)
        dofs = f"{model.nv} = {model.n_vehicle} + {model.n_joints}"
        rows.append((name, dofs, _vehicle(model), bundled_entry(name).summary))
    headers = ("model", "DOF (vehicle + joints)", "vehicle", "description")
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers)]
    for row in (headers, *rows):
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip())
    return 0
