"""Hand-over of shaft speed and bending stiffness to a ball-balancer study."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from modal.errors import ParameterError
from modal.units import STANDARD_GRAVITY_M_S2, rad_s_to_rpm

from ..._checks import positive
from .statics import STEEL_DENSITY_KG_M3, STEEL_YOUNGS_MODULUS_PA, ShaftGeometry, _check_position
from .stiffness import (
    CriticalSpeed,
    SpeedMargin,
    bending_stiffness_n_per_m,
    critical_speed,
    rotor_layout,
    second_moment_of_area_m4,
    speed_margin,
)

__all__ = [
    "RotorHandover",
    "rotor_handover",
]


# --------------------------------------------------------------------------- hand-over
@dataclass(frozen=True, slots=True)
class RotorHandover:
    """What a ball-balancer study needs from the drive: speed, stiffness, mass,
    and how far the running speed is from the critical speed.

    Attributes
    ----------
    speed_rad_s, speed_rpm : float
        Rotor (shaft) running speed W, rad/s and rev/min.
    stiffness_n_per_m : float
        Shaft bending stiffness at the rotor, N/m (isotropic support k of the study).
    rotor_mass_kg : float
        Rotor mass M, kg.
    rotor_position_m : float
        Where the rotor sits, m.
    layout : str
        ``"between bearings"`` or ``"overhung"``.
    diameter_m : float
        Shaft diameter, m.
    flexural_rigidity_n_m2 : float
        E I, N m^2.
    rotor_natural_frequency_rad_s : float
        ``sqrt(k / M)`` (rotor on a massless shaft), rad/s.
    speed_ratio : float
        ``W / sqrt(k/M)``: the nondimensional speed of the ball-balancer model.
    critical : CriticalSpeed
        Dunkerley first critical speed with every mass and the shaft.
    margin : SpeedMargin
        1x and 2x separations from ``critical.critical_speed_rad_s``.
    """

    speed_rad_s: float
    speed_rpm: float
    stiffness_n_per_m: float
    rotor_mass_kg: float
    rotor_position_m: float
    layout: str
    diameter_m: float
    flexural_rigidity_n_m2: float
    rotor_natural_frequency_rad_s: float
    speed_ratio: float
    critical: CriticalSpeed
    margin: SpeedMargin


#: largest bending stress (Pa) the rotor's weight alone may put in the shaft: the strongest shaft steels yield near
#: 1 GPa, and a running shaft is loaded far below its yield; everyday rotors stress it a few MPa
MAX_WEIGHT_STRESS_PA = 1e9


def _check_weight_stress(geometry: ShaftGeometry, position_m: float, diameter_m: float, mass_kg: float) -> None:
    """A rotor whose weight across the shaft would bend it beyond any steel's yield: a mass in g written as kg,
    or a diameter in the wrong unit. The moment is the point load's largest: ``W a b / L`` under it between the
    bearings, ``W c`` at the bearing next to an overhang ``c``."""
    weight = mass_kg * STANDARD_GRAVITY_M_S2
    x, span = float(position_m), geometry.span_m
    if geometry.bearing_a_m < x < geometry.bearing_b_m:
        moment = weight * (x - geometry.bearing_a_m) * (geometry.bearing_b_m - x) / span
    else:
        moment = weight * (geometry.bearing_a_m - x if x < geometry.bearing_a_m else x - geometry.bearing_b_m)
    stress = moment * (0.5 * diameter_m) / second_moment_of_area_m4(diameter_m)
    if stress > MAX_WEIGHT_STRESS_PA:
        raise ParameterError(
            f"rotor_mass_kg = {mass_kg:.6g} kg at {x:.6g} m would bend the {diameter_m:.6g} m shaft at "
            f"{stress / 1e9:.3g} GPa under its weight alone; expected far below {MAX_WEIGHT_STRESS_PA / 1e9:g} GPa "
            "(the strongest shaft steels yield there): a mass in g written as kg, or the diameter in the wrong unit?")


def rotor_handover(shaft_speed_rad_s: float, geometry: ShaftGeometry, diameter_m: float, rotor_position_m: float,
                   rotor_mass_kg: float, *, other_masses_kg: Sequence[float] = (), other_positions_m: Sequence[float] = (),
                   youngs_modulus_pa: float = STEEL_YOUNGS_MODULUS_PA, density_kg_m3: float = STEEL_DENSITY_KG_M3,
                   include_shaft_mass: bool = True, required_separation: float = 0.2) -> RotorHandover:
    """Speed and stiffness for a ball-balancer study, with the critical-speed check.

    Parameters
    ----------
    shaft_speed_rad_s : float
        Running speed of the shaft carrying the rotor, rad/s (e.g. a belt stage's
        ``driven_speed_rad_s``).
    geometry : ShaftGeometry
        Shaft and bearings.
    diameter_m : float
        Shaft diameter, m (e.g. a sizing's ``standard_diameter_m``).
    rotor_position_m : float
        Where the rotor (disc, pulley) sits, m.
    rotor_mass_kg : float
        Rotor mass, kg.
    other_masses_kg, other_positions_m : sequence of float
        Further point masses on the shaft, kg and m, for Dunkerley's combination.
    youngs_modulus_pa : float
        Young's modulus, Pa.
    density_kg_m3 : float
        Shaft density, kg/m^3.
    include_shaft_mass : bool
        Whether the bare span's own mode enters the combination.
    required_separation : float
        Margin asked of the 1x and 2x checks (dimensionless).

    Returns
    -------
    RotorHandover
        Speed (rad/s), stiffness (N/m), mass and the margins.
    """
    speed = positive("shaft_speed_rad_s", shaft_speed_rad_s, "rad/s")
    mass = positive("rotor_mass_kg", rotor_mass_kg, "kg")
    position = _check_position(geometry, "rotor_position_m", rotor_position_m)
    k = bending_stiffness_n_per_m(geometry, position, diameter_m, youngs_modulus_pa)
    _check_weight_stress(geometry, position, diameter_m, mass)
    critical = critical_speed(
        geometry, diameter_m, [mass, *other_masses_kg], [position, *other_positions_m],
        youngs_modulus_pa, density_kg_m3, include_shaft_mass,
    )
    omega_rotor = math.sqrt(k / mass)
    return RotorHandover(
        speed_rad_s=speed,
        speed_rpm=float(rad_s_to_rpm(speed)),
        stiffness_n_per_m=k,
        rotor_mass_kg=mass,
        rotor_position_m=position,
        layout=rotor_layout(geometry, position),
        diameter_m=float(diameter_m),
        flexural_rigidity_n_m2=float(youngs_modulus_pa) * second_moment_of_area_m4(diameter_m),
        rotor_natural_frequency_rad_s=omega_rotor,
        speed_ratio=speed / omega_rotor,
        critical=critical,
        margin=speed_margin(speed, critical.critical_speed_rad_s, required_separation),
    )
