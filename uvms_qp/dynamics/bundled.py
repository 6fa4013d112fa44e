"""Bundled plant parameter sets: two published BlueROV2 sets and an "Alpha-5-like" arm.

Vehicle sets (each number with its source; both papers write Fossen's model in Fossen's body
frame, x forward, y starboard, z down, which *is* the library's FRD vehicle frame, so no axis
changes; the hydrodynamic derivatives are published as negative numbers, ``M_A = -diag(X_udot,
...)`` and ``D = -diag(X_u, ...)``, and are stored here as positive magnitudes):

- :func:`von_benzon_2022_vehicle`: the BlueROV2 *Heavy* of von Benzon, Sorensen, Uth, Ouerghi,
  Gabrielsson, Johansen (2022), "An Open-Source Benchmark Simulator: Control of a BlueROV2
  Underwater Robot", J. Mar. Sci. Eng. 10(12):1898. Body origin at the centre of gravity; centre
  of buoyancy 0.01 m above it (``r_b = (0, 0, -0.01)`` m, z down); water 1000 kg/m^3, g 9.82.
- :func:`wu_2018_vehicle`: the standard BlueROV2 of Wu (2018), "6-DoF Modelling and Control of a
  Remotely Operated Vehicle", Master's thesis, Flinders University. Body origin at the centre of
  buoyancy; centre of gravity 0.02 m below it (``r_g = (0, 0, 0.02)`` m); weight 112.8 N and
  buoyancy 114.8 N, so ``V = 114.8 / (1000 * 9.81)`` m^3.

Neither paper places its body origin relative to the arm mount: the sets take their origin to be
the model's ``vehicle`` frame, the point the published mount (0.24, 0.099, -0.029) m is measured
from.

The arm (:func:`alpha5_like_links`): the vendor's per-link data may not be shipped, so the arm is
"Alpha-5-like", from a stated assumption (facts on the BlueROV2 Heavy and Reach Alpha 5): about
1.3 kg in air and 0.6 L displaced, split over the moving links in proportion to their length; each
link is a uniform solid circular cylinder along the segment from its joint to the next joint (the
last one to the tool frame), one diameter for all (from the total volume and length), with centres
of gravity and buoyancy at the segment's middle. Hydrodynamics by strip theory on that cylinder:
transverse added mass ``rho pi r^2`` per unit length (potential flow about a circle, added-mass
coefficient 1; Newman (1977), Marine Hydrodynamics, MIT Press, Chapter 4), none along the axis;
quadratic drag with a cross-flow drag coefficient 1.2 (circular cylinder below the drag crisis)
and 0.9 on the end area for flow along the axis (Hoerner (1965), Fluid-Dynamic Drag); no linear
(skin friction) damping. Damping acts at the link's frame origin (the joint): the translational
coefficients from the cylinder's projected area along each link axis, the rotational ones from
integrating the cross-flow drag of a link swinging about that axis through the joint; the moment
of a translational drag about the joint is neglected.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..errors import PlantDataError, UnknownParameterSetError
from ..model import Model
from ..model.bundled import bluerov2_heavy_alpha5
from .parameters import BodyParameters, PlantParameters
from .thrusters import ThrusterLayout

VON_BENZON_2022 = ("von Benzon, Sorensen, Uth, Ouerghi, Gabrielsson, Johansen (2022), "
                   "J. Mar. Sci. Eng. 10(12):1898")
WU_2018 = "Wu (2018), Master's thesis, Flinders University"
ALPHA5_LIKE = ("Alpha-5-like assumption: 1.3 kg, 0.6 L split by link length, uniform slender "
               "cylinders (strip-theory added mass, cross-flow drag)")

#: The assumed arm: total mass in air [kg] and displaced volume [m^3] (facts on the Reach Alpha 5).
ARM_MASS = 1.3
ARM_VOLUME = 0.6e-3
#: The arm's rated payload at full reach [kg] (mass in air; the vendor's figure of about 2 kg,
#: facts on the Reach Alpha 5). The facts give no per-joint torque rating.
ARM_RATED_PAYLOAD = 2.0
#: Added-mass coefficient of a circular section in cross-flow (2-D potential flow).
CROSS_FLOW_ADDED_MASS_COEFFICIENT = 1.0
#: Drag coefficients of the link cylinders: in cross-flow and on the end area (axial flow).
CROSS_FLOW_DRAG_COEFFICIENT = 1.2
AXIAL_DRAG_COEFFICIENT = 0.9


def von_benzon_2022_vehicle() -> BodyParameters:
    """BlueROV2 Heavy, von Benzon et al. (2022) (module docstring: frame and origin)."""
    return BodyParameters(
        mass=13.5,                                             # [kg]
        inertia=np.diag([0.26, 0.23, 0.37]),                   # Ixx, Iyy, Izz [kg m^2]
        centre_of_gravity=np.zeros(3),                         # body origin at the CG
        volume=0.0134,                                         # [m^3]
        centre_of_buoyancy=np.array([0.0, 0.0, -0.01]),        # 1 cm above the CG (z down)
        added_mass=np.diag([6.36, 7.12, 18.68, 0.189, 0.135, 0.222]),  # -X_udot .. -N_rdot
        linear_damping=np.array([13.7, 0.0, 33.0, 0.0, 0.8, 0.0]),  # -X_u .. -N_r
        quadratic_damping=np.array([141.0, 217.0, 190.0, 1.19, 0.47, 1.5]),  # -X_u|u| ..
        source=VON_BENZON_2022,
    )


def wu_2018_vehicle() -> BodyParameters:
    """Standard BlueROV2, Wu (2018) (module docstring: frame and origin).

    The inertia is taken as given about the centre of gravity; read about the body origin
    instead, Ixx and Iyy would be ``m z_g^2 = 0.0046`` kg m^2 (3 %) smaller, well inside the
    set's uncertainty.
    """
    return BodyParameters(
        mass=11.5,                                             # W = 112.8 N at g = 9.81
        inertia=np.diag([0.16, 0.16, 0.16]),
        centre_of_gravity=np.array([0.0, 0.0, 0.02]),          # 2 cm below the origin (CB)
        volume=114.8 / (1000.0 * 9.81),                        # B = 114.8 N
        centre_of_buoyancy=np.zeros(3),
        added_mass=np.diag([5.5, 12.7, 14.57, 0.12, 0.12, 0.12]),
        linear_damping=np.array([4.03, 6.22, 5.18, 0.07, 0.07, 0.07]),
        quadratic_damping=np.array([18.18, 21.66, 36.99, 1.55, 1.55, 1.55]),
        source=WU_2018,
    )


def link_segments(model: Model) -> dict[str, np.ndarray]:
    """Arm joint name -> the segment from that joint to the next (the last: to the tool) [m].

    Each segment is expressed in the frame of the body the joint moves (Pinocchio's joint frame).

    Raises:
        PlantDataError: the arm branches (a joint with several child joints).
    """
    pm = model.pin_model
    tool = pm.frames[model.frame_id("tool")]
    out: dict[str, np.ndarray] = {}
    for name in model.joint_names:
        jid = pm.getJointId(name)
        children = [c for c in range(1, pm.njoints) if pm.parents[c] == jid]
        if len(children) > 1:
            raise PlantDataError(f"model {model.name!r}: joint {name!r} carries several "
                                 "joints; the link assumption needs a serial arm")
        if children:
            out[name] = np.array(pm.jointPlacements[children[0]].translation)
        elif tool.parentJoint == jid:
            out[name] = np.array(tool.placement.translation)
        else:
            out[name] = np.zeros(3)
    return out


def _cylinder_axes(axis: np.ndarray) -> np.ndarray:
    """A rotation whose first column is the unit vector ``axis``."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    second = np.cross(axis, helper)
    second /= np.linalg.norm(second)
    return np.column_stack((axis, second, np.cross(axis, second)))


def slender_link(segment: np.ndarray, mass: float, volume: float, diameter: float,
                 water_density: float, source: str) -> BodyParameters:
    """A link as a uniform solid cylinder along ``segment`` from its frame origin.

    Args:
        segment: From the link's frame origin to its far end, link frame [m].
        mass: Mass in air [kg].
        volume: Displaced volume [m^3].
        diameter: Cylinder diameter [m].
        water_density: [kg/m^3].
        source: Provenance text.

    Returns:
        The link's parameters (module docstring: the strip-theory model).
    """
    length = float(np.linalg.norm(segment))
    centre = 0.5 * segment
    if length == 0.0:
        return BodyParameters(mass, np.zeros(3), centre, volume, centre, np.zeros(6),
                              np.zeros(6), np.zeros(6), source)
    axis = segment / length
    R = _cylinder_axes(axis)
    r = 0.5 * diameter
    axial = 0.5 * mass * r * r
    transverse = mass * (3.0 * r * r + length * length) / 12.0
    inertia = R @ np.diag([axial, transverse, transverse]) @ R.T
    # strip-theory added mass at the centre, cylinder axes, moved to the link frame origin
    section = CROSS_FLOW_ADDED_MASS_COEFFICIENT * water_density * math.pi * r * r * length
    centre_added = np.diag([0.0, section, section, 0.0,
                            section * length ** 2 / 12.0, section * length ** 2 / 12.0])
    X = pin.SE3(R, centre).inverse().action      # link-origin twist -> cylinder-centre twist
    added = X.T @ centre_added @ X
    sin = np.sqrt(np.clip(1.0 - axis * axis, 0.0, 1.0))
    end_area = math.pi * r * r
    translational = 0.5 * water_density * (CROSS_FLOW_DRAG_COEFFICIENT * diameter * length * sin
                                           + AXIAL_DRAG_COEFFICIENT * end_area * np.abs(axis))
    rotational = (water_density * CROSS_FLOW_DRAG_COEFFICIENT * diameter * length ** 4
                  * sin ** 3 / 8.0)
    return BodyParameters(
        mass=mass, inertia=inertia, centre_of_gravity=centre, volume=volume,
        centre_of_buoyancy=centre, added_mass=added, linear_damping=np.zeros(6),
        quadratic_damping=np.concatenate((translational, rotational)), source=source)


def alpha5_like_links(model: Model, water_density: float, *, mass: float = ARM_MASS,
                      volume: float = ARM_VOLUME) -> dict[str, BodyParameters]:
    """The "Alpha-5-like" arm's link bodies on ``model`` (module docstring: the assumption).

    Args:
        model: A model with a serial arm (its joint frames and tool frame give the segments).
        water_density: [kg/m^3] (for the added mass and drag).
        mass: Total arm mass in air [kg].
        volume: Total displaced volume [m^3].
    """
    segments = link_segments(model)
    lengths = {k: float(np.linalg.norm(s)) for k, s in segments.items()}
    total = sum(lengths.values())
    if total <= 0.0:
        raise PlantDataError(f"model {model.name!r}: the arm has zero length")
    diameter = math.sqrt(4.0 * volume / (math.pi * total))
    return {k: slender_link(segments[k], mass * lengths[k] / total, volume * lengths[k] / total,
                            diameter, water_density, ALPHA5_LIKE)
            for k in model.joint_names}


def _arm_model() -> Model:
    return bluerov2_heavy_alpha5()


def _carrying_the_arm(name: str, vehicle: BodyParameters, gravity: float, source: str
                      ) -> PlantParameters:
    """A bundled set: ``vehicle`` in fresh water, the Alpha-5-like arm, the Heavy's thrusters."""
    rho = 1000.0
    return PlantParameters(
        name=name, vehicle=vehicle, links=alpha5_like_links(_arm_model(), rho),
        water_density=rho, gravity=gravity, thrusters=ThrusterLayout.bluerov2_heavy(),
        rated_payload=ARM_RATED_PAYLOAD,
        source=f"{source}; arm: {ALPHA5_LIKE}; thrusters: the Heavy's eight T200 at 16 V")


@functools.cache
def bluerov2_heavy_von_benzon_2022() -> PlantParameters:
    """BlueROV2 Heavy (von Benzon et al. 2022) carrying the Alpha-5-like arm."""
    return _carrying_the_arm("bluerov2_heavy_von_benzon_2022", von_benzon_2022_vehicle(), 9.82,
                             f"vehicle: {VON_BENZON_2022}")


@functools.cache
def bluerov2_wu_2018() -> PlantParameters:
    """Standard BlueROV2 (Wu 2018) carrying the Alpha-5-like arm (on the Heavy's mount).

    It flies the Heavy's eight thrusters: the standard vehicle's six would leave roll and pitch
    passive, which the bundled model actuates.
    """
    return _carrying_the_arm("bluerov2_wu_2018", wu_2018_vehicle(), 9.81,
                             f"vehicle: {WU_2018} (with the Heavy's thrusters)")


_SETS: dict[str, Callable[[], PlantParameters]] = {
    "bluerov2_heavy_von_benzon_2022": bluerov2_heavy_von_benzon_2022,
    "bluerov2_wu_2018": bluerov2_wu_2018,
}
#: The set a model uses when none is named.
DEFAULT_SETS: dict[str, str] = {"bluerov2_heavy_alpha5": "bluerov2_heavy_von_benzon_2022"}


def plant_parameter_sets() -> list[str]:
    """Names of the bundled plant parameter sets."""
    return list(_SETS)


def plant_parameters(name: str) -> PlantParameters:
    """A bundled parameter set by name.

    Raises:
        UnknownParameterSetError: unknown name (the message lists the sets).
    """
    try:
        return _SETS[name]()
    except (KeyError, TypeError):
        raise UnknownParameterSetError(name, _SETS) from None


def default_plant_parameters(model: Model | str) -> PlantParameters:
    """The default parameter set of a model (by the model's name).

    Raises:
        PlantDataError: the model has no parameter set; the message says what a plant needs and
            how to give it.
    """
    name = model if isinstance(model, str) else model.name
    if name not in DEFAULT_SETS:
        raise PlantDataError(
            f"model {name!r} has no plant parameters: a dynamic plant needs the vehicle's mass, "
            "inertia, centres of gravity and buoyancy, displaced volume, added mass and damping, "
            "and the same for each arm link. Models with data: "
            f"{', '.join(DEFAULT_SETS)}; parameter sets: {', '.join(_SETS)}. Give your own with "
            "load_plant_parameters(path) (docs/dynamics.md)")
    return plant_parameters(DEFAULT_SETS[name])
