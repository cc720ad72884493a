"""Shaft stiffness at the rotor, first critical speed (Dunkerley) and the margin of the
running speed from it."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from modal.errors import ParameterError
from modal.units import rad_s_to_rpm

from ..._checks import non_negative, positive
from .statics import STEEL_DENSITY_KG_M3, STEEL_YOUNGS_MODULUS_PA, ShaftGeometry, _check_position

__all__ = [
    "CriticalSpeed",
    "SpeedMargin",
    "second_moment_of_area_m4",
    "rotor_layout",
    "bending_stiffness_n_per_m",
    "span_critical_speed_rad_s",
    "critical_speed",
    "speed_margin",
]


# --------------------------------------------------------------------------- stiffness
def second_moment_of_area_m4(diameter_m: float) -> float:
    """``I = pi d**4 / 64`` of a solid round shaft, m^4.

    Parameters
    ----------
    diameter_m : float
        Shaft diameter, m (> 0).
    """
    d = positive("diameter_m", diameter_m, "m")
    return math.pi * d**4 / 64.0


def rotor_layout(geometry: ShaftGeometry, position_m: float) -> str:
    """Where a rotor sits relative to the bearings.

    Parameters
    ----------
    geometry : ShaftGeometry
        Shaft and bearings.
    position_m : float
        Rotor position, m.

    Returns
    -------
    str
        ``"between bearings"`` or ``"overhung"``.

    Raises
    ------
    ParameterError
        At a bearing (a simply supported shaft is rigid there) or off the shaft.
    """
    x = _check_position(geometry, "position_m", position_m)
    if x == geometry.bearing_a_m or x == geometry.bearing_b_m:
        raise ParameterError(
            f"position_m = {x:.6g} m is at a bearing, where a simply supported shaft is rigid; "
            "expected a position between the bearings or on an overhang"
        )
    return "between bearings" if geometry.bearing_a_m < x < geometry.bearing_b_m else "overhung"


#: Young's moduli accepted (Pa): from engineering plastics (PTFE 0.5 GPa, nylon 3 GPa) to tungsten carbide
#: (about 700 GPa) with room on either side; a modulus in GPa or MPa written as Pa lies far below
SOLID_MODULUS_RANGE_PA = (1e8, 1.2e12)


def solid_modulus_pa(youngs_modulus_pa: float) -> float:
    """``youngs_modulus_pa`` checked to be a solid shaft's modulus (:data:`SOLID_MODULUS_RANGE_PA`).

    Raises
    ------
    ParameterError
        Not a positive number, or outside the range: a modulus in GPa or MPa written as Pa.
    """
    modulus = positive("youngs_modulus_pa", youngs_modulus_pa, "Pa")
    low, high = SOLID_MODULUS_RANGE_PA
    if not low <= modulus <= high:
        raise ParameterError(
            f"youngs_modulus_pa = {modulus:.6g} Pa; expected a solid shaft's modulus, {low / 1e9:g}-{high / 1e9:g} GPa "
            "(steel 205 GPa, aluminium 70 GPa, nylon 3 GPa): a modulus in GPa or MPa written as Pa?")
    return modulus


def bending_stiffness_n_per_m(geometry: ShaftGeometry, position_m: float, diameter_m: float,
                              youngs_modulus_pa: float = STEEL_YOUNGS_MODULUS_PA) -> float:
    """Transverse bending stiffness of a uniform shaft at ``position_m`` (load and deflection there).

    Between the bearings, a from A and b from B on span L: ``k = 3 E I L / (a**2 b**2)``
    (``48 E I / L**3`` at mid-span).  Overhang c beyond a bearing:
    ``k = 3 E I / (c**2 (L + c))``.

    Parameters
    ----------
    geometry : ShaftGeometry
        Shaft and bearings (simple supports).
    position_m : float
        Where the rotor sits, m.
    diameter_m : float
        Shaft diameter, m.
    youngs_modulus_pa : float
        Young's modulus, Pa.

    Returns
    -------
    float
        Stiffness, N/m.
    """
    layout = rotor_layout(geometry, position_m)
    ei = solid_modulus_pa(youngs_modulus_pa) * second_moment_of_area_m4(diameter_m)
    if diameter_m >= geometry.length_m:
        raise ParameterError(
            f"diameter_m = {diameter_m:.6g} m is not below the shaft's length_m = {geometry.length_m:.6g} m; expected "
            "a slender shaft (the bending formulas hold for lengths many diameters long): a diameter in mm written as m?")
    x, span = float(position_m), geometry.span_m
    if layout == "between bearings":
        a, b = x - geometry.bearing_a_m, geometry.bearing_b_m - x
        stiffness = 3.0 * ei * span / (a * b) / (a * b)  # a*b first: a*a*b*b underflows near a bearing
    else:
        c = geometry.bearing_a_m - x if x < geometry.bearing_a_m else x - geometry.bearing_b_m
        stiffness = 3.0 * ei / c / (c * (span + c))
    if not math.isfinite(stiffness):
        raise ParameterError(
            f"position_m = {position_m!r} m lies (numerically) on a bearing: the shaft's stiffness there is "
            "unbounded; expected a rotor position away from the bearings")
    return stiffness


def span_critical_speed_rad_s(span_m: float, diameter_m: float, youngs_modulus_pa: float = STEEL_YOUNGS_MODULUS_PA,
                              density_kg_m3: float = STEEL_DENSITY_KG_M3) -> float:
    """First bending critical speed of the bare shaft span, simply supported:
    ``omega = (pi/L)**2 sqrt(E I / (rho A))`` (overhang mass ignored).

    Parameters
    ----------
    span_m : float
        Bearing span, m.
    diameter_m : float
        Shaft diameter, m.
    youngs_modulus_pa : float
        Young's modulus, Pa.
    density_kg_m3 : float
        Density, kg/m^3.

    Returns
    -------
    float
        Critical speed, rad/s.
    """
    span = positive("span_m", span_m, "m")
    e = positive("youngs_modulus_pa", youngs_modulus_pa, "Pa")
    rho = positive("density_kg_m3", density_kg_m3, "kg/m^3")
    d = positive("diameter_m", diameter_m, "m")
    area = math.pi * d * d / 4.0
    return (math.pi / span) ** 2 * math.sqrt(e * second_moment_of_area_m4(d) / (rho * area))


@dataclass(frozen=True, slots=True)
class CriticalSpeed:
    """First critical speed by Dunkerley's combination ``1/w**2 = sum 1/w_i**2``
    (a lower bound on the true first critical speed).

    Attributes
    ----------
    partial_labels : tuple of str
        What each partial speed is (``"shaft span"``, ``"mass 1 at 1.3 m"``...).
    partial_speeds_rad_s : numpy.ndarray
        Each mass alone on the massless shaft, ``sqrt(k_ii / m_i)``, and the bare shaft, rad/s.
    critical_speed_rad_s : float
        Dunkerley's combination, rad/s.
    critical_speed_rpm : float
        The same, rev/min.
    """

    partial_labels: tuple[str, ...]
    partial_speeds_rad_s: np.ndarray
    critical_speed_rad_s: float
    critical_speed_rpm: float


def critical_speed(geometry: ShaftGeometry, diameter_m: float, masses_kg: Sequence[float], positions_m: Sequence[float],
                   youngs_modulus_pa: float = STEEL_YOUNGS_MODULUS_PA, density_kg_m3: float = STEEL_DENSITY_KG_M3,
                   include_shaft_mass: bool = True) -> CriticalSpeed:
    """First critical speed of a shaft carrying point masses, by Dunkerley.

    Parameters
    ----------
    geometry : ShaftGeometry
        Shaft and bearings.
    diameter_m : float
        Shaft diameter, m.
    masses_kg : sequence of float
        Point masses (rotors, pulleys), kg, > 0.
    positions_m : sequence of float
        Their positions, m (not at a bearing).
    youngs_modulus_pa : float
        Young's modulus, Pa.
    density_kg_m3 : float
        Shaft density, kg/m^3 (used when ``include_shaft_mass``).
    include_shaft_mass : bool
        Whether the bare span's own first mode enters the combination.

    Returns
    -------
    CriticalSpeed
        Partial speeds and their combination.
    """
    if len(masses_kg) != len(positions_m):
        raise ParameterError(
            f"masses_kg has {len(masses_kg)} values and positions_m {len(positions_m)}; expected equal lengths"
        )
    if len(masses_kg) == 0 and not include_shaft_mass:
        raise ParameterError("masses_kg = [] and include_shaft_mass = False; expected something that vibrates")
    labels: list[str] = []
    speeds: list[float] = []
    for index, (mass, position) in enumerate(zip(masses_kg, positions_m)):
        m = positive(f"masses_kg[{index}]", mass, "kg")
        x = _check_position(geometry, f"positions_m[{index}]", position)
        k = bending_stiffness_n_per_m(geometry, x, diameter_m, youngs_modulus_pa)
        labels.append(f"mass {index + 1} ({m:g} kg at {x:g} m, {rotor_layout(geometry, x)})")
        speeds.append(math.sqrt(k / m))
    if include_shaft_mass:
        labels.append("shaft span (simply supported)")
        speeds.append(span_critical_speed_rad_s(geometry.span_m, diameter_m, youngs_modulus_pa, density_kg_m3))
    partial = np.asarray(speeds)
    combined = float(1.0 / math.sqrt(float(np.sum(1.0 / partial**2))))
    return CriticalSpeed(
        partial_labels=tuple(labels),
        partial_speeds_rad_s=partial,
        critical_speed_rad_s=combined,
        critical_speed_rpm=float(rad_s_to_rpm(combined)),
    )


@dataclass(frozen=True, slots=True)
class SpeedMargin:
    """Separation of the running speed (1x) and its double (2x) from a critical speed.

    Separation at harmonic h is ``|w_c / (h W) - 1|``: the critical speed's distance
    from the excitation frequency ``h W``, as a fraction of it.

    Attributes
    ----------
    running_speed_rad_s, critical_speed_rad_s : float
        W and w_c, rad/s.
    critical_to_running_ratio : float
        ``w_c / W``.
    separation_1x, separation_2x : float
        Separations at 1x and 2x (dimensionless).
    required_separation : float
        The margin asked for (dimensionless).
    ok_1x, ok_2x : bool
        Whether each separation meets it.
    supercritical : bool
        Whether the shaft runs above the critical speed (W > w_c), which an
        automatic ball balancer needs in order to balance.
    """

    running_speed_rad_s: float
    critical_speed_rad_s: float
    critical_to_running_ratio: float
    separation_1x: float
    separation_2x: float
    required_separation: float
    ok_1x: bool
    ok_2x: bool
    supercritical: bool


def speed_margin(running_speed_rad_s: float, critical_speed_rad_s: float, required_separation: float = 0.2) -> SpeedMargin:
    """Check the running speed and twice it against a critical speed.

    Parameters
    ----------
    running_speed_rad_s : float
        Shaft speed W, rad/s.
    critical_speed_rad_s : float
        First critical speed w_c, rad/s.
    required_separation : float
        Minimum ``|w_c/(h W) - 1|`` (default 0.2, i.e. 20 %).

    Returns
    -------
    SpeedMargin
        Ratios and pass/fail flags at 1x and 2x.
    """
    w = positive("running_speed_rad_s", running_speed_rad_s, "rad/s")
    wc = positive("critical_speed_rad_s", critical_speed_rad_s, "rad/s")
    required = non_negative("required_separation", required_separation, "(dimensionless)")
    s1 = abs(wc / w - 1.0)
    s2 = abs(wc / (2.0 * w) - 1.0)
    return SpeedMargin(
        running_speed_rad_s=w,
        critical_speed_rad_s=wc,
        critical_to_running_ratio=wc / w,
        separation_1x=s1,
        separation_2x=s2,
        required_separation=required,
        ok_1x=bool(s1 >= required),
        ok_2x=bool(s2 >= required),
        supercritical=bool(w > wc),
    )
