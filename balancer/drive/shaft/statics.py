"""Shaft inputs (geometry, point loads) and statics: bearing reactions, bending moments
and torque in two planes, and the moment diagram."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from modal.errors import ParameterError
from modal.units import rpm_to_rad_s

from ..._checks import finite, non_negative, positive

__all__ = [
    "STANDARD_SHAFT_DIAMETERS_M",
    "STEEL_YOUNGS_MODULUS_PA",
    "STEEL_DENSITY_KG_M3",
    "PointLoad",
    "ShaftGeometry",
    "ShaftAnalysis",
    "ShaftDiagram",
    "analyse_shaft",
    "bending_moment_at",
    "shaft_diagram",
    "shaft_torque_n_m",
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
        magnitude = finite("magnitude_n", magnitude_n, "N")
        angle_rad = math.radians(finite("angle_from_vertical_deg", angle_from_vertical_deg, "deg"))
        position = finite("position_m", position_m, "m")
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
        length = positive("length_m", self.length_m, "m")
        a = finite("bearing_a_m", self.bearing_a_m, "m")
        b = finite("bearing_b_m", self.bearing_b_m, "m")
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
    x = finite(name, position_m, "m")
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
        vertical.append(finite(f"loads[{index}].vertical_n", load.vertical_n, "N"))
        horizontal.append(finite(f"loads[{index}].horizontal_n", load.horizontal_n, "N"))
    torque = finite("torque_n_m", torque_n_m, "N m")
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
    power = non_negative("power_w", power_w, "W")
    speed = positive("shaft_speed_rpm", shaft_speed_rpm, "rpm")
    return power / float(rpm_to_rad_s(speed))
