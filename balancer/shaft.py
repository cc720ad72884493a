"""Two-bearing shaft: reactions, bending moments and torque from point loads in
two planes; diameter by the report's Soderberg-type formula and by the ASME
code form; bending stiffness at the rotor, first critical speed (Dunkerley) and
the hand-over of speed and stiffness to a ball-balancer study.

Conventions
-----------
* The shaft runs along x from 0 to ``length_m``; bearing A at ``bearing_a_m``,
  bearing B at ``bearing_b_m`` (simple supports).  Loads outside the bearings are
  overhung.
* Forces are components along two perpendicular transverse axes called
  "vertical" and "horizontal"; a load given by magnitude and angle has
  ``vertical = F cos(angle)``, ``horizontal = F sin(angle)``, as in the report's
  free-body diagrams.  Reactions are the signed forces the bearings apply, in
  the same axes.
* Bending moment at x: ``M(x) = sum over forces left of x of F_j (x - x_j)``;
  shear ``V(x) = sum of F_j left of x`` (value just right of x at a station).
* SI inside: m, N, N m, Pa, kg, rad/s.  rpm and degrees only in names that say so.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from modal.errors import ParameterError
from modal.units import rad_s_to_rpm, rpm_to_rad_s

from .drive import _finite, _non_negative, _positive, next_standard_size

__all__ = [
    "STANDARD_SHAFT_DIAMETERS_M",
    "STEEL_YOUNGS_MODULUS_PA",
    "STEEL_DENSITY_KG_M3",
    "PointLoad",
    "ShaftGeometry",
    "ShaftAnalysis",
    "ShaftDiagram",
    "ShaftSizing",
    "CriticalSpeed",
    "SpeedMargin",
    "RotorHandover",
    "analyse_shaft",
    "bending_moment_at",
    "shaft_diagram",
    "shaft_torque_n_m",
    "endurance_limit_pa",
    "allowable_shear_stress_pa",
    "asme_allowable_shear_stress_pa",
    "shaft_diameter_soderberg",
    "shaft_diameter_asme",
    "second_moment_of_area_m4",
    "rotor_layout",
    "bending_stiffness_n_per_m",
    "span_critical_speed_rad_s",
    "critical_speed",
    "speed_margin",
    "rotor_handover",
]

#: Standard shaft sizes, m: rolling-bearing bore diameters (10 mm to 200 mm).
STANDARD_SHAFT_DIAMETERS_M: tuple[float, ...] = tuple(
    mm / 1000.0
    for mm in (10, 12, 15, 17, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80, 85, 90, 95, 100,
               105, 110, 120, 130, 140, 150, 160, 170, 180, 190, 200)
)
#: Young's modulus of carbon steel, Pa (the value assumed in the reference note).
STEEL_YOUNGS_MODULUS_PA = 205e9
#: Density of carbon steel, kg/m^3.
STEEL_DENSITY_KG_M3 = 7850.0


# --------------------------------------------------------------------------- inputs
@dataclass(frozen=True, slots=True)
class PointLoad:
    """A transverse point load on the shaft.

    Attributes
    ----------
    position_m : float
        Axial position, m, within ``[0, length_m]`` of the shaft.
    vertical_n, horizontal_n : float
        Components in the two transverse planes, N (signed).
    name : str
        Label (e.g. ``"pulley"``).
    """

    position_m: float
    vertical_n: float
    horizontal_n: float = 0.0
    name: str = ""

    @classmethod
    def from_direction(cls, position_m: float, magnitude_n: float, angle_from_vertical_deg: float, name: str = "") -> "PointLoad":
        """Load of ``magnitude_n`` N at ``angle_from_vertical_deg`` degrees from the vertical
        (``vertical = F cos``, ``horizontal = F sin``), at ``position_m`` m."""
        magnitude = _finite("magnitude_n", magnitude_n, "N")
        angle_rad = math.radians(_finite("angle_from_vertical_deg", angle_from_vertical_deg, "deg"))
        position = _finite("position_m", position_m, "m")
        return cls(position, magnitude * math.cos(angle_rad), magnitude * math.sin(angle_rad), name)


@dataclass(frozen=True, slots=True)
class ShaftGeometry:
    """A shaft on two simple supports.

    Attributes
    ----------
    length_m : float
        Shaft length, m (x from 0 to ``length_m``).
    bearing_a_m, bearing_b_m : float
        Bearing positions, m, with ``0 <= bearing_a_m < bearing_b_m <= length_m``.
    """

    length_m: float
    bearing_a_m: float
    bearing_b_m: float

    def __post_init__(self) -> None:
        length = _positive("length_m", self.length_m, "m")
        a = _finite("bearing_a_m", self.bearing_a_m, "m")
        b = _finite("bearing_b_m", self.bearing_b_m, "m")
        if not 0.0 <= a < b <= length:
            raise ParameterError(
                f"bearing_a_m = {a:.6g} m, bearing_b_m = {b:.6g} m; expected "
                f"0 <= bearing_a_m < bearing_b_m <= length_m = {length:.6g} m"
            )

    @property
    def span_m(self) -> float:
        """Distance between the bearings, m."""
        return self.bearing_b_m - self.bearing_a_m


def _check_position(geometry: ShaftGeometry, name: str, position_m: float) -> float:
    x = _finite(name, position_m, "m")
    if not 0.0 <= x <= geometry.length_m:
        raise ParameterError(
            f"{name} = {x:.6g} m is outside the shaft; expected 0 <= {name} <= length_m = {geometry.length_m:.6g} m"
        )
    return x


# --------------------------------------------------------------------------- statics
@dataclass(frozen=True, slots=True)
class ShaftAnalysis:
    """Reactions, moments and torque of a two-bearing shaft.

    Attributes
    ----------
    geometry : ShaftGeometry
        The shaft.
    force_positions_m : numpy.ndarray
        Positions of every force (loads, then reactions A and B), m.
    force_vertical_n, force_horizontal_n : numpy.ndarray
        Components of those forces, N.
    reaction_a_vertical_n, reaction_a_horizontal_n : float
        Signed reaction of bearing A, N.
    reaction_b_vertical_n, reaction_b_horizontal_n : float
        Signed reaction of bearing B, N.
    reaction_a_n, reaction_b_n : float
        Resultant bearing loads, N.
    station_positions_m : numpy.ndarray
        Shaft ends, bearings and load positions, sorted, m.
    moment_vertical_n_m, moment_horizontal_n_m, moment_resultant_n_m : numpy.ndarray
        Bending moments at the stations, N m (the resultant is ``hypot`` of the two).
    max_moment_n_m : float
        Largest resultant moment (moments are piecewise linear, so it lies at a station), N m.
    max_moment_position_m : float
        Where it occurs, m.
    torque_n_m : float
        Torque carried by the shaft, N m.
    """

    geometry: ShaftGeometry
    force_positions_m: np.ndarray
    force_vertical_n: np.ndarray
    force_horizontal_n: np.ndarray
    reaction_a_vertical_n: float
    reaction_a_horizontal_n: float
    reaction_b_vertical_n: float
    reaction_b_horizontal_n: float
    reaction_a_n: float
    reaction_b_n: float
    station_positions_m: np.ndarray
    moment_vertical_n_m: np.ndarray
    moment_horizontal_n_m: np.ndarray
    moment_resultant_n_m: np.ndarray
    max_moment_n_m: float
    max_moment_position_m: float
    torque_n_m: float


def _moments(positions: np.ndarray, forces: np.ndarray, x: np.ndarray) -> np.ndarray:
    arm = x[:, None] - positions[None, :]
    return np.sum(np.where(arm > 0.0, arm, 0.0) * forces[None, :], axis=1)


def analyse_shaft(geometry: ShaftGeometry, loads: Sequence[PointLoad], torque_n_m: float = 0.0) -> ShaftAnalysis:
    """Bearing reactions and bending moments of a shaft on two bearings.

    Parameters
    ----------
    geometry : ShaftGeometry
        Shaft length and bearing positions.
    loads : sequence of PointLoad
        Transverse point loads (at least one), each within the shaft.
    torque_n_m : float
        Torque carried by the shaft, N m (see :func:`shaft_torque_n_m`).

    Returns
    -------
    ShaftAnalysis
        Reactions, moments at every station and the largest resultant moment.

    Raises
    ------
    ParameterError
        If there are no loads or a load lies outside the shaft.
    """
    if not isinstance(geometry, ShaftGeometry):
        raise ParameterError(f"geometry is a {type(geometry).__name__}; expected a ShaftGeometry")
    if len(loads) == 0:
        raise ParameterError("loads = []; expected at least one PointLoad")
    positions, vertical, horizontal = [], [], []
    for index, load in enumerate(loads):
        if not isinstance(load, PointLoad):
            raise ParameterError(f"loads[{index}] is a {type(load).__name__}; expected a PointLoad")
        positions.append(_check_position(geometry, f"loads[{index}].position_m", load.position_m))
        vertical.append(_finite(f"loads[{index}].vertical_n", load.vertical_n, "N"))
        horizontal.append(_finite(f"loads[{index}].horizontal_n", load.horizontal_n, "N"))
    torque = _finite("torque_n_m", torque_n_m, "N m")
    x = np.asarray(positions)
    xa, xb, span = geometry.bearing_a_m, geometry.bearing_b_m, geometry.span_m

    def reactions(f: np.ndarray) -> tuple[float, float]:
        rb = -float(np.sum(f * (x - xa))) / span
        ra = -float(np.sum(f)) - rb
        return ra, rb

    fv, fh = np.asarray(vertical), np.asarray(horizontal)
    ra_v, rb_v = reactions(fv)
    ra_h, rb_h = reactions(fh)
    all_x = np.concatenate([x, [xa, xb]])
    all_v = np.concatenate([fv, [ra_v, rb_v]])
    all_h = np.concatenate([fh, [ra_h, rb_h]])
    stations = np.unique(np.concatenate([[0.0, geometry.length_m], all_x]))
    mv = _moments(all_x, all_v, stations)
    mh = _moments(all_x, all_h, stations)
    mr = np.hypot(mv, mh)
    for array in (all_x, all_v, all_h, stations, mv, mh, mr):
        array.flags.writeable = False
    peak = int(np.argmax(mr))
    return ShaftAnalysis(
        geometry=geometry,
        force_positions_m=all_x,
        force_vertical_n=all_v,
        force_horizontal_n=all_h,
        reaction_a_vertical_n=ra_v,
        reaction_a_horizontal_n=ra_h,
        reaction_b_vertical_n=rb_v,
        reaction_b_horizontal_n=rb_h,
        reaction_a_n=math.hypot(ra_v, ra_h),
        reaction_b_n=math.hypot(rb_v, rb_h),
        station_positions_m=stations,
        moment_vertical_n_m=mv,
        moment_horizontal_n_m=mh,
        moment_resultant_n_m=mr,
        max_moment_n_m=float(mr[peak]),
        max_moment_position_m=float(stations[peak]),
        torque_n_m=torque,
    )


def bending_moment_at(analysis: ShaftAnalysis, position_m: float) -> tuple[float, float]:
    """Bending moment components at ``position_m``.

    Parameters
    ----------
    analysis : ShaftAnalysis
        Result of :func:`analyse_shaft`.
    position_m : float
        Axial position, m, on the shaft.

    Returns
    -------
    tuple of float
        ``(vertical-plane moment, horizontal-plane moment)``, N m.
    """
    x = np.array([_check_position(analysis.geometry, "position_m", position_m)])
    return (
        float(_moments(analysis.force_positions_m, analysis.force_vertical_n, x)[0]),
        float(_moments(analysis.force_positions_m, analysis.force_horizontal_n, x)[0]),
    )


@dataclass(frozen=True, slots=True)
class ShaftDiagram:
    """Shear-force and bending-moment diagrams ready to plot.

    Attributes
    ----------
    position_m : numpy.ndarray
        Axial positions, m; each station appears twice (left and right values) so
        that shear jumps are vertical.
    shear_vertical_n, shear_horizontal_n : numpy.ndarray
        Shear force in each plane, N.
    moment_vertical_n_m, moment_horizontal_n_m, moment_resultant_n_m : numpy.ndarray
        Bending moment in each plane and resultant, N m.
    """

    position_m: np.ndarray
    shear_vertical_n: np.ndarray
    shear_horizontal_n: np.ndarray
    moment_vertical_n_m: np.ndarray
    moment_horizontal_n_m: np.ndarray
    moment_resultant_n_m: np.ndarray


def shaft_diagram(analysis: ShaftAnalysis, points_per_segment: int = 16) -> ShaftDiagram:
    """Sample the shear and moment diagrams of an analysed shaft.

    Parameters
    ----------
    analysis : ShaftAnalysis
        Result of :func:`analyse_shaft`.
    points_per_segment : int
        Samples inside each segment between stations (>= 2); the resultant moment
        is curved between stations when both planes carry moment.

    Returns
    -------
    ShaftDiagram
        Positions with doubled stations, shear and moment arrays.
    """
    if isinstance(points_per_segment, bool) or int(points_per_segment) != points_per_segment or points_per_segment < 2:
        raise ParameterError(f"points_per_segment = {points_per_segment!r}; expected a whole number >= 2")
    stations = analysis.station_positions_m
    pieces = [np.linspace(lo, hi, int(points_per_segment)) for lo, hi in zip(stations[:-1], stations[1:])]
    # the diagram starts just left of x = 0 and ends just right of x = L, so it closes at zero;
    # inside, the first sample of a segment is the right side of its station
    x = np.concatenate([[stations[0]], *pieces, [stations[-1]]])
    right_of = np.concatenate(
        [[False], *[np.r_[True, np.zeros(len(p) - 1, dtype=bool)] for p in pieces], [True]]
    )
    px = analysis.force_positions_m

    def shear(forces: np.ndarray) -> np.ndarray:
        left = px[None, :] < x[:, None]
        at = px[None, :] == x[:, None]
        include = left | (at & right_of[:, None])
        return np.sum(np.where(include, forces[None, :], 0.0), axis=1)

    mv = _moments(px, analysis.force_vertical_n, x)
    mh = _moments(px, analysis.force_horizontal_n, x)
    return ShaftDiagram(
        position_m=x,
        shear_vertical_n=shear(analysis.force_vertical_n),
        shear_horizontal_n=shear(analysis.force_horizontal_n),
        moment_vertical_n_m=mv,
        moment_horizontal_n_m=mh,
        moment_resultant_n_m=np.hypot(mv, mh),
    )


def shaft_torque_n_m(power_w: float, shaft_speed_rpm: float) -> float:
    """Torque ``T = P / omega`` of a shaft turning at its own speed.

    Parameters
    ----------
    power_w : float
        Power carried, W (>= 0).
    shaft_speed_rpm : float
        The shaft's own speed, rev/min (> 0).

    Returns
    -------
    float
        Torque, N m.
    """
    power = _non_negative("power_w", power_w, "W")
    speed = _positive("shaft_speed_rpm", shaft_speed_rpm, "rpm")
    return power / float(rpm_to_rad_s(speed))


# --------------------------------------------------------------------------- strength
def endurance_limit_pa(ultimate_strength_pa: float, surface_factor: float = 1.0, size_factor: float = 1.0,
                       other_factor: float = 1.0, endurance_ratio: float = 0.5) -> float:
    """Corrected endurance limit ``S_e = ratio * S_u * k_a * k_b * k_c`` (Marin-type factors).

    Parameters
    ----------
    ultimate_strength_pa : float
        Tensile strength used for the endurance limit, Pa.
    surface_factor, size_factor, other_factor : float
        Marin factors k_a, k_b and any further product (dimensionless, in (0, 1]).
    endurance_ratio : float
        Rotating-beam endurance limit over tensile strength (0.5 for steels).

    Returns
    -------
    float
        Endurance limit, Pa.
    """
    value = _positive("ultimate_strength_pa", ultimate_strength_pa, "Pa")
    for name, factor in (("surface_factor", surface_factor), ("size_factor", size_factor),
                         ("other_factor", other_factor), ("endurance_ratio", endurance_ratio)):
        f = _positive(name, factor, "(dimensionless)")
        if f > 1.0:
            raise ParameterError(f"{name} = {f} must be in (0, 1]")
        value *= f
    return value


def allowable_shear_stress_pa(yield_strength_pa: float, safety_factor: float, shear_yield_ratio: float = 0.577) -> float:
    """Allowable shear stress ``tau = ratio * S_y / N`` (distortion energy: ratio = 1/sqrt(3),
    printed as 0.577 in design tables and in the report).

    Parameters
    ----------
    yield_strength_pa : float
        Tensile yield strength, Pa.
    safety_factor : float
        Factor of safety N (>= 1).
    shear_yield_ratio : float
        Shear yield over tensile yield (default 0.577).

    Returns
    -------
    float
        Allowable shear stress, Pa.
    """
    yield_strength = _positive("yield_strength_pa", yield_strength_pa, "Pa")
    n = _positive("safety_factor", safety_factor, "(dimensionless)")
    if n < 1.0:
        raise ParameterError(f"safety_factor = {n} must be >= 1")
    ratio = _positive("shear_yield_ratio", shear_yield_ratio, "(dimensionless)")
    return ratio * yield_strength / n


def asme_allowable_shear_stress_pa(yield_strength_pa: float, ultimate_strength_pa: float, keyway: bool = True) -> float:
    """ASME shaft-code allowable shear: ``min(0.30 S_y, 0.18 S_u)``, times 0.75 with a keyway.

    Parameters
    ----------
    yield_strength_pa, ultimate_strength_pa : float
        Tensile yield and ultimate strengths, Pa.
    keyway : bool
        Whether the section has a keyway.

    Returns
    -------
    float
        Allowable shear stress, Pa.
    """
    sy = _positive("yield_strength_pa", yield_strength_pa, "Pa")
    su = _positive("ultimate_strength_pa", ultimate_strength_pa, "Pa")
    return min(0.30 * sy, 0.18 * su) * (0.75 if keyway else 1.0)


@dataclass(frozen=True, slots=True)
class ShaftSizing:
    """Shaft diameter from a combined bending-and-torsion formula.

    Attributes
    ----------
    method : str
        ``"soderberg"`` (the report's eq. 3.20) or ``"asme"`` (ASME code form).
    formula : str
        The formula, in words.
    moment_n_m, torque_n_m : float
        Design bending moment and torque, N m.
    bending_factor, torsion_factor : float
        Factors on M and T (K or K_m; K_t), dimensionless.
    stress_ratio : float
        ``S_y / S_e`` for the Soderberg form; 1 for ASME.
    allowable_shear_pa : float
        Allowable shear stress, Pa.
    equivalent_torque_n_m : float
        ``sqrt((ratio K M)**2 + (K_t T)**2)``, N m.
    diameter_m : float
        Required diameter, m.
    standard_diameter_m : float
        Next standard size, m.
    """

    method: str
    formula: str
    moment_n_m: float
    torque_n_m: float
    bending_factor: float
    torsion_factor: float
    stress_ratio: float
    allowable_shear_pa: float
    equivalent_torque_n_m: float
    diameter_m: float
    standard_diameter_m: float


def _sizing(method: str, formula: str, moment: float, torque: float, bending: float, torsion: float,
            ratio: float, tau: float, standard_diameters_m: Sequence[float]) -> ShaftSizing:
    equivalent = math.hypot(ratio * bending * moment, torsion * torque)
    if equivalent == 0.0:
        raise ParameterError("moment_n_m and torque_n_m are both 0; expected a loaded shaft")
    diameter = (16.0 * equivalent / (math.pi * tau)) ** (1.0 / 3.0)
    return ShaftSizing(
        method=method,
        formula=formula,
        moment_n_m=moment,
        torque_n_m=torque,
        bending_factor=bending,
        torsion_factor=torsion,
        stress_ratio=ratio,
        allowable_shear_pa=tau,
        equivalent_torque_n_m=equivalent,
        diameter_m=diameter,
        standard_diameter_m=next_standard_size(diameter, standard_diameters_m, "diameter_m"),
    )


def shaft_diameter_soderberg(moment_n_m: float, torque_n_m: float, yield_strength_pa: float,
                             endurance_limit_pa: float, allowable_shear_pa: float, bending_factor: float = 1.0,
                             standard_diameters_m: Sequence[float] = STANDARD_SHAFT_DIAMETERS_M) -> ShaftSizing:
    """Diameter by the report's fatigue formula (eq. 3.20, Soderberg-type maximum shear):
    ``tau_allow = 16 / (pi d**3) * sqrt(((S_y/S_e) K M)**2 + T**2)``.

    Parameters
    ----------
    moment_n_m : float
        Design (resultant) bending moment, N m (>= 0).
    torque_n_m : float
        Torque, N m (>= 0).
    yield_strength_pa : float
        Tensile yield strength S_y, Pa.
    endurance_limit_pa : float
        Corrected endurance limit S_e, Pa (see :func:`endurance_limit_pa`).
    allowable_shear_pa : float
        Allowable shear stress, Pa (see :func:`allowable_shear_stress_pa`).
    bending_factor : float
        Fatigue stress-concentration factor K on the moment (the report uses 1.8).
    standard_diameters_m : sequence of float
        Standard sizes, m, for the rounded-up diameter.

    Returns
    -------
    ShaftSizing
        Diameter and next standard size (method ``"soderberg"``).
    """
    moment = _non_negative("moment_n_m", moment_n_m, "N m")
    torque = _non_negative("torque_n_m", torque_n_m, "N m")
    sy = _positive("yield_strength_pa", yield_strength_pa, "Pa")
    se = _positive("endurance_limit_pa", endurance_limit_pa, "Pa")
    tau = _positive("allowable_shear_pa", allowable_shear_pa, "Pa")
    k = _positive("bending_factor", bending_factor, "(dimensionless)")
    return _sizing("soderberg", "d = [16/(pi tau) sqrt(((Sy/Se) K M)^2 + T^2)]^(1/3)",
                   moment, torque, k, 1.0, sy / se, tau, standard_diameters_m)


def shaft_diameter_asme(moment_n_m: float, torque_n_m: float, allowable_shear_pa: float, bending_factor: float = 1.5,
                        torsion_factor: float = 1.0,
                        standard_diameters_m: Sequence[float] = STANDARD_SHAFT_DIAMETERS_M) -> ShaftSizing:
    """Diameter by the ASME code form: ``d**3 = 16/(pi tau) sqrt((K_m M)**2 + (K_t T)**2)``.

    Parameters
    ----------
    moment_n_m, torque_n_m : float
        Design bending moment and torque, N m (>= 0).
    allowable_shear_pa : float
        Allowable shear, Pa (see :func:`asme_allowable_shear_stress_pa`).
    bending_factor, torsion_factor : float
        Combined shock and fatigue factors K_m and K_t (defaults 1.5 and 1.0, the
        values commonly tabulated for a rotating shaft with gradually applied load;
        take them from your code's table).
    standard_diameters_m : sequence of float
        Standard sizes, m.

    Returns
    -------
    ShaftSizing
        Diameter and next standard size (method ``"asme"``).
    """
    moment = _non_negative("moment_n_m", moment_n_m, "N m")
    torque = _non_negative("torque_n_m", torque_n_m, "N m")
    tau = _positive("allowable_shear_pa", allowable_shear_pa, "Pa")
    km = _positive("bending_factor", bending_factor, "(dimensionless)")
    kt = _positive("torsion_factor", torsion_factor, "(dimensionless)")
    return _sizing("asme", "d = [16/(pi tau) sqrt((Km M)^2 + (Kt T)^2)]^(1/3)",
                   moment, torque, km, kt, 1.0, tau, standard_diameters_m)


# --------------------------------------------------------------------------- stiffness
def second_moment_of_area_m4(diameter_m: float) -> float:
    """``I = pi d**4 / 64`` of a solid round shaft, m^4 (``diameter_m`` in m)."""
    d = _positive("diameter_m", diameter_m, "m")
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
    ei = _positive("youngs_modulus_pa", youngs_modulus_pa, "Pa") * second_moment_of_area_m4(diameter_m)
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
    span = _positive("span_m", span_m, "m")
    e = _positive("youngs_modulus_pa", youngs_modulus_pa, "Pa")
    rho = _positive("density_kg_m3", density_kg_m3, "kg/m^3")
    d = _positive("diameter_m", diameter_m, "m")
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
        m = _positive(f"masses_kg[{index}]", mass, "kg")
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
    w = _positive("running_speed_rad_s", running_speed_rad_s, "rad/s")
    wc = _positive("critical_speed_rad_s", critical_speed_rad_s, "rad/s")
    required = _non_negative("required_separation", required_separation, "(dimensionless)")
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
    speed = _positive("shaft_speed_rad_s", shaft_speed_rad_s, "rad/s")
    mass = _positive("rotor_mass_kg", rotor_mass_kg, "kg")
    position = _check_position(geometry, "rotor_position_m", rotor_position_m)
    k = bending_stiffness_n_per_m(geometry, position, diameter_m, youngs_modulus_pa)
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
