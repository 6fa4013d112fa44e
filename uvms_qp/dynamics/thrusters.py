"""Thrusters: their layout on the vehicle, the allocation of a body wrench, their dynamics.

Frames and units: every position, axis, force and wrench is in the vehicle's FRD body frame
(``docs/notation.md``), wrenches in ``nu`` order ``[X, Y, Z, K, M, N]`` [N, N m], thruster forces
[N] (positive along the thruster's axis), times [s], power [W], energy [J].

* :class:`Thruster`: one thruster (position, axis, force limits, dead band, lag, power fit).
* :class:`ThrusterLayout`: the thrusters of one vehicle and the allocation matrix ``B``
  (6 x n) *derived* from their positions and axes: column ``i`` is ``[a_i; r_i x a_i]``
  (Fossen, Handbook of Marine Craft Hydrodynamics and Motion Control, 2011, Section 11.2). A
  layout that cannot produce a DOF the vehicle actuates is refused, naming that DOF.
* :class:`ThrustAllocator`: the body wrench ``tau`` the velocity loop demands, turned into
  thruster forces by bounded least squares,
  ``min_u ||W^(1/2) (B u - tau)||^2 + eps ||u||^2`` subject to ``lower <= u <= upper``,
  solved by DAQP on a set-up made once (only the linear term changes per call); what the
  thrusters cannot produce is reported as the unmet wrench.
* :class:`ThrusterDynamics`: what the thrusters do with a command: clamp to the limits, a dead
  band, a first-order lag advanced exactly over each physics step, electrical power from the
  published fit and the energy drawn.

The bundled BlueROV2 Heavy (:meth:`ThrusterLayout.bluerov2_heavy`) has eight Blue Robotics T200
thrusters; its limits and dead band come from the T200's public performance data (Blue Robotics,
2019) at a chosen supply voltage (:data:`T200_RATINGS`).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import daqp
import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import ConfigError, InputError, ModelFileError, ShapeError, UvmsQpError
from ..model.transforms import R_FRD_FLU
from ..model.vehicle import NU_NAMES

#: What each wrench component is, in ``nu`` order (for messages).
DOF_MEANINGS: dict[str, str] = {
    "u": "surge force", "v": "sway force", "w": "heave force",
    "p": "roll moment", "q": "pitch moment", "r": "yaw moment",
}

_NEUTRAL_PWM = 1500.0  # [us] the T200's stop command
_PWM_SPAN = 400.0  # [us] from stop to full thrust either way (1100-1900 us)

#: Default first-order time constant of a T200's force [s]: the first moment (the area between
#: a unit step and the response) of the third-order thruster model of von Benzon, Sorensen, Uth,
#: Ouerghi, Gabrielsson, Johansen (2022), "An Open-Source Benchmark Simulator: Control of a
#: BlueROV2 Underwater Robot", J. Mar. Sci. Eng. 10(12):1898,
#: ``K(s) = (6136 s + 108700) / (s^3 + 89 s^2 + 9258 s + 108700)``, whose first moment is
#: ``9258/108700 - 6136/108700 = 0.0287`` s, rounded. See ``docs/dynamics.md``.
T200_TIME_CONSTANT = 0.03

#: Electrical power fit of the T200 at 16 V, ``P = c |T|^e`` [W] with T [N]: (c, e) forward and
#: reverse (a fit to Blue Robotics' public T200 performance data, 2019). Used at every supply
#: voltage (assumption: the shaft power a thrust needs does not depend on the supply; the ESC's
#: duty cycle absorbs the voltage).
T200_POWER_FORWARD = (0.74, 1.58)
T200_POWER_REVERSE = (0.95, 1.62)


@dataclass(frozen=True)
class T200Rating:
    """The T200's published figures at one supply voltage (Blue Robotics, 2019).

    Attributes:
        voltage: Supply voltage [V].
        forward_limit: Largest forward force [N].
        reverse_limit: Largest reverse force (a magnitude) [N].
        zero_band: PWM commands that give no thrust, ``(low, high)`` [us].
    """

    voltage: float
    forward_limit: float
    reverse_limit: float
    zero_band: tuple[float, float]

    @property
    def forward_dead_band(self) -> float:
        """Forward commands below this give no thrust [N] (see :meth:`reverse_dead_band`)."""
        return (self.zero_band[1] - _NEUTRAL_PWM) / _PWM_SPAN * self.forward_limit

    @property
    def reverse_dead_band(self) -> float:
        """Reverse commands whose magnitude is below this give no thrust [N].

        Assumption: a force command is sent as PWM through the linear map of an ArduSub-style
        output (stop at 1500 us, the largest forward force at 1900 us, the largest reverse force
        at 1100 us), so a command that lands in the zero-thrust band produces nothing; the band's
        width beyond 1500 us, as a fraction of the 400 us span, is the dead band as a fraction of
        the limit. At 16 V: 28/400 of 51.5 N = 3.6 N forward, 28/400 of 39.9 N = 2.8 N reverse.
        A controller that inverts the static thrust curve would see a much narrower band: this
        is the conservative reading.
        """
        return (_NEUTRAL_PWM - self.zero_band[0]) / _PWM_SPAN * self.reverse_limit


#: The T200's published limits and zero-thrust bands, by supply voltage [V].
T200_RATINGS: dict[float, T200Rating] = {
    12.0: T200Rating(12.0, 36.4, 28.6, (1464.0, 1536.0)),
    16.0: T200Rating(16.0, 51.5, 39.9, (1472.0, 1528.0)),
    20.0: T200Rating(20.0, 65.9, 49.4, (1476.0, 1528.0)),
}


def t200_rating(voltage: Any) -> T200Rating:
    """The published T200 figures at ``voltage`` [V] (12, 16 or 20).

    Raises:
        InputError: a voltage without published figures (the message lists those there are).
    """
    v = as_scalar(voltage, "voltage", positive=True)
    rating = T200_RATINGS.get(v)
    if rating is None:
        known = ", ".join(f"{k:g}" for k in T200_RATINGS)
        raise InputError(f"voltage: no published T200 figures at {v:g} V (known: {known} V)")
    return rating


def _power_fit(value: Any, name: str) -> tuple[float, float]:
    if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray):
        raise InputError(f"{name}: expected (coefficient, exponent), got {value!r}")
    pair = as_vector(value, name)
    if pair.shape[0] != 2:
        raise ShapeError(f"{name}: expected (coefficient, exponent), got {pair.shape[0]} numbers")
    if pair[0] < 0.0 or pair[1] <= 0.0:
        raise InputError(f"{name}: expected a coefficient >= 0 and an exponent > 0, "
                         f"got {tuple(pair.tolist())}")
    return float(pair[0]), float(pair[1])


@dataclass(frozen=True, eq=False)
class Thruster:
    """One thruster, in the vehicle's FRD body frame.

    Attributes:
        name: Name used in messages and reports.
        position: Point of application of the thrust [m] (3,), FRD body frame.
        axis: Direction of positive thrust (3,), FRD body frame; normalised here (a zero vector
            is refused).
        forward_limit: Largest force along ``axis`` [N] (> 0).
        reverse_limit: Largest force against ``axis``, a magnitude [N] (> 0).
        forward_dead_band: Forward commands below this produce no thrust [N] (>= 0).
        reverse_dead_band: Reverse commands whose magnitude is below this produce no thrust [N].
        time_constant: First-order lag of the force toward its command [s] (> 0).
        power_forward: ``(c, e)`` of the electrical power ``P = c T^e`` [W] for ``T >= 0`` [N].
        power_reverse: ``(c, e)`` of ``P = c |T|^e`` [W] for ``T < 0``.

    Raises:
        InputError: a value of the wrong shape or sign (the message names the thruster and the
            field).
    """

    name: str
    position: FloatArray
    axis: FloatArray
    forward_limit: float
    reverse_limit: float
    time_constant: float
    power_forward: tuple[float, float]
    power_reverse: tuple[float, float]
    forward_dead_band: float = 0.0
    reverse_dead_band: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InputError(f"thruster name: expected a non-empty string, got {self.name!r}")
        where = f"thruster {self.name!r}"
        position = as_vector(self.position, f"{where} position", 3).copy()
        axis = as_vector(self.axis, f"{where} axis", 3)
        norm = float(np.linalg.norm(axis))
        if not norm > 1e-9:
            raise InputError(f"{where} axis: expected a non-zero direction, got {axis.tolist()}")
        axis = axis / norm
        position.flags.writeable = False
        axis.flags.writeable = False
        set_ = object.__setattr__
        set_(self, "position", position)
        set_(self, "axis", axis)
        for field in ("forward_limit", "reverse_limit", "time_constant"):
            set_(self, field, as_scalar(getattr(self, field), f"{where} {field}", positive=True))
        for field, limit in (("forward_dead_band", self.forward_limit),
                             ("reverse_dead_band", self.reverse_limit)):
            band = as_scalar(getattr(self, field), f"{where} {field}", nonnegative=True)
            if band >= limit:
                raise InputError(f"{where} {field}: {band:g} N leaves no thrust below the "
                                 f"{limit:g} N limit")
            set_(self, field, band)
        for field in ("power_forward", "power_reverse"):
            set_(self, field, _power_fit(getattr(self, field), f"{where} {field}"))

    @classmethod
    def t200(cls, name: str, position: Any, axis: Any, voltage: float = 16.0,
             time_constant: float = T200_TIME_CONSTANT) -> Thruster:
        """A Blue Robotics T200 at a supply ``voltage`` [V] (12, 16 or 20).

        Its published limits, the dead band of :class:`T200Rating`, the power fit and a lag of
        ``time_constant`` [s].
        """
        rating = t200_rating(voltage)
        return cls(name, position, axis, rating.forward_limit, rating.reverse_limit,
                   time_constant, T200_POWER_FORWARD, T200_POWER_REVERSE,
                   rating.forward_dead_band, rating.reverse_dead_band)


# BlueROV2 Heavy geometry (ROS FLU body axes, metres) from the public description of the vehicle
# used with ArduSub's Gazebo simulation (the "bluerov2_heavy" model of the bluerov2_gz and
# ardupilot_gazebo projects), thrusters numbered as ArduSub's vectored-6DOF frame: 1-4 horizontal
# (front right, front left, rear right, rear left), 5-8 vertical (same order). The axis is the
# direction the vehicle is pushed by a positive command; in FRD these give the force rows of the
# allocation matrix used by public controllers (x = [-1, -1, 1, 1, 0, 0, 0, 0] / sqrt 2,
# y = [1, -1, 1, -1, 0, 0, 0, 0] / sqrt 2, z = [0, 0, 0, 0, 1, 1, 1, 1]).
_S = math.sqrt(0.5)
_BLUEROV2_HEAVY_FLU: tuple[tuple[str, tuple[float, float, float], tuple[float, float, float]],
                           ...] = (
    ("t1", (0.14, -0.092, 0.0), (-_S, -_S, 0.0)),
    ("t2", (0.14, 0.092, 0.0), (-_S, _S, 0.0)),
    ("t3", (-0.15, -0.092, 0.0), (_S, -_S, 0.0)),
    ("t4", (-0.15, 0.092, 0.0), (_S, _S, 0.0)),
    ("t5", (0.118, -0.215, 0.064), (0.0, 0.0, -1.0)),
    ("t6", (0.118, 0.215, 0.064), (0.0, 0.0, -1.0)),
    ("t7", (-0.118, -0.215, 0.064), (0.0, 0.0, -1.0)),
    ("t8", (-0.118, 0.215, 0.064), (0.0, 0.0, -1.0)),
)

_THRUSTER_KEYS = ("name", "model", "voltage", "position", "axis", "forward_limit",
                  "reverse_limit", "forward_dead_band", "reverse_dead_band", "time_constant",
                  "power_forward", "power_reverse")
_LAYOUT_KEYS = ("name", "source", "axes", "actuated", "defaults", "thrusters")
_RANK_TOL = 1e-9


class AllocationRankError(InputError):
    """A thruster layout cannot produce some DOF the vehicle actuates.

    Attributes:
        dofs: The actuated DOFs the thrusters cannot produce independently (``nu`` names).
    """

    def __init__(self, message: str, dofs: tuple[str, ...]) -> None:
        self.dofs = dofs
        super().__init__(message)


class AllocationError(UvmsQpError):
    """The allocation's solver failed (it should not on a box-constrained problem)."""


def _names_of(dofs: Sequence[str]) -> str:
    return ", ".join(f"{DOF_MEANINGS[d]} ({d})" for d in dofs)


class ThrusterLayout:
    """The thrusters of one vehicle and the allocation matrix derived from them.

    ``matrix`` (6 x n) maps thruster forces ``u`` [N] to the body wrench ``B u`` [N, N m] in
    the FRD body frame: column ``i`` is ``[a_i; r_i x a_i]`` for the axis ``a_i`` and position
    ``r_i`` of thruster ``i``. Read-only, like every array of the layout.

    Args:
        thrusters: The thrusters (at least one, distinct names).
        actuated: The DOFs the vehicle actuates (``nu`` names, default all six). Each must be
            producible independently of the others: the rows of ``matrix`` of the actuated
            DOFs must have full rank.
        name: Name of the layout (reports).
        source: Where the numbers come from (reports).
        supply_voltage: The supply voltage [V] the thrusters' limits are for, when they come
            from a rating at one voltage (reports); None: limits of one's own.

    Attributes:
        thrusters: The thrusters, in column order; ``names`` their names.
        actuated: The actuated DOFs in ``nu`` order; ``actuated_mask`` (6,) bool.
        matrix: ``B`` (6, n) [-, m].
        lower, upper: Force limits (n,) [N] (``lower = -reverse_limit``).
        wrench_lower, wrench_upper: The extreme wrench each DOF alone can receive (6,)
            [N, N m]: ``sum_i min/max(B_ji lower_i, B_ji upper_i)``.

    Raises:
        AllocationRankError: the thrusters cannot produce an actuated DOF; the message names the
            DOFs whose rows depend on the others (a row of zeros: that DOF alone).
        InputError: no thrusters, duplicate names, an unknown DOF name.
    """

    def __init__(self, thrusters: Sequence[Thruster], *, actuated: Sequence[str] | None = None,
                 name: str = "", source: str = "",
                 supply_voltage: float | None = None) -> None:
        thrusters = tuple(thrusters)
        if not thrusters:
            raise InputError("thrusters: expected at least one thruster")
        names = []
        for k, t in enumerate(thrusters):
            if not isinstance(t, Thruster):
                raise InputError(f"thrusters[{k}]: expected a Thruster, got {type(t).__name__}")
            if t.name in names:
                raise InputError(f"thrusters[{k}]: duplicate thruster name {t.name!r}")
            names.append(t.name)
        dofs = NU_NAMES if actuated is None else tuple(actuated)
        for d in dofs:
            if d not in NU_NAMES:
                raise InputError(f"actuated: unknown DOF {d!r}; known DOFs: "
                                 f"{', '.join(NU_NAMES)}")
        if len(set(dofs)) != len(dofs):
            raise InputError(f"actuated: a DOF is named twice in {list(dofs)}")
        self.thrusters = thrusters
        self.names: tuple[str, ...] = tuple(names)
        self.actuated: tuple[str, ...] = tuple(d for d in NU_NAMES if d in dofs)
        self.name = name
        self.source = source
        self.supply_voltage = (None if supply_voltage is None
                               else as_scalar(supply_voltage, "supply_voltage", positive=True))
        axes = np.array([t.axis for t in thrusters]).T  # (3, n)
        positions = np.array([t.position for t in thrusters]).T
        matrix = np.vstack([axes, np.cross(positions, axes, axis=0)])
        self.matrix = _frozen(matrix)
        self.lower = _frozen(np.array([-t.reverse_limit for t in thrusters]))
        self.upper = _frozen(np.array([t.forward_limit for t in thrusters]))
        self.actuated_mask = _frozen(np.array([d in self.actuated for d in NU_NAMES]))
        # the largest wrench each DOF alone can receive: sum of each thruster's extreme share
        low, high = matrix * self.lower, matrix * self.upper
        self.wrench_lower = _frozen(np.minimum(low, high).sum(axis=1))
        self.wrench_upper = _frozen(np.maximum(low, high).sum(axis=1))
        self._check_rank()

    @property
    def size(self) -> int:
        """Number of thrusters."""
        return len(self.thrusters)

    def _check_rank(self) -> None:
        rows = [NU_NAMES.index(d) for d in self.actuated]
        B = self.matrix[rows]
        scale = max(float(np.linalg.norm(self.matrix, 2)), 1e-300)

        def rank(M: FloatArray) -> int:
            if M.shape[0] == 0:
                return 0
            s = np.linalg.svd(M, compute_uv=False)
            return int(np.count_nonzero(s > _RANK_TOL * scale))

        full = rank(B)
        if full == len(rows):
            return
        culprits = tuple(d for k, d in enumerate(self.actuated)
                         if rank(np.delete(B, k, axis=0)) == full)
        label = f"thruster layout {self.name!r}" if self.name else "thruster layout"
        raise AllocationRankError(
            f"{label} cannot produce {_names_of(culprits)} independently of the other actuated "
            f"DOFs (allocation rank {full} of {len(rows)} actuated DOFs): move or turn a "
            f"thruster, or leave the DOF out of 'actuated'", culprits)

    def __eq__(self, other: object) -> bool:
        """Equal by value: the same thrusters' figures and actuated DOFs (a pickled copy)."""
        if not isinstance(other, ThrusterLayout):
            return NotImplemented
        return (self.names == other.names and self.actuated == other.actuated
                and all(_same_thruster(a, b) for a, b in zip(self.thrusters, other.thrusters,
                                                               strict=True)))

    __hash__ = None  # type: ignore[assignment]

    def power(self, forces: Any) -> FloatArray:
        """Electrical power of each thruster at ``forces`` [N] (n,), from its fit [W] (n,)."""
        return _power(as_vector(forces, "forces", self.size), _fits(self))

    def __repr__(self) -> str:
        label = f" {self.name!r}" if self.name else ""
        return f"ThrusterLayout{label}({self.size} thrusters, actuated {''.join(self.actuated)})"

    # --- constructors -----------------------------------------------------------------------

    @classmethod
    def bluerov2_heavy(cls, voltage: float = 16.0, *,
                       time_constant: float = T200_TIME_CONSTANT) -> ThrusterLayout:
        """The BlueROV2 Heavy's eight T200 thrusters at a supply ``voltage`` [V] (12, 16, 20).

        Positions and axes: the public description of the vehicle used with ArduSub's Gazebo
        simulation (ROS FLU body axes), converted to FRD (``R_FRD_FLU = diag(1, -1, -1)``).
        Thrusters ``t1``-``t4`` are the horizontal vectored ones (front right, front left, rear
        right, rear left), ``t5``-``t8`` the vertical ones in the same order. Limits and dead
        band: :func:`t200_rating`; lag ``time_constant`` [s] (default
        :data:`T200_TIME_CONSTANT`); power: the 16 V fit at every voltage.
        """
        rating = t200_rating(voltage)
        thrusters = [Thruster.t200(name, R_FRD_FLU @ np.array(r), R_FRD_FLU @ np.array(a),
                                   rating.voltage, time_constant)
                     for name, r, a in _BLUEROV2_HEAVY_FLU]
        return cls(thrusters, name=f"bluerov2_heavy_{rating.voltage:g}V",
                   supply_voltage=rating.voltage,
                   source=("BlueROV2 Heavy public description (ArduSub Gazebo model); Blue "
                           f"Robotics T200 public performance data (2019) at {rating.voltage:g} V"))

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], *, source: str = "") -> ThrusterLayout:
        """A layout from a table (as read from TOML): a user's own vehicle.

        Keys: ``thrusters`` (a list of tables, one per thruster), optional ``axes`` (``"frd"``,
        the default, or ``"flu"`` for positions and axes in ROS body axes), ``actuated`` (DOF
        names), ``name``, ``source`` and ``defaults`` (a table of thruster keys shared by every
        thruster). Thruster keys: ``position`` [m] and ``axis`` (required), ``name`` (default
        ``t1``, ``t2``, ...), ``forward_limit``, ``reverse_limit`` [N], ``time_constant`` [s],
        ``power_forward`` and ``power_reverse`` (``[c, e]``: ``P = c |T|^e`` W), and optional
        ``forward_dead_band``, ``reverse_dead_band`` [N] (default 0). ``model = "T200"`` with
        ``voltage`` (12, 16 or 20; default 16) fills the limits, dead bands, lag and power from
        the T200's published data; keys given explicitly take precedence.

        Args:
            data: The table.
            source: Where the table comes from (a file name), put before the key in messages.

        Raises:
            ConfigError: an unknown or missing key, a value of the wrong type, shape or sign; the
                message gives the key's path (``thrusters[2].axis``), ``path`` holds it.
            AllocationRankError: the thrusters cannot produce an actuated DOF.
        """
        if not isinstance(data, Mapping):
            raise _config_error(source, "", f"expected a table, got {type(data).__name__}")
        _check_keys(data, _LAYOUT_KEYS, source, "")
        axes = data.get("axes", "frd")
        if axes not in ("frd", "flu"):
            raise _config_error(source, "axes", f"expected 'frd' or 'flu', got {axes!r}")
        defaults = data.get("defaults", {})
        if not isinstance(defaults, Mapping):
            raise _config_error(source, "defaults",
                                f"expected a table, got {type(defaults).__name__}")
        _check_keys(defaults, tuple(k for k in _THRUSTER_KEYS if k != "name"), source,
                    "defaults")
        entries = data.get("thrusters")
        if not isinstance(entries, Sequence) or isinstance(entries, str) or not entries:
            raise _config_error(source, "thrusters",
                                f"expected a non-empty list of thruster tables, got {entries!r}")
        thrusters = []
        for k, entry in enumerate(entries):
            path = f"thrusters[{k}]"
            if not isinstance(entry, Mapping):
                raise _config_error(source, path, f"expected a table, got {type(entry).__name__}")
            _check_keys(entry, _THRUSTER_KEYS, source, path)
            thrusters.append(_thruster_from_table({**defaults, **entry}, k, axes, source, path))
        actuated = data.get("actuated")
        if actuated is not None and (isinstance(actuated, str)
                                     or not isinstance(actuated, Sequence)):
            raise _config_error(source, "actuated",
                                f"expected a list of DOF names, got {actuated!r}")
        name = data.get("name", "")
        layout_source = data.get("source", source)
        for key, value in (("name", name), ("source", layout_source)):
            if not isinstance(value, str):
                raise _config_error(source, key, f"expected a string, got {value!r}")
        try:
            return cls(thrusters, actuated=actuated, name=name, source=layout_source)
        except AllocationRankError as exc:
            raise AllocationRankError(f"{source}: {exc}" if source else str(exc),
                                      exc.dofs) from None
        except InputError as exc:  # duplicate names, unknown DOFs
            key = "actuated" if str(exc).startswith("actuated") else "thrusters"
            raise _config_error(source, key, str(exc).split(": ", 1)[-1]) from None

    @classmethod
    def from_toml(cls, path: str | Path, table: str | None = "thrusters") -> ThrusterLayout:
        """A layout from a TOML file: its ``[thrusters]`` table (the whole file if ``table``).

        ``table`` None reads the file's top level; :meth:`from_mapping` lists the keys.

        Raises:
            ModelFileError: the file is missing or not valid TOML.
            ConfigError: an invalid key or value (the message names the file and the key).
        """
        file = Path(path)
        try:
            data = tomllib.loads(file.read_text(encoding="utf-8"))
        except FileNotFoundError as exc:
            raise ModelFileError(f"{file}: no such thruster file") from exc
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
            raise ModelFileError(f"{file}: cannot read thruster file ({exc})") from exc
        if table is not None:
            if table not in data:
                raise _config_error(str(file), table, "no such table (top-level keys: "
                                    f"{', '.join(data) or '(none)'})")
            data = data[table]
        return cls.from_mapping(data, source=str(file))


def _same_thruster(a: Thruster, b: Thruster) -> bool:
    """Two thrusters with the same figures (arrays compared by value)."""
    return all(np.array_equal(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))


def _config_error(source: str, path: str, message: str) -> ConfigError:
    """``ConfigError`` at ``path`` whose message reads ``source: path: message``."""
    where = ": ".join(p for p in (source, path) if p)
    error = ConfigError(f"{where}: {message}" if where else message)
    error.path = path
    return error


def _check_keys(table: Mapping[str, Any], known: Sequence[str], source: str, path: str) -> None:
    for key in table:
        if key not in known:
            raise _config_error(source, f"{path}.{key}" if path else str(key),
                                f"unknown key; known keys: {', '.join(known)}")


def _thruster_from_table(entry: Mapping[str, Any], index: int, axes: str, source: str,
                         path: str) -> Thruster:
    values = dict(entry)
    name = values.pop("name", f"t{index + 1}")
    if not isinstance(name, str) or not name:
        raise _config_error(source, f"{path}.name", f"expected a non-empty string, got {name!r}")
    model = values.pop("model", None)
    voltage = values.pop("voltage", None)
    if model is not None:
        if not isinstance(model, str) or model.lower() != "t200":
            raise _config_error(source, f"{path}.model",
                                f"unknown thruster model {model!r}; known models: T200")
        try:
            rating = t200_rating(16.0 if voltage is None else voltage)
        except InputError as exc:
            raise _config_error(source, f"{path}.voltage",
                                str(exc).split(": ", 1)[-1]) from None
        preset = {"forward_limit": rating.forward_limit, "reverse_limit": rating.reverse_limit,
                  "forward_dead_band": rating.forward_dead_band,
                  "reverse_dead_band": rating.reverse_dead_band,
                  "time_constant": T200_TIME_CONSTANT, "power_forward": T200_POWER_FORWARD,
                  "power_reverse": T200_POWER_REVERSE}
        values = {**preset, **values}
    elif voltage is not None:
        raise _config_error(source, f"{path}.voltage", "needs model = \"T200\"")
    for key in ("position", "axis", "forward_limit", "reverse_limit", "time_constant",
                "power_forward", "power_reverse"):
        if key not in values:
            raise _config_error(source, f"{path}.{key}", f"missing key (thruster {name!r})")
    for key in ("position", "axis"):
        try:
            vector = as_vector(values[key], key, 3)
        except InputError as exc:
            raise _config_error(source, f"{path}.{key}",
                                f"thruster {name!r}: {str(exc).split(': ', 1)[-1]}") from None
        values[key] = R_FRD_FLU @ vector if axes == "flu" else vector
    try:
        return Thruster(name=name, **values)
    except InputError as exc:  # "thruster 'n' <field>: <what>"
        message = str(exc)
        field = message.split(": ", 1)[0].rsplit(" ", 1)[-1]
        key = f"{path}.{field}" if field in _THRUSTER_KEYS else path
        raise _config_error(source, key, message) from None


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.ascontiguousarray(array)
    array.flags.writeable = False
    return array


def _fits(layout: ThrusterLayout) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    t = layout.thrusters
    return (np.array([x.power_forward[0] for x in t]), np.array([x.power_forward[1] for x in t]),
            np.array([x.power_reverse[0] for x in t]), np.array([x.power_reverse[1] for x in t]))


def _power(forces: FloatArray, fits: tuple[FloatArray, FloatArray, FloatArray, FloatArray]
           ) -> FloatArray:
    """``c |T|^e`` per thruster with the forward or the reverse fit by the sign of ``T`` [W]."""
    cf, ef, cr, er = fits
    magnitude = np.abs(forces)
    forward = forces >= 0.0
    return np.where(forward, cf * magnitude ** ef, cr * magnitude ** er)


# --- allocation -------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Allocation:
    """Thruster forces for a demanded wrench, and what they cannot produce.

    Attributes:
        forces: Thruster forces [N] (n,), within the layout's limits.
        demanded: The demanded body wrench [N, N m] (6,), FRD body frame.
        produced: ``B forces`` [N, N m] (6,).
        unmet: ``demanded - produced`` [N, N m] (6,): what the thrusters cannot give (zero up to
            the regularisation's bias when the demand is feasible).
        saturated: Thrusters at a force limit (n,) bool.
    """

    forces: FloatArray
    demanded: FloatArray
    produced: FloatArray
    unmet: FloatArray
    saturated: np.ndarray

    @property
    def feasible(self) -> bool:
        """True when the thrusters produce the demand.

        Every unmet component is below 1e-6 of the demand's scale, ``max(1, |demanded|)``.
        """
        scale = max(1.0, float(np.abs(self.demanded).max()))
        return float(np.abs(self.unmet).max()) <= 1e-6 * scale


class ThrustAllocator:
    """Bounded least-squares allocation of a body wrench to the thrusters of a layout.

    Solves ``min_u ||W^(1/2) (B u - tau)||^2 + eps ||u||^2`` subject to
    ``lower <= u <= upper`` with DAQP, as the QP ``0.5 u' H u + f' u`` with the constant
    ``H = B' W B + eps I`` (set up once) and ``f = -B' W tau`` (the only data that changes per
    call); each solve starts from the previous one's active set. ``eps`` is ``regularization``
    times the largest eigenvalue of ``B' W B``: it picks the least-effort forces among those that
    produce the same wrench (8 thrusters for 6 DOFs leave two free directions) and moves the
    produced wrench by a relative ``~eps / sigma_min(B)^2`` (below 1e-7 for the BlueROV2 Heavy
    at the default 1e-9).

    Args:
        layout: The thrusters.
        wrench_weights: ``W``'s diagonal (6,), > 0 (default ones: newtons and newton metres
            weighed alike). Passive DOFs keep their weight: the allocation produces as little
            of them as it can (the loop demands zero there).
        regularization: ``eps`` relative to ``||B' W B||``, > 0.

    Raises:
        InputError: a weight or regularisation that is not positive and finite.
    """

    def __init__(self, layout: ThrusterLayout, *, wrench_weights: Any = None,
                 regularization: float = 1e-9) -> None:
        if not isinstance(layout, ThrusterLayout):
            raise InputError(f"layout: expected a ThrusterLayout, got {type(layout).__name__}")
        self.layout = layout
        weights = (np.ones(6) if wrench_weights is None
                   else as_vector(wrench_weights, "wrench_weights", 6, positive=True).copy())
        self.wrench_weights = _frozen(weights)
        self.regularization = as_scalar(regularization, "regularization", positive=True)
        n = layout.size
        B = layout.matrix
        BtW = B.T * weights  # (n, 6)
        gram = BtW @ B
        eps = self.regularization * float(np.linalg.eigvalsh(gram)[-1])
        self._H = gram + eps * np.eye(n)
        self._minus_BtW = -BtW
        self._lower = layout.lower.copy()
        self._upper = layout.upper.copy()
        self._model = daqp.Model()
        self._f = np.zeros(n)
        flag, _ = self._model.setup(self._H, self._f, np.zeros((0, n)), self._upper,
                                    self._lower, np.zeros(n, dtype=np.intc))
        if flag < 0:  # pragma: no cover - H is positive definite by construction
            raise AllocationError(f"DAQP could not set the allocation up (exit flag {flag})")
        tol = 1e-9 * np.maximum(self._upper, -self._lower)  # "at a limit" [N]
        self._upper_reached = self._upper - tol
        self._lower_reached = self._lower + tol

    def allocate(self, wrench: Any) -> Allocation:
        """Thruster forces for the demanded body ``wrench`` [N, N m] (6,), FRD body frame.

        Raises:
            ShapeError, NonFiniteError: the wrench is not 6 finite numbers.
            AllocationError: DAQP failed (not expected: the problem is a strictly convex QP
                over a box that is never empty).
        """
        tau = as_vector(wrench, "wrench", 6)
        model = self._model
        model.update(f=self._minus_BtW.dot(tau))
        x, _, flag, _ = model.solve()  # a new array every solve
        if flag < 0 or not x.dot(x) < math.inf:  # NaN fails the comparison
            raise AllocationError(f"DAQP failed on the allocation of wrench {tau.tolist()} "
                                  f"(exit flag {flag})")
        np.maximum(x, self._lower, out=x)  # round-off at an active bound
        np.minimum(x, self._upper, out=x)
        produced = self.layout.matrix.dot(x)
        saturated = (x >= self._upper_reached) | (x <= self._lower_reached)
        return Allocation(x, tau.copy(), produced, tau - produced, saturated)


# --- actuator dynamics ------------------------------------------------------------------------


class ThrusterDynamics:
    """The forces of a layout's thrusters over time: command, dead band, lag, power, energy.

    Each physics step of ``dt``: the force ``T`` of every thruster moves toward its effective
    command ``c`` by the exact solution of ``time_constant * dT/dt = c - T`` with ``c`` held,
    ``T(t + dt) = c + (T(t) - c) exp(-dt / time_constant)``. The effective command is the
    command clamped to the thruster's limits, then zero when its magnitude is below the dead
    band of its direction (commands within the band produce no thrust). Energy adds the
    trapezoid of the electrical power at both ends of the step (exact while the force is
    constant; the force moves by a few percent per millisecond step at a 30 ms lag).

    Args:
        layout: The thrusters.

    Attributes:
        layout: The thrusters.
    """

    def __init__(self, layout: ThrusterLayout) -> None:
        if not isinstance(layout, ThrusterLayout):
            raise InputError(f"layout: expected a ThrusterLayout, got {type(layout).__name__}")
        self.layout = layout
        n = layout.size
        t = layout.thrusters
        self._lower = layout.lower.copy()
        self._upper = layout.upper.copy()
        self._tol = 1e-9 * np.maximum(self._upper, -self._lower)
        self._forward_band = np.array([x.forward_dead_band for x in t])
        self._reverse_band = np.array([x.reverse_dead_band for x in t])
        self._time_constants = np.array([x.time_constant for x in t])
        self._fits = _fits(layout)
        self._forces = np.zeros(n)
        self._command = np.zeros(n)
        self._saturated = np.zeros(n, dtype=bool)
        self._power = np.zeros(n)
        self._energy = np.zeros(n)
        self._dt = math.nan
        self._decay = np.ones(n)

    def reset(self, forces: Any = None) -> None:
        """Forces back to ``forces`` [N] (default zero; within the limits), command and energy 0."""
        f = (np.zeros(self.layout.size) if forces is None
             else as_vector(forces, "forces", self.layout.size))
        bad = np.flatnonzero((f > self._upper) | (f < self._lower))
        if bad.size:
            i = int(bad[0])
            raise InputError(f"forces: thruster {self.layout.names[i]!r} at {f[i]:g} N is "
                             f"outside its limits [{self._lower[i]:g}, {self._upper[i]:g}] N")
        self._forces[:] = f
        self._command[:] = 0.0
        self._saturated[:] = False
        self._power[:] = _power(self._forces, self._fits)
        self._energy[:] = 0.0

    def set_command(self, command: Any) -> None:
        """Hold ``command`` [N] (n,) until the next call: clamp, flag saturation, dead band.

        Raises:
            ShapeError, NonFiniteError: not n finite numbers.
        """
        c = as_vector(command, "command", self.layout.size)
        tol = self._tol
        self._saturated = (c >= self._upper - tol) | (c <= self._lower + tol)
        c = np.clip(c, self._lower, self._upper)
        band = np.where(c >= 0.0, self._forward_band, self._reverse_band)
        c[np.abs(c) < band] = 0.0
        self._command = c

    def step(self, dt: float) -> FloatArray:
        """Advance the forces over ``dt`` [s] toward the held command; returns them [N] (n,).

        Raises:
            InputError: ``dt`` not a positive finite number.
        """
        if dt != self._dt:
            dt = as_scalar(dt, "dt", positive=True)
            self._decay = np.exp(-dt / self._time_constants)
            self._dt = dt
        f, c = self._forces, self._command
        f -= c
        f *= self._decay
        f += c
        power = _power(f, self._fits)
        self._energy += 0.5 * dt * (self._power + power)
        self._power = power
        return f.copy()

    @property
    def forces(self) -> FloatArray:
        """Present thruster forces [N] (n,) (a copy)."""
        return self._forces.copy()

    @property
    def command(self) -> FloatArray:
        """The effective command the forces move toward [N] (n,): clamped, dead band applied."""
        return self._command.copy()

    @property
    def saturated(self) -> np.ndarray:
        """Thrusters whose latest command was at or beyond a force limit (n,) bool (a copy)."""
        return self._saturated.copy()

    @property
    def power(self) -> FloatArray:
        """Electrical power of each thruster at the present forces [W] (n,)."""
        return self._power.copy()

    @property
    def energy(self) -> float:
        """Electrical energy drawn by all thrusters since the last reset [J]."""
        return float(self._energy.sum())

    @property
    def energy_per_thruster(self) -> FloatArray:
        """Electrical energy drawn by each thruster since the last reset [J] (n,)."""
        return self._energy.copy()

    def wrench(self) -> FloatArray:
        """Body wrench of the present forces, ``B T`` [N, N m] (6,), FRD body frame."""
        return self.layout.matrix.dot(self._forces)
