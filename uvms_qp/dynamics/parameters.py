"""Physical parameters of a floating UVMS, as data with provenance.

:class:`BodyParameters` describes one rigid body in water (mass, inertia, centres of gravity and
buoyancy, displaced volume, added mass, damping) in its own body frame; :class:`PlantParameters`
gathers the vehicle, the arm's link bodies and the environment (water density, gravity) with the
arm's servo time constant. Both are frozen and validated at construction: an error names the
field (``vehicle.added_mass``, ``links.axis_b.mass``) and the value.

Conventions (``docs/dynamics.md``):

- The vehicle's body frame is the model's ``vehicle`` frame, FRD (x forward, y right, z down),
  Fossen's body frame; a link's body frame is the frame of the Pinocchio joint that moves it.
- Spatial vectors and matrices are ordered ``[linear; angular]`` (Pinocchio's order; Fossen's
  ``nu = [u, v, w, p, q, r]``). Matrices are given at the body frame origin, in body axes.
- Hydrodynamic coefficients are stored as positive magnitudes: Fossen writes them as negative
  derivatives (``X_udot = -6.36``; ``M_A = -diag(X_udot, ...)``, ``D = -diag(X_u, ...)``).
"""

from __future__ import annotations

import math
import types
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError

FloatArray = NDArray[np.float64]

#: Default time constant of the arm's joint velocity servos [s]. The vendor's servos close their
#: velocity loop at about 100 Hz (facts on the Reach Alpha 5): with one sample of computation
#: delay and the zero-order hold's half sample, the loop carries about 15 ms of delay, and a 60
#: degree phase margin caps its crossover at (pi/6) / 0.015 s = 35 rad/s: a first-order lag of
#: 1/35 s = 0.029 s, rounded to 0.03 s. It is an estimate: give a measured value when you have one.
DEFAULT_SERVO_TIME_CONSTANT = 0.03
#: Default water density [kg/m^3] (sea water) and gravity [m/s^2] when a set gives none.
DEFAULT_WATER_DENSITY = 1025.0
DEFAULT_GRAVITY = 9.81

#: Fields of :class:`BodyParameters` that hold numbers (what :meth:`PlantParameters.scaled`
#: may scale).
BODY_FIELDS: tuple[str, ...] = (
    "mass", "inertia", "centre_of_gravity", "volume", "centre_of_buoyancy", "added_mass",
    "linear_damping", "quadratic_damping",
)
#: Scalar fields of :class:`PlantParameters` that :meth:`PlantParameters.scaled` may scale.
PLANT_FIELDS: tuple[str, ...] = ("water_density", "gravity", "joint_servo_time_constant")

_RELATIVE_TOLERANCE = 1e-9


def _number(value: Any, name: str, *, minimum: float | None = None,
            strict: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ParameterError(f"expected a number, got {type(value).__name__}", name, value=value)
    number = float(value)
    if not math.isfinite(number):
        raise ParameterError(f"expected a finite number, got {number}", name, value=value)
    if minimum is not None and (number <= minimum if strict else number < minimum):
        relation = ">" if strict else ">="
        raise ParameterError(f"must be {relation} {minimum:g}, got {number:g}", name, value=value)
    return number


def _array(value: Any, name: str, shapes: tuple[tuple[int, ...], ...]) -> FloatArray:
    """``value`` as a finite float64 array of one of ``shapes``."""
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"expected numbers of shape {' or '.join(map(str, shapes))}",
                             name, value=value) from exc
    if isinstance(value, np.ndarray) and value.dtype.kind not in "fiu":
        raise ParameterError(f"expected real numbers, got {value.dtype}", name, value=value)
    if array.shape not in shapes:
        raise ParameterError(f"expected shape {' or '.join(map(str, shapes))}, got "
                             f"{array.shape}", name, value=value)
    if not np.isfinite(array).all():
        raise ParameterError("contains NaN or inf", name, value=value)
    return array


def _symmetric_psd(value: Any, name: str, n: int, *, allow_diagonal: bool = True) -> FloatArray:
    shapes = ((n, n), (n,)) if allow_diagonal else ((n, n),)
    matrix = _array(value, name, shapes)
    if matrix.ndim == 1:
        matrix = np.diag(matrix)
    scale = max(1.0, float(np.abs(matrix).max()))
    asym = float(np.abs(matrix - matrix.T).max())
    if asym > _RELATIVE_TOLERANCE * scale:
        raise ParameterError(f"must be symmetric (largest |A - A^T| = {asym:.3g})", name,
                             value=value)
    matrix = 0.5 * (matrix + matrix.T)
    smallest = float(np.linalg.eigvalsh(matrix)[0])
    if smallest < -_RELATIVE_TOLERANCE * scale:
        raise ParameterError(f"must be positive semidefinite (smallest eigenvalue "
                             f"{smallest:.4g})", name, value=value)
    return matrix


def _frozen(array: FloatArray) -> FloatArray:
    array.flags.writeable = False
    return array


@contextmanager
def parameter_path(prefix: str, file: str | None = None) -> Iterator[None]:
    """Re-raise a :class:`~uvms_qp.errors.ParameterError` with ``prefix.`` before its path."""
    try:
        yield
    except ParameterError as exc:
        path = f"{prefix}.{exc.path}" if exc.path and prefix else (exc.path or prefix)
        raise ParameterError(exc.reason, path, file=file if exc.file is None else exc.file,
                             value=exc.value) from None


def skew(vector: FloatArray) -> FloatArray:
    """Cross-product matrix ``S(a)`` with ``S(a) b = a x b`` (Fossen's ``S``)."""
    x, y, z = (float(c) for c in vector)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


@dataclass(frozen=True, eq=False)
class BodyParameters:
    """One rigid body in water, in its own body frame (see the module's conventions).

    Attributes:
        mass: Mass in air [kg], >= 0.
        inertia: Inertia about the centre of gravity, body axes [kg m^2] (3x3 symmetric positive
            semidefinite, or its 3 diagonal entries), with principal moments obeying the
            triangle inequality of a rigid body.
        centre_of_gravity: Centre of gravity in the body frame [m] (3,).
        volume: Displaced volume [m^3], >= 0 (the buoyancy is ``water_density * gravity *
            volume``).
        centre_of_buoyancy: Centre of buoyancy (centroid of the displaced volume) [m] (3,).
        added_mass: Added mass at the body frame origin, ``[linear; angular]`` order [kg, kg m,
            kg m^2] (6x6 symmetric positive semidefinite, or its 6 diagonal entries).
        linear_damping: Linear damping coefficients ``[X_u, Y_v, Z_w, K_p, M_q, N_r]`` as
            magnitudes [N s/m, N m s/rad] (6,), >= 0, acting on the body's velocity relative to
            the water at its frame origin, body axes.
        quadratic_damping: Quadratic damping ``[X_u|u|, ..., N_r|r|]`` magnitudes [N s^2/m^2,
            N m s^2/rad^2] (6,), >= 0, on the same relative velocity.
        source: Where the numbers come from (authors, year, venue; or an assumption).
    """

    mass: float
    inertia: FloatArray
    centre_of_gravity: FloatArray
    volume: float
    centre_of_buoyancy: FloatArray
    added_mass: FloatArray
    linear_damping: FloatArray
    quadratic_damping: FloatArray
    source: str = ""

    def __post_init__(self) -> None:
        setattr_ = object.__setattr__
        setattr_(self, "mass", _number(self.mass, "mass", minimum=0.0))
        setattr_(self, "volume", _number(self.volume, "volume", minimum=0.0))
        inertia = _symmetric_psd(self.inertia, "inertia", 3)
        moments = np.linalg.eigvalsh(inertia)
        slack = moments[0] + moments[1] - moments[2]
        if slack < -_RELATIVE_TOLERANCE * max(1.0, float(moments[2])):
            raise ParameterError(
                f"principal moments {np.round(moments, 6).tolist()} break the triangle "
                "inequality of a rigid body (I1 + I2 >= I3)", "inertia", value=self.inertia)
        setattr_(self, "inertia", _frozen(inertia))
        for name in ("centre_of_gravity", "centre_of_buoyancy"):
            setattr_(self, name, _frozen(_array(getattr(self, name), name, ((3,),))))
        setattr_(self, "added_mass", _frozen(_symmetric_psd(self.added_mass, "added_mass", 6)))
        for name in ("linear_damping", "quadratic_damping"):
            vec = _array(getattr(self, name), name, ((6,),))
            if (vec < 0.0).any():
                k = int(np.flatnonzero(vec < 0.0)[0])
                raise ParameterError(f"entries must be >= 0 (magnitudes), got {vec[k]:g} at "
                                     f"index {k}", name, value=getattr(self, name))
            setattr_(self, name, _frozen(vec))
        if not isinstance(self.source, str):
            raise ParameterError(f"expected a string, got {type(self.source).__name__}",
                                 "source", value=self.source)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BodyParameters):
            return NotImplemented
        return self.source == other.source and all(
            np.array_equal(getattr(self, f), getattr(other, f)) for f in BODY_FIELDS)

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt through the constructor: validated again, arrays read-only again
        return (BodyParameters, tuple(getattr(self, f) for f in (*BODY_FIELDS, "source")))

    def rigid_inertia(self) -> FloatArray:
        """Rigid-body spatial inertia at the body frame origin, ``[linear; angular]`` (6x6).

        ``[[m I, -m S(r_g)], [m S(r_g), I_g - m S(r_g)^2]]`` (Fossen (2011), Section 3.3, the
        rigid-body mass matrix about a point away from the centre of gravity).
        """
        m, S = self.mass, skew(self.centre_of_gravity)
        out = np.zeros((6, 6))
        out[:3, :3] = m * np.eye(3)
        out[:3, 3:] = -m * S
        out[3:, :3] = m * S
        out[3:, 3:] = self.inertia - m * S @ S
        return out

    def scaled(self, name: str, factor: float) -> BodyParameters:
        """A copy with the numeric field ``name`` multiplied by ``factor`` (validated again)."""
        if name not in BODY_FIELDS:
            raise ParameterError(f"unknown field; known: {', '.join(BODY_FIELDS)}", name)
        return replace(self, **{name: getattr(self, name) * factor})


def _links(value: Any) -> Mapping[str, BodyParameters]:
    if not isinstance(value, Mapping):
        raise ParameterError(f"expected a mapping joint name -> BodyParameters, got "
                             f"{type(value).__name__}", "links", value=value)
    out: dict[str, BodyParameters] = {}
    for name, body in value.items():
        if not isinstance(name, str):
            raise ParameterError(f"joint names must be strings, got {name!r}", "links")
        if not isinstance(body, BodyParameters):
            raise ParameterError(f"expected BodyParameters, got {type(body).__name__}",
                                 f"links.{name}", value=body)
        out[name] = body
    return types.MappingProxyType(out)


@dataclass(frozen=True, eq=False)
class PlantParameters:
    """Every physical number of a floating UVMS: vehicle, arm links, water, servos.

    Attributes:
        name: Name of the set.
        vehicle: The vehicle body, in the FRD vehicle frame (origin: the model's ``vehicle``
            frame, the point the arm mount is measured from).
        links: Arm joint name -> the body that joint moves, in that joint's frame.
        joint_servo_time_constant: Time constant of the arm's first-order joint velocity servos
            [s] (:data:`DEFAULT_SERVO_TIME_CONSTANT` and why).
        water_density: [kg/m^3].
        gravity: Gravitational acceleration [m/s^2], along world z (NED: down).
        thrusters: The vehicle's thruster layout (an object of the actuator layer) or None;
            opaque to the plant, whose input is the vehicle wrench.
        source: Where the set comes from (its bodies carry their own sources too).
        rated_payload: The payload the arm is rated to hold at full reach [kg] (mass in air),
            > 0, or None when unknown. A run reports a payload beyond it; nothing is limited.
    """

    name: str
    vehicle: BodyParameters
    links: Mapping[str, BodyParameters]
    joint_servo_time_constant: float = DEFAULT_SERVO_TIME_CONSTANT
    water_density: float = DEFAULT_WATER_DENSITY
    gravity: float = DEFAULT_GRAVITY
    thrusters: Any = field(default=None)
    source: str = ""
    rated_payload: float | None = None

    def __post_init__(self) -> None:
        setattr_ = object.__setattr__
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError("expected a non-empty string", "name", value=self.name)
        if not isinstance(self.vehicle, BodyParameters):
            raise ParameterError(f"expected BodyParameters, got {type(self.vehicle).__name__}",
                                 "vehicle", value=self.vehicle)
        if not self.vehicle.mass > 0.0:
            raise ParameterError("the vehicle needs a positive mass", "vehicle.mass",
                                 value=self.vehicle.mass)
        setattr_(self, "links", _links(self.links))
        setattr_(self, "joint_servo_time_constant", _number(
            self.joint_servo_time_constant, "joint_servo_time_constant", minimum=0.0,
            strict=True))
        setattr_(self, "water_density", _number(self.water_density, "water_density",
                                                minimum=0.0))
        setattr_(self, "gravity", _number(self.gravity, "gravity", minimum=0.0))
        if not isinstance(self.source, str):
            raise ParameterError(f"expected a string, got {type(self.source).__name__}",
                                 "source", value=self.source)
        if self.rated_payload is not None:
            setattr_(self, "rated_payload", _number(self.rated_payload, "rated_payload",
                                                    minimum=0.0, strict=True))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PlantParameters):
            return NotImplemented
        return (self.name == other.name and self.vehicle == other.vehicle
                and dict(self.links) == dict(other.links) and self.source == other.source
                and self.thrusters == other.thrusters
                and self.rated_payload == other.rated_payload
                and all(getattr(self, f) == getattr(other, f) for f in PLANT_FIELDS))

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> tuple[Any, ...]:
        # the links' read-only view does not pickle: rebuilt from a plain dict (for workers of a
        # parameter sweep)
        return (PlantParameters, (self.name, self.vehicle, dict(self.links),
                                  self.joint_servo_time_constant, self.water_density,
                                  self.gravity, self.thrusters, self.source,
                                  self.rated_payload))

    def bodies(self) -> dict[str, BodyParameters]:
        """``{"vehicle": ..., "links.<joint>": ...}``: every body with its key path."""
        return {"vehicle": self.vehicle, **{f"links.{k}": b for k, b in self.links.items()}}

    def with_changes(self, **changes: Any) -> PlantParameters:
        """A validated copy with some fields replaced (``dataclasses.replace``)."""
        known = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - known)
        if unknown:
            raise ParameterError(f"unknown field; known: {', '.join(sorted(known))}",
                                 unknown[0])
        return replace(self, **changes)

    def scaled(self, factors: Mapping[str, float]) -> PlantParameters:
        """A copy with parameters multiplied by relative factors (Monte-Carlo sweeps).

        Args:
            factors: Path -> factor. Paths: ``water_density``, ``gravity``,
                ``joint_servo_time_constant``; ``vehicle.<field>``; ``links.<field>`` (every
                link); ``links.<joint>.<field>``; with ``<field>`` one of :data:`BODY_FIELDS`
                (a vector or matrix is scaled as a whole: ``vehicle.centre_of_buoyancy`` by 2
                doubles the distance from the origin). Factors on the same quantity multiply.

        Raises:
            ParameterError: an unknown path, a factor that is not a finite number, or a factor
                that makes a mass or volume negative or a matrix indefinite (the error names the
                path and the factor).
        """
        if not isinstance(factors, Mapping):
            raise ParameterError(f"expected a mapping path -> factor, got "
                                 f"{type(factors).__name__}", "factors", value=factors)
        result = self
        for path, value in factors.items():
            factor = _number(value, str(path))
            result = result._scale_one(str(path), factor)
        return result

    def _scale_one(self, path: str, factor: float) -> PlantParameters:
        parts = path.split(".")
        try:
            if len(parts) == 1 and path in PLANT_FIELDS:
                with parameter_path(""):
                    return replace(self, **{path: getattr(self, path) * factor})
            if len(parts) == 2 and parts[0] == "vehicle" and parts[1] in BODY_FIELDS:
                with parameter_path("vehicle"):
                    vehicle = self.vehicle.scaled(parts[1], factor)
                return replace(self, vehicle=vehicle)
            if len(parts) == 2 and parts[0] == "links" and parts[1] in BODY_FIELDS:
                links = {}
                for joint, body in self.links.items():
                    with parameter_path(f"links.{joint}"):
                        links[joint] = body.scaled(parts[1], factor)
                return replace(self, links=links)
            if len(parts) == 3 and parts[0] == "links" and parts[2] in BODY_FIELDS:
                if parts[1] not in self.links:
                    raise ParameterError(f"no link for joint {parts[1]!r}; links: "
                                         f"{', '.join(self.links) or '(none)'}", path)
                links = dict(self.links)
                with parameter_path(f"links.{parts[1]}"):
                    links[parts[1]] = self.links[parts[1]].scaled(parts[2], factor)
                return replace(self, links=links)
        except ParameterError as exc:
            raise ParameterError(f"scaling {path} by {factor:g}: {exc.reason}", exc.path,
                                 value=factor) from None
        raise ParameterError(
            "unknown parameter path; known: " + ", ".join(
                [*PLANT_FIELDS, *(f"vehicle.{f}" for f in BODY_FIELDS),
                 *(f"links.{f}" for f in BODY_FIELDS), "links.<joint>.<field>"]),
            path, value=factor)

    def summary(self) -> str:
        """A few lines a person can read: masses, volumes, net weights, sources."""
        g, rho = self.gravity, self.water_density
        lines = [f"{self.name}: water {rho:g} kg/m^3, g {g:g} m/s^2, joint servo time constant "
                 f"{self.joint_servo_time_constant:g} s"]
        for key, body in self.bodies().items():
            net = (body.mass - rho * body.volume) * g
            lines.append(f"  {key}: {body.mass:.4g} kg, {body.volume * 1e3:.4g} L, net weight "
                         f"in water {net:+.3g} N  ({body.source})")
        if self.source:
            lines.append(f"  source: {self.source}")
        return "\n".join(lines)
