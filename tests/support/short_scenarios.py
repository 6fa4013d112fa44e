"""Bundled scenarios shortened for fast tests: a shorter top-level ``duration``, and no phases,
events or plant payload (they may lie beyond the new end)."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

from uvms_qp.sim.scenario import bundled_scenarios, load_scenario

_DURATION = re.compile(r"^duration\s*=\s*[0-9.eE+-]+", re.MULTILINE)
_HEADER = re.compile(r"^\[", re.MULTILINE)
_DROPPED = ("[[phases]]", "[[events]]", "[events.", "[phases.", "[plant.payload]")


def _without_timed_tables(text: str) -> str:
    starts = [m.start() for m in _HEADER.finditer(text)]
    pieces = [text[: starts[0]]] if starts else [text]
    for a, b in zip(starts, [*starts[1:], len(text)], strict=True):
        if not text[a:b].startswith(_DROPPED):
            pieces.append(text[a:b])
    return "".join(pieces)


def short_copy(name: str, duration: float, directory: Path) -> Path:
    """Write bundled scenario ``name`` with ``duration`` [s] into ``directory``; return the file."""
    text = resources.files("uvms_qp.scenarios").joinpath(f"{name}.toml").read_text()
    text, count = _DURATION.subn(f"duration = {duration!r}", text, count=1)
    assert count == 1, f"{name}: no top-level duration"
    text = _without_timed_tables(text)
    path = directory / f"{name}.toml"
    path.write_text(text)
    return path


def short_steps(name: str, steps: int, directory: Path) -> Path:
    """:func:`short_copy` lasting ``steps`` control periods of the scenario."""
    dt = load_scenario(name).dt
    return short_copy(name, steps * dt, directory)


__all__ = ["bundled_scenarios", "short_copy", "short_steps"]
