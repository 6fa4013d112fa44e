"""A user's own plant parameters from a TOML file (``uvms_qp/dynamics/data/example_plant.toml``).

The file is read strictly: an unknown key, a value of the wrong type or shape, a negative mass or
volume, a non-symmetric or indefinite matrix is a :class:`~uvms_qp.errors.ParameterError` naming
the file, the key path and the value. A file may start from a bundled set (``base = "..."``) and
give only what differs; without ``base`` every number is required.

Layout (units as in :class:`~uvms_qp.dynamics.parameters.BodyParameters`)::

    name = "my_rov"                      # required
    source = "..."                       # optional text
    base = "bluerov2_heavy_von_benzon_2022"   # optional bundled set to start from
    water_density = 1025.0               # [kg/m^3]
    gravity = 9.81                       # [m/s^2]
    joint_servo_time_constant = 0.03     # [s]
    rated_payload = 2.0                  # [kg] the arm's rated payload at full reach (optional)

    [vehicle]                            # FRD body frame
    mass = 13.5                          # [kg]
    inertia = [0.26, 0.23, 0.37]         # diagonal, or a 3x3 list of rows [kg m^2]
    centre_of_gravity = [0, 0, 0]        # [m]
    volume = 0.0134                      # [m^3]
    centre_of_buoyancy = [0, 0, -0.01]   # [m]
    added_mass = [6.36, 7.12, 18.68, 0.189, 0.135, 0.222]   # diagonal, or 6x6 rows
    linear_damping = [13.7, 0, 33, 0, 0.8, 0]
    quadratic_damping = [141, 217, 190, 1.19, 0.47, 1.5]
    source = "..."

    [links.axis_e]                       # one table per arm joint, same keys, joint frame
    ...

    [[thrusters]]                        # one table per thruster (FRD body frame)
    position = [0.14, 0.092, 0.0]        # [m]
    axis = [-0.707, 0.707, 0.0]          # direction of positive thrust
    model = "T200"                       # its published limits, dead band, lag and power
    voltage = 16.0                       # [V]
    ...

With ``base``, a ``[vehicle]`` or ``[links.<joint>]`` table changes only the keys it gives, and
the base's thrusters stay unless the file lists its own. ``thrusters`` may also be a table with
the keys of :meth:`~uvms_qp.dynamics.ThrusterLayout.from_mapping` (``axes = "flu"``,
``actuated``, ``defaults``, and its own ``thrusters`` list).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import ConfigError, ModelFileError, ParameterError, UnknownParameterSetError
from .bundled import plant_parameters
from .parameters import BODY_FIELDS, BodyParameters, PlantParameters, parameter_path
from .thrusters import AllocationRankError, ThrusterLayout

_TOP_KEYS = ("name", "source", "base", "water_density", "gravity", "joint_servo_time_constant",
             "rated_payload", "vehicle", "links", "thrusters")
_BODY_KEYS = (*BODY_FIELDS, "source")
_MAX_BYTES = 1_000_000


def _table(value: Any, path: str, file: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ParameterError(f"expected a table, got {type(value).__name__}", path, file=file,
                             value=value)
    return value


def _check_keys(table: Mapping[str, Any], known: tuple[str, ...], path: str, file: str) -> None:
    for key in table:
        if key not in known:
            where = f"{path}.{key}" if path else key
            raise ParameterError(f"unknown key; known keys: {', '.join(known)}", where,
                                 file=file, value=table[key])


def _body(table: Mapping[str, Any], base: BodyParameters | None, path: str,
          file: str, missing: str = "missing (required when the file has no `base`)"
          ) -> BodyParameters:
    _check_keys(table, _BODY_KEYS, path, file)
    values: dict[str, Any] = {}
    for key in _BODY_KEYS:
        if key in table:
            values[key] = table[key]
        elif base is not None:
            values[key] = getattr(base, key)
            if key == "source" and table:  # its numbers are no longer all the base's
                values[key] = f"{file} over {base.source}" if base.source else file
        elif key != "source":
            raise ParameterError(missing, f"{path}.{key}", file=file)
    if "source" in values and not isinstance(values["source"], str):
        raise ParameterError("expected a string", f"{path}.source", file=file,
                             value=values["source"])
    with parameter_path(path, file):
        return BodyParameters(**values)


def _thrusters(value: Any, file: str) -> ThrusterLayout:
    """The thruster layout of a file's ``thrusters`` (a list of thrusters or a layout table)."""
    mapping = {"thrusters": value} if isinstance(value, list) else value
    try:
        return ThrusterLayout.from_mapping(_table(mapping, "thrusters", file))
    except AllocationRankError as exc:
        raise ParameterError(str(exc), "thrusters", file=file) from None
    except ConfigError as exc:
        inner = exc.path if isinstance(value, list) or not exc.path else f"thrusters.{exc.path}"
        message = str(exc).split(": ", 1)[-1] if exc.path else str(exc)
        raise ParameterError(message, inner or "thrusters", file=file) from None


def load_plant_parameters(path: str | Path) -> PlantParameters:
    """Plant parameters from a TOML file (module docstring: the layout).

    Args:
        path: The file.

    Raises:
        ModelFileError: the file is missing, too large or not valid TOML.
        ParameterError: an unknown key, a missing key, a wrong type or shape, a negative mass or
            volume, a non-symmetric or indefinite matrix, an unknown ``base`` (the message names
            the file, the key path and the value).
    """
    file = str(path)
    try:
        raw = Path(path).read_bytes()
    except (OSError, TypeError, ValueError) as exc:
        raise ModelFileError(f"plant parameter file {file!r}: cannot read it ({exc})") from exc
    if len(raw) > _MAX_BYTES:
        raise ModelFileError(f"plant parameter file {file!r}: {len(raw)} bytes, more than "
                             f"{_MAX_BYTES}")
    try:
        data = tomllib.loads(raw.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ModelFileError(f"plant parameter file {file!r}: not valid TOML ({exc})") from exc
    _check_keys(data, _TOP_KEYS, "", file)
    base: PlantParameters | None = None
    if "base" in data:
        try:
            base = plant_parameters(data["base"])
        except UnknownParameterSetError as exc:
            raise ParameterError(str(exc), "base", file=file, value=data["base"]) from None
    if "name" not in data:
        raise ParameterError("missing", "name", file=file)
    vehicle_table = _table(data.get("vehicle", {}), "vehicle", file)
    if base is None and "vehicle" not in data:
        raise ParameterError("missing (required when the file has no `base`)", "vehicle",
                             file=file)
    vehicle = _body(vehicle_table, None if base is None else base.vehicle, "vehicle", file)
    links_table = _table(data.get("links", {}), "links", file)
    links: dict[str, BodyParameters] = dict(base.links) if base is not None else {}
    for joint, table in links_table.items():
        where = f"links.{joint}"
        missing = "missing (required when the file has no `base`)"
        if base is not None and joint not in base.links:
            missing = (f"missing: {joint!r} is not a joint of the base set {base.name!r} (its "
                       f"joints: {', '.join(base.links)}), so its link needs every key")
        links[joint] = _body(_table(table, where, file), links.get(joint), where, file, missing)
    changes: dict[str, Any] = {"name": data["name"], "vehicle": vehicle, "links": links}
    for key in ("source", "water_density", "gravity", "joint_servo_time_constant",
                "rated_payload"):
        if key in data:
            changes[key] = data[key]
    if "thrusters" in data:
        changes["thrusters"] = _thrusters(data["thrusters"], file)
    if base is not None and "source" not in data:
        changes["source"] = f"{file}, from {base.name}"
    with parameter_path("", file):
        if base is None:
            return PlantParameters(**changes)
        return base.with_changes(**changes)
