"""Models described in TOML: a scenario's ``[model]`` table and model files.

A model table builds a :class:`~uvms_qp.model.Model` the way ``Model.from_urdf`` or
``Model.from_dh`` do in Python, with the same keyword names:

- the arm: ``urdf = "arm.urdf"`` (a path relative to the file that holds the table) or
  ``dh = [{a = ..., alpha = ..., d = ..., theta = ...}, ...]`` (rows of
  :class:`~uvms_qp.model.DHRow`, with ``convention = "standard"`` or ``"modified"``);
- ``vehicle``: ``"spatial"``, ``"planar"``, ``"fixed"``, or a table
  ``{kind = "spatial", actuated = ["u", "v", "w", "r"], rate_limit = [...]}``;
- ``mount``: ``T_vehicle_arm_base`` as ``{xyz = [...], rpy = [...]}`` [m, rad] in the FRD body
  frame (``axes = "flu"`` for a mount published in ROS FLU body axes) or a 4 x 4 array;
- ``tool``: the URDF link that carries the tool frame (``tool_offset`` from that link), or for a
  DH arm the transform from the last DH frame to the tool;
- ``home``, ``joint_rate_limit``, ``name``, ``source``; for a DH arm also ``joint_names``,
  ``joint_lower`` and ``joint_upper``.

A model file (``uvms-qp run --model-path FILE``) is such a table at the top level of its own file,
with a required ``name`` and an optional one-line ``description``; :func:`register_model_file`
validates it once and registers it, so scenarios name it like a bundled model
(``model = "name"``). See ``docs/models.md``.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import ConfigError, ModelFileError, UvmsQpError
from ..model import DHRow, Model, Vehicle, flu_to_frd, register_model, transform
from .config import (
    Table,
    check_numbers,
    config_error_from,
    describe,
    instantiate,
    join,
    keyword_arguments,
    read_toml,
)

#: Keys of a model table (``description`` only in a model file).
COMMON_KEYS = ("name", "source", "vehicle", "mount", "home", "joint_rate_limit")
URDF_KEYS = ("urdf", "tool", "tool_offset")
DH_KEYS = ("dh", "convention", "tool", "joint_names", "joint_lower", "joint_upper")
MODEL_KEYS = tuple(dict.fromkeys((*COMMON_KEYS, *URDF_KEYS, *DH_KEYS)))


def _transform(value: Any, path: str) -> Any:
    """A transform value: ``{xyz, rpy, axes}`` -> 4 x 4 array, or a checked 4 x 4 array."""
    if isinstance(value, dict):
        table = Table(value, path, ("xyz", "rpy", "axes"))
        xyz = table.take_numbers("xyz", [0.0, 0.0, 0.0], size=3)
        rpy = table.take_numbers("rpy", [0.0, 0.0, 0.0], size=3)
        axes = table.take_str("axes", "frd", choices=("frd", "flu"))
        table.finish()
        T = transform(xyz, rpy)
        return flu_to_frd(T) if axes == "flu" else T
    if isinstance(value, list):
        if len(value) != 4:
            raise ConfigError(f"expected 4 rows of a 4 x 4 transform, got {len(value)}", path)
        return [check_numbers(row, join(path, i), 4) for i, row in enumerate(value)]
    raise ConfigError(f"expected a table {{xyz = [...], rpy = [...]}} or a 4 x 4 array, "
                      f"got {describe(value)}", path)


def _vehicle(value: Any, path: str) -> Vehicle:
    if isinstance(value, str):
        value = {"kind": value}
    table = Table(value, path, ("kind", "actuated", "rate_limit"))
    kwargs = keyword_arguments(Vehicle, table, skip=())
    return instantiate(Vehicle, kwargs, path)  # type: ignore[no-any-return]


def _dh_rows(value: Any, path: str) -> list[DHRow]:
    if not isinstance(value, list) or not value:
        raise ConfigError(f"expected a non-empty array of row tables, got {describe(value)}", path)
    rows = []
    for i, row in enumerate(value):
        table = Table(row, join(path, i))
        rows.append(instantiate(DHRow, keyword_arguments(DHRow, table, skip=()), table.path))
    return rows


def _strings(table: Table, key: str) -> list[str] | None:
    values = table.take_strs(key)
    return None if values is None else list(values)


def model_from_table(table: Table, base: Path) -> Model:
    """Build the model a model table describes (see the module docstring).

    Args:
        table: The table (its path prefixes every message: ``model.mount.xyz``).
        base: Folder that a relative ``urdf`` path is relative to.

    Raises:
        ConfigError: any invalid key or value, a missing URDF file, or a model that
            ``Model.from_urdf`` / ``Model.from_dh`` rejects, with the field path.
    """
    urdf = table.take_str("urdf")
    dh = table.raw("dh")
    if (urdf is None) == (dh is None):
        raise ConfigError("expected exactly one of 'urdf' (a URDF file) and 'dh' (a DH table)",
                          table.path)
    kwargs: dict[str, Any] = {}
    name = table.take_str("name")
    if name is not None:
        kwargs["name"] = name
    source = table.take_str("source")
    if source is not None:
        kwargs["source"] = source
    if table.has("vehicle"):
        kwargs["vehicle"] = _vehicle(table.raw("vehicle"), table.at("vehicle"))
    if table.has("mount"):
        kwargs["mount"] = _transform(table.raw("mount"), table.at("mount"))
    for key in ("home", "joint_rate_limit"):
        values = table.take_numbers(key)
        if values is not None:
            kwargs[key] = values
    if urdf is not None:
        for key in DH_KEYS:
            if key != "tool" and table.has(key):
                raise ConfigError("only for a DH arm ('dh'), not with 'urdf'", table.at(key))
        tool = table.take_str("tool")
        if tool is not None:
            kwargs["tool"] = tool
        if table.has("tool_offset"):
            kwargs["tool_offset"] = _transform(table.raw("tool_offset"), table.at("tool_offset"))
        table.finish()
        path = Path(urdf)
        if not path.is_absolute():
            path = base / path
        if not path.is_file():
            where = "" if Path(urdf).is_absolute() else (
                f" ({urdf!r} taken relative to {os.path.abspath(base)})")
            raise ConfigError(f"URDF file not found: {os.path.abspath(path)}{where}",
                              table.at("urdf"))
        return _build(Model.from_urdf, table, {"path": path, **kwargs},
                      {"urdf": urdf, **kwargs})
    if table.has("tool_offset"):
        raise ConfigError("only for a URDF arm ('urdf'); a DH arm takes 'tool' as a transform",
                          table.at("tool_offset"))
    kwargs["table"] = _dh_rows(dh, table.at("dh"))
    convention = table.take_str("convention", "standard", choices=("standard", "modified"))
    kwargs["convention"] = convention
    if table.has("tool"):
        kwargs["tool"] = _transform(table.raw("tool"), table.at("tool"))
    names = _strings(table, "joint_names")
    if names is not None:
        kwargs["joint_names"] = names
    for key in ("joint_lower", "joint_upper"):
        values = table.take_numbers(key)
        if values is not None:
            kwargs[key] = values
    table.finish()
    return _build(Model.from_dh, table, kwargs, {"dh": dh, **kwargs})


def _build(factory: Callable[..., Model], table: Table, kwargs: dict[str, Any],
           values: dict[str, Any]) -> Model:
    """``factory(**kwargs)`` with its errors at the field they name."""
    try:
        return factory(**kwargs)
    except ModelFileError as exc:
        raise ConfigError(str(exc), table.at("urdf")) from exc
    except (UvmsQpError, ValueError, TypeError) as exc:
        raise config_error_from(exc, table.path, list(MODEL_KEYS), values) from exc


def read_model_file(path: str | Path) -> tuple[str, str, Callable[[], Model]]:
    """Read and validate a model file.

    Args:
        path: The TOML file (a model table at the top level, with ``name`` and an optional
            ``description``).

    Returns:
        ``(name, description, build)``; ``build()`` returns a fresh model from the validated
        description (the file is not read again).

    Raises:
        ConfigError: the file is missing, malformed, or any key is invalid (the message starts
            with the file, then the field path).
    """
    file = Path(path)
    data = read_toml(file, "model file")
    spec = {key: value for key, value in data.items() if key != "description"}
    try:
        top = Table(dict(data), "", (*MODEL_KEYS, "description"))
        description = top.take_str("description", "") or ""
        name = top.take_str("name", required=True)
        model_from_table(Table(copy.deepcopy(spec), ""), file.parent)
    except ConfigError as exc:
        raise ConfigError(f"{file}: {exc}") from None

    def build() -> Model:
        return model_from_table(Table(copy.deepcopy(spec), ""), file.parent)

    build.__doc__ = description
    return str(name), description, build


def register_model_file(path: str | Path, *, replace: bool = False) -> str:
    """Validate a model file and register its model under its ``name``; returns the name.

    Raises:
        ConfigError: an invalid file (see :func:`read_model_file`), or a name that is bundled or
            already registered (unless ``replace``).
    """
    name, description, build = read_model_file(path)
    try:
        register_model(name, build, description or f"from {Path(path).name}", replace=replace)
    except UvmsQpError as exc:
        raise ConfigError(f"{path}: name: {exc}") from None
    return name
