"""V-belt drive stages: speeds, design power, belt length, arc of contact, belt
count and the load a stage puts on its shafts.

The chain follows the classical catalogue method, as used in the machine-drive
report decoded in ``../shared/reference/crank_drive.md`` (section 4):

* driven speed ``n2 = n1 d / D`` (no slip);
* design power ``P_d = P * service_factor``;
* pitch length ``L = 2C + 1.57 (D + d) + (D - d)**2 / (4C)`` and its inverse;
* arc of contact on the small pulley ``theta = pi - 2 asin(|D - d| / 2C)``;
* belt speed ``v = omega1 d / 2``; effective pull ``F_e = P / v`` (rated power,
  as the report does, not design power);
* belts ``z = P_d / (P_1 K_theta K_L)`` rounded up;
* shaft load ``F_s = (k1 F_e + z k2 v**2) sin(theta / 2)``, where ``k1 F_e`` is
  ``T1 + T2`` (``k1 = 1.5`` is ``T1 / T2 = 5``) and ``k2 v**2`` the centrifugal
  tension of both spans of one belt (``k2`` = twice the belt mass per metre).

SI inside (m, rad/s, W, N); speeds in rpm and angles in degrees exist only in
argument and field names that say so.  Every function is pure; results are
frozen dataclasses of numbers, strings, bools and tuples.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from modal.errors import ParameterError, warn
from modal.units import rpm_to_rad_s

from .._checks import finite, non_negative, positive

__all__ = [
    "BELT_LENGTH_ARC_COEFFICIENT",
    "ARC_CORRECTION_VV",
    "CorrectionTable",
    "BeltStage",
    "BeltStageSpec",
    "BeltDrive",
    "belt_stage",
    "belt_drive",
    "belt_pitch_length_m",
    "center_distance_for_length_m",
    "arc_of_contact_rad",
    "next_standard_size",
    "tension_sum_factor_from_ratio",
    "tension_ratio_from_friction",
]

#: Coefficient of ``(D + d)`` in the catalogue pitch-length formula (pi/2 rounded
#: to 1.57, as in belt catalogues and the report).
BELT_LENGTH_ARC_COEFFICIENT = 1.57


# --------------------------------------------------------------------------- tables
@dataclass(frozen=True, slots=True)
class CorrectionTable:
    """A correction factor tabulated against one variable, read by linear
    interpolation (never extrapolated).

    Parameters
    ----------
    variable : str
        What ``x`` is, e.g. ``"(D - d)/C"`` (dimensionless) or ``"pitch length (m)"``.
    x : tuple of float
        Strictly increasing abscissae, in the unit named by ``variable``.
    factor : tuple of float
        Correction factor (dimensionless, > 0) at each ``x``.
    source : str
        Where the numbers come from.
    """

    variable: str
    x: tuple[float, ...]
    factor: tuple[float, ...]
    source: str = ""

    def __post_init__(self) -> None:
        x = np.asarray(self.x, dtype=float)
        f = np.asarray(self.factor, dtype=float)
        if x.ndim != 1 or x.size < 2 or f.shape != x.shape:
            raise ParameterError(
                f"CorrectionTable {self.variable!r}: x has {x.size} values and factor {f.size}; "
                "expected two equally long sequences of at least 2 values"
            )
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
            raise ParameterError(f"CorrectionTable {self.variable!r}: x and factor must be finite")
        if np.any(np.diff(x) <= 0.0):
            raise ParameterError(f"CorrectionTable {self.variable!r}: x = {self.x} must be strictly increasing")
        if np.any(f <= 0.0):
            raise ParameterError(f"CorrectionTable {self.variable!r}: factor = {self.factor} must all be > 0")
        object.__setattr__(self, "x", tuple(float(v) for v in x))
        object.__setattr__(self, "factor", tuple(float(v) for v in f))

    def lookup(self, value: float) -> float:
        """Factor at ``value`` (linear interpolation); raises
        :class:`~modal.errors.ParameterError` outside the table."""
        number = finite(self.variable, value, "(table variable)")
        if number < self.x[0] or number > self.x[-1]:
            raise ParameterError(
                f"{self.variable} = {number:.6g} is outside the correction table "
                f"[{self.x[0]:g}, {self.x[-1]:g}] ({self.source or 'user table'}); "
                "give the factor explicitly or extend the table"
            )
        return float(np.interp(number, self.x, self.factor))


#: Arc-of-contact correction factor K_theta for V-groove to V-groove drives against
#: ``(D - d)/C``: the classical catalogue "factor G" (arc 180 deg at 0 down to 83 deg at
#: 1.5).  Replace it with your belt maker's table through ``arc_correction_table``.
ARC_CORRECTION_VV = CorrectionTable(
    variable="(D - d)/C",
    x=(0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5),
    factor=(1.00, 0.99, 0.97, 0.96, 0.94, 0.93, 0.91, 0.89, 0.87, 0.85, 0.82, 0.80, 0.77, 0.73, 0.70, 0.65),
    source="classical V-belt catalogue arc-of-contact factor G, V-V drives",
)


# --------------------------------------------------------------------------- geometry
#: fastest belt speed accepted (m/s): classical V-belts are rated to about 30 m/s, narrow wedge belts to 40-50 m/s;
#: above this a pulley diameter was given in the wrong unit
MAX_BELT_SPEED_M_S = 60.0
#: slowest belt speed not warned of (m/s): V-belt drives run 5-30 m/s; a motor speed in rad/s written as rpm runs
#: the belt about 10 times slower than meant, in rev/s 60 times
MIN_BELT_SPEED_M_S = 1.0
#: longest belt accepted (m): V-belt catalogues end near 15 m; a centre distance in mm written as m makes belts
#: hundreds of metres long
MAX_BELT_LENGTH_M = 30.0


def _check_pulleys(driver_diameter_m: float, driven_diameter_m: float, center_distance_m: float) -> tuple[float, float, float]:
    d1 = positive("driver_diameter_m", driver_diameter_m, "m")
    d2 = positive("driven_diameter_m", driven_diameter_m, "m")
    c = positive("center_distance_m", center_distance_m, "m")
    if c <= 0.5 * (d1 + d2):
        raise ParameterError(
            f"center_distance_m = {c:.6g} m is too small for pulleys of {d1:.6g} m and {d2:.6g} m: "
            f"it must exceed (D + d)/2 = {0.5 * (d1 + d2):.6g} m so that the pulleys do not overlap"
        )
    return d1, d2, c


def belt_pitch_length_m(driver_diameter_m: float, driven_diameter_m: float, center_distance_m: float) -> float:
    """Open-belt pitch length, catalogue form.

    Parameters
    ----------
    driver_diameter_m, driven_diameter_m : float
        Pitch diameters of the two pulleys, m.
    center_distance_m : float
        Centre distance C, m; must exceed the sum of the pulley radii.

    Returns
    -------
    float
        ``L = 2C + 1.57 (D + d) + (D - d)**2 / (4C)``, m.
    """
    d1, d2, c = _check_pulleys(driver_diameter_m, driven_diameter_m, center_distance_m)
    return 2.0 * c + BELT_LENGTH_ARC_COEFFICIENT * (d1 + d2) + (d2 - d1) ** 2 / (4.0 * c)


def center_distance_for_length_m(belt_length_m: float, driver_diameter_m: float, driven_diameter_m: float) -> float:
    """Centre distance that makes the catalogue pitch-length formula give ``belt_length_m``.

    Solves ``8C**2 - (4L - 6.28 (D + d)) C + (D - d)**2 = 0`` for its larger root.

    Parameters
    ----------
    belt_length_m : float
        Pitch length of the belt, m.
    driver_diameter_m, driven_diameter_m : float
        Pitch diameters, m.

    Returns
    -------
    float
        Centre distance C, m.

    Raises
    ------
    ParameterError
        If the belt is too short to wrap the two pulleys without overlap.
    """
    length = positive("belt_length_m", belt_length_m, "m")
    d1 = positive("driver_diameter_m", driver_diameter_m, "m")
    d2 = positive("driven_diameter_m", driven_diameter_m, "m")
    b = 4.0 * length - 4.0 * BELT_LENGTH_ARC_COEFFICIENT * (d1 + d2)
    discriminant = b * b - 32.0 * (d2 - d1) ** 2
    c = (b + math.sqrt(discriminant)) / 16.0 if discriminant >= 0.0 and b > 0.0 else -1.0
    if c <= 0.5 * (d1 + d2):
        minimum = belt_pitch_length_m(d1, d2, 0.5 * (d1 + d2) * (1.0 + 1e-12))
        raise ParameterError(
            f"belt_length_m = {length:.6g} m is too short for pulleys of {d1:.6g} m and {d2:.6g} m; "
            f"expected more than {minimum:.6g} m (the pulleys would overlap)"
        )
    return c


def arc_of_contact_rad(driver_diameter_m: float, driven_diameter_m: float, center_distance_m: float) -> float:
    """Arc of contact on the smaller pulley of an open belt.

    Parameters
    ----------
    driver_diameter_m, driven_diameter_m : float
        Pitch diameters, m.
    center_distance_m : float
        Centre distance, m.

    Returns
    -------
    float
        ``pi - 2 asin(|D - d| / (2C))``, rad.
    """
    d1, d2, c = _check_pulleys(driver_diameter_m, driven_diameter_m, center_distance_m)
    return math.pi - 2.0 * math.asin(abs(d2 - d1) / (2.0 * c))


def next_standard_size(value: float, series: Sequence[float], name: str = "value") -> float:
    """Smallest member of ``series`` that is >= ``value`` (within 1e-9 relative).

    Parameters
    ----------
    value : float
        The computed size (any unit, the same as ``series``).
    series : sequence of float
        Available standard sizes.
    name : str
        What the value is, for the error message.

    Returns
    -------
    float
        The standard size.

    Raises
    ------
    ParameterError
        If every member of the series is smaller than ``value``.
    """
    value = finite(name, value, "(size)")
    try:
        sizes = np.sort(np.asarray(series, dtype=float))
    except (TypeError, ValueError):
        raise ParameterError(f"standard series for {name} = {series!r}; expected a sequence of sizes") from None
    if sizes.ndim != 1 or sizes.size == 0 or not np.all(np.isfinite(sizes)):
        raise ParameterError(f"standard series for {name} = {series!r}; expected a non-empty sequence of finite sizes")
    candidates = sizes[sizes >= value * (1.0 - 1e-9)]
    if candidates.size == 0:
        raise ParameterError(
            f"{name} = {value:.6g} exceeds the largest standard size {sizes[-1]:.6g}; extend the series"
        )
    return float(candidates[0])


def tension_sum_factor_from_ratio(tension_ratio: float) -> float:
    """``k1 = (T1 + T2)/(T1 - T2) = (R + 1)/(R - 1)`` for a tight-to-slack ratio ``R``.

    Parameters
    ----------
    tension_ratio : float
        ``R = T1/T2`` (dimensionless), > 1.

    Returns
    -------
    float
        ``k1`` such that ``T1 + T2 = k1 F_e`` (``R = 5`` gives 1.5).
    """
    ratio = finite("tension_ratio", tension_ratio, "(dimensionless)")
    if ratio <= 1.0:
        raise ParameterError(f"tension_ratio = {ratio} must be > 1 (tight side tighter than slack side)")
    return (ratio + 1.0) / (ratio - 1.0)


def tension_ratio_from_friction(friction_coefficient: float, arc_of_contact_rad: float, groove_angle_rad: float = math.radians(38.0)) -> float:
    """Euler-Eytelwein ratio for a V-belt: ``T1/T2 = exp(mu theta / sin(beta/2))``.

    Parameters
    ----------
    friction_coefficient : float
        Belt-to-groove friction coefficient mu (dimensionless), > 0.
    arc_of_contact_rad : float
        Arc of contact theta on the small pulley, rad, in (0, 2 pi).
    groove_angle_rad : float
        Included groove angle beta, rad (default 38 deg).

    Returns
    -------
    float
        The tension ratio ``T1/T2`` (dimensionless).
    """
    mu = positive("friction_coefficient", friction_coefficient, "(dimensionless)")
    theta = positive("arc_of_contact_rad", arc_of_contact_rad, "rad")
    beta = positive("groove_angle_rad", groove_angle_rad, "rad")
    if theta >= 2.0 * math.pi or beta >= math.pi:
        raise ParameterError(
            f"arc_of_contact_rad = {theta:.6g}, groove_angle_rad = {beta:.6g}; expected theta < 2 pi and beta < pi"
        )
    return math.exp(mu * theta / math.sin(0.5 * beta))


# --------------------------------------------------------------------------- stage
@dataclass(frozen=True, slots=True)
class BeltStage:
    """One V-belt stage, every quantity of the catalogue chain.

    Attributes
    ----------
    name : str
        Label of the stage.
    driver_diameter_m, driven_diameter_m : float
        Pitch diameters, m.
    center_distance_m : float
        Design centre distance, m (the arc and shaft load use it).
    driver_speed_rpm, driven_speed_rpm : float
        Shaft speeds, rev/min (no slip).
    driver_speed_rad_s, driven_speed_rad_s : float
        The same, rad/s.
    speed_ratio : float
        ``D/d = n1/n2`` (dimensionless).
    power_w : float
        Rated (transmitted) power, W.
    service_factor : float
        Service factor (dimensionless).
    design_power_w : float
        ``power_w * service_factor``, W.
    belt_length_m : float
        Computed pitch length before rounding to a standard length, m.
    standard_length_m : float
        The chosen standard length, m (equal to ``belt_length_m`` when no series was given).
    standard_length_from_series : bool
        Whether ``standard_length_m`` was taken from a series.
    center_distance_for_standard_length_m : float
        Centre distance at which the standard belt fits, m.
    arc_of_contact_rad, arc_of_contact_deg : float
        Arc of contact on the smaller pulley, rad and degrees.
    belt_speed_m_s : float
        Pitch-line speed, m/s.
    effective_pull_n : float
        ``power_w / belt_speed_m_s`` (rated power, as the report), N.
    tight_side_tension_n, slack_side_tension_n : float
        ``T1, T2`` from ``T1 - T2 = F_e`` and ``T1 + T2 = k1 F_e``, all belts together, N
        (centrifugal tension excluded).
    driver_torque_n_m, driven_torque_n_m : float
        Rated power over each shaft's own speed, N m.
    arc_correction_factor, length_correction_factor : float
        K_theta and K_L (dimensionless).
    per_belt_rating_w : float
        Rated power of one belt at this speed and diameter, W (0.0 if not given).
    belts_required : float
        ``P_d / (P_1 K_theta K_L)`` (0.0 when no rating was given).
    belt_count : int
        Number of belts used (rounded up from ``belts_required`` or as given).
    belt_count_basis : str
        ``"rating"`` (rounded up from the rating), ``"given"`` or ``"default"`` (one belt, unrated).
    tension_sum_factor : float
        ``k1`` (dimensionless).
    centrifugal_factor_kg_per_m : float
        ``k2``, per belt, kg/m.
    shaft_load_n : float
        ``(k1 F_e + z k2 v**2) sin(theta/2)`` with the integer belt count, N.
    """

    name: str
    driver_diameter_m: float
    driven_diameter_m: float
    center_distance_m: float
    driver_speed_rpm: float
    driven_speed_rpm: float
    driver_speed_rad_s: float
    driven_speed_rad_s: float
    speed_ratio: float
    power_w: float
    service_factor: float
    design_power_w: float
    belt_length_m: float
    standard_length_m: float
    standard_length_from_series: bool
    center_distance_for_standard_length_m: float
    arc_of_contact_rad: float
    arc_of_contact_deg: float
    belt_speed_m_s: float
    effective_pull_n: float
    tight_side_tension_n: float
    slack_side_tension_n: float
    driver_torque_n_m: float
    driven_torque_n_m: float
    arc_correction_factor: float
    length_correction_factor: float
    per_belt_rating_w: float
    belts_required: float
    belt_count: int
    belt_count_basis: str
    tension_sum_factor: float
    centrifugal_factor_kg_per_m: float
    shaft_load_n: float


def belt_stage(
    driver_diameter_m: float,
    driven_diameter_m: float,
    center_distance_m: float,
    driver_speed_rpm: float,
    power_w: float,
    service_factor: float = 1.0,
    *,
    per_belt_rating_w: float | None = None,
    arc_correction_factor: float | None = None,
    length_correction_factor: float = 1.0,
    arc_correction_table: CorrectionTable = ARC_CORRECTION_VV,
    belt_count: int | None = None,
    tension_sum_factor: float = 1.5,
    centrifugal_factor_kg_per_m: float = 0.0,
    standard_lengths_m: Sequence[float] | None = None,
    name: str = "",
) -> BeltStage:
    """Compute one V-belt stage.

    Parameters
    ----------
    driver_diameter_m, driven_diameter_m : float
        Pitch diameters of the driving and driven pulleys, m.
    center_distance_m : float
        Centre distance, m; must exceed ``(D + d)/2``.
    driver_speed_rpm : float
        Speed of the driving shaft, rev/min, > 0.
    power_w : float
        Rated power transmitted, W, > 0.
    service_factor : float
        Service factor for the driver and load (>= 1 in practice; > 0 accepted).
    per_belt_rating_w : float, optional
        Catalogue power of one belt for this section, small-pulley diameter and speed, W.
        With it the number of belts is computed; without it ``belt_count`` (or 1) is used.
    arc_correction_factor : float, optional
        K_theta; by default looked up in ``arc_correction_table`` at ``|D - d|/C``.
    length_correction_factor : float
        K_L for the chosen belt length (dimensionless, default 1).
    arc_correction_table : CorrectionTable
        Table used when ``arc_correction_factor`` is not given (variable ``|D - d|/C``).
    belt_count : int, optional
        Number of belts; overrides the rounded-up count (it must not be below the required count).
    tension_sum_factor : float
        ``k1 = (T1 + T2)/F_e`` (default 1.5, i.e. ``T1/T2 = 5``); see
        :func:`tension_sum_factor_from_ratio`.
    centrifugal_factor_kg_per_m : float
        ``k2`` per belt, kg/m (twice the belt mass per metre; 0 neglects centrifugal tension).
    standard_lengths_m : sequence of float, optional
        Standard pitch lengths, m; the smallest one not shorter than the computed length is chosen.
    name : str
        Label of the stage.

    Returns
    -------
    BeltStage
        Every quantity of the chain.

    Raises
    ------
    ParameterError
        For non-positive diameters, speeds or power, overlapping pulleys, or a
        given belt count below the required count.
    """
    d1, d2, c = _check_pulleys(driver_diameter_m, driven_diameter_m, center_distance_m)
    n1_rpm = positive("driver_speed_rpm", driver_speed_rpm, "rpm")
    power = positive("power_w", power_w, "W")
    factor = positive("service_factor", service_factor, "(dimensionless)")
    k1 = finite("tension_sum_factor", tension_sum_factor, "(dimensionless)")
    if k1 <= 1.0:
        raise ParameterError(f"tension_sum_factor = {k1} must be > 1 ((T1 + T2)/(T1 - T2) with T2 > 0)")
    k2 = non_negative("centrifugal_factor_kg_per_m", centrifugal_factor_kg_per_m, "kg/m")
    k_length = positive("length_correction_factor", length_correction_factor, "(dimensionless)")
    if arc_correction_factor is None:
        k_arc = arc_correction_table.lookup(abs(d2 - d1) / c)
    else:
        k_arc = positive("arc_correction_factor", arc_correction_factor, "(dimensionless)")

    omega1 = float(rpm_to_rad_s(n1_rpm))
    ratio = d2 / d1
    omega2 = omega1 / ratio
    design_power = power * factor
    length = belt_pitch_length_m(d1, d2, c)
    if standard_lengths_m is not None:
        standard = next_standard_size(length, standard_lengths_m, "belt_length_m")
        c_standard = center_distance_for_length_m(standard, d1, d2)
    else:
        standard, c_standard = length, c
    theta = arc_of_contact_rad(d1, d2, c)
    speed = 0.5 * omega1 * d1
    if speed > MAX_BELT_SPEED_M_S:
        raise ParameterError(
            f"driver_diameter_m = {d1:.6g} m at {n1_rpm:.6g} rpm runs the belt at {speed:.4g} m/s; expected below "
            f"{MAX_BELT_SPEED_M_S:.0f} m/s (V-belts are rated to 30-50 m/s): diameters in mm written as m?"
        )
    if length > MAX_BELT_LENGTH_M:
        raise ParameterError(
            f"center_distance_m = {c:.6g} m with pulleys of {d1:.6g} m and {d2:.6g} m makes a belt {length:.4g} m "
            f"long; expected below {MAX_BELT_LENGTH_M:.0f} m (V-belt catalogues end near 15 m): a distance in mm "
            "written as m?")
    if speed < MIN_BELT_SPEED_M_S:
        warn(f"driver_diameter_m = {d1:.6g} m at {n1_rpm:.6g} rpm runs the belt at {speed:.3g} m/s (its pull for the "
             f"power would be {power / speed:.4g} N); V-belt drives run 5-30 m/s: a motor speed in rad/s or rev/s "
             "written as rpm?")
    pull = power / speed

    if per_belt_rating_w is not None:
        rating = positive("per_belt_rating_w", per_belt_rating_w, "W")
        required = design_power / (rating * k_arc * k_length)
        minimum_count = max(1, math.ceil(required * (1.0 - 1e-9)))
    else:
        rating, required, minimum_count = 0.0, 0.0, 1
    if belt_count is not None:
        if not isinstance(belt_count, (int, np.integer)) or isinstance(belt_count, bool) or belt_count < 1:
            raise ParameterError(f"belt_count = {belt_count!r}; expected an int >= 1 (a whole number of belts)")
        if belt_count < minimum_count:
            raise ParameterError(
                f"belt_count = {belt_count} is below the {required:.4g} belts the rating requires; "
                f"expected at least {minimum_count}"
            )
        count, basis = int(belt_count), "given"
    else:
        count, basis = minimum_count, ("rating" if per_belt_rating_w is not None else "default")

    shaft_load = (k1 * pull + count * k2 * speed**2) * math.sin(0.5 * theta)
    return BeltStage(
        name=str(name),
        driver_diameter_m=d1,
        driven_diameter_m=d2,
        center_distance_m=c,
        driver_speed_rpm=n1_rpm,
        driven_speed_rpm=n1_rpm / ratio,
        driver_speed_rad_s=omega1,
        driven_speed_rad_s=omega2,
        speed_ratio=ratio,
        power_w=power,
        service_factor=factor,
        design_power_w=design_power,
        belt_length_m=length,
        standard_length_m=standard,
        standard_length_from_series=standard_lengths_m is not None,
        center_distance_for_standard_length_m=c_standard,
        arc_of_contact_rad=theta,
        arc_of_contact_deg=math.degrees(theta),
        belt_speed_m_s=speed,
        effective_pull_n=pull,
        tight_side_tension_n=0.5 * (k1 + 1.0) * pull,
        slack_side_tension_n=0.5 * (k1 - 1.0) * pull,
        driver_torque_n_m=power / omega1,
        driven_torque_n_m=power / omega2,
        arc_correction_factor=k_arc,
        length_correction_factor=k_length,
        per_belt_rating_w=rating,
        belts_required=required,
        belt_count=count,
        belt_count_basis=basis,
        tension_sum_factor=k1,
        centrifugal_factor_kg_per_m=k2,
        shaft_load_n=shaft_load,
    )


# --------------------------------------------------------------------------- series
@dataclass(frozen=True, slots=True)
class BeltStageSpec:
    """Geometry and catalogue data of one stage of a drive in series (speed and
    power come from the stage before it).

    Attributes
    ----------
    driver_diameter_m, driven_diameter_m, center_distance_m : float
        Pulley pitch diameters and centre distance, m.
    per_belt_rating_w : float or None
        Rated power per belt, W (None: not rated, one belt unless ``belt_count``).
    arc_correction_factor : float or None
        K_theta (None: from the default table).
    length_correction_factor : float
        K_L (dimensionless).
    belt_count : int or None
        Number of belts (None: from the rating).
    tension_sum_factor : float
        k1 (dimensionless).
    centrifugal_factor_kg_per_m : float
        k2 per belt, kg/m.
    standard_lengths_m : tuple of float or None
        Standard pitch lengths, m.
    efficiency : float
        Power passed on to the next stage over power in, in (0, 1].
    name : str
        Label.
    """

    driver_diameter_m: float
    driven_diameter_m: float
    center_distance_m: float
    per_belt_rating_w: float | None = None
    arc_correction_factor: float | None = None
    length_correction_factor: float = 1.0
    belt_count: int | None = None
    tension_sum_factor: float = 1.5
    centrifugal_factor_kg_per_m: float = 0.0
    standard_lengths_m: tuple[float, ...] | None = None
    efficiency: float = 1.0
    name: str = ""


@dataclass(frozen=True, slots=True)
class BeltDrive:
    """Several belt stages in series.

    Attributes
    ----------
    stages : tuple of BeltStage
        The stages, from the motor outwards.
    input_speed_rpm, output_speed_rpm : float
        Motor speed and the last driven shaft's speed, rev/min.
    output_speed_rad_s : float
        The last driven shaft's speed, rad/s.
    overall_ratio : float
        ``input_speed / output_speed`` (dimensionless).
    output_power_w : float
        Power reaching the last shaft, W.
    """

    stages: tuple[BeltStage, ...]
    input_speed_rpm: float
    output_speed_rpm: float
    output_speed_rad_s: float
    overall_ratio: float
    output_power_w: float


def belt_drive(motor_speed_rpm: float, power_w: float, stages: Sequence[BeltStageSpec], service_factor: float = 1.0) -> BeltDrive:
    """Chain belt stages in series: each stage is driven at the speed, and with
    the power, that the previous one delivers.

    Parameters
    ----------
    motor_speed_rpm : float
        Speed of the motor shaft, rev/min.
    power_w : float
        Rated power into the first stage, W.
    stages : sequence of BeltStageSpec
        The stages, from the motor outwards (at least one).
    service_factor : float
        Service factor applied at every stage (dimensionless).

    Returns
    -------
    BeltDrive
        The stages and the output speed.
    """
    stages = tuple(stages)
    if len(stages) == 0:
        raise ParameterError("stages = []; expected at least one BeltStageSpec")
    speed_rpm = positive("motor_speed_rpm", motor_speed_rpm, "rpm")
    power = positive("power_w", power_w, "W")
    results: list[BeltStage] = []
    for index, spec in enumerate(stages):
        if not isinstance(spec, BeltStageSpec):
            raise ParameterError(f"stages[{index}] is a {type(spec).__name__}; expected a BeltStageSpec")
        efficiency = positive(f"stages[{index}].efficiency", spec.efficiency, "(dimensionless)")
        if efficiency > 1.0:
            raise ParameterError(f"stages[{index}].efficiency = {efficiency} must be in (0, 1]")
        stage = belt_stage(
            spec.driver_diameter_m,
            spec.driven_diameter_m,
            spec.center_distance_m,
            speed_rpm,
            power,
            service_factor,
            per_belt_rating_w=spec.per_belt_rating_w,
            arc_correction_factor=spec.arc_correction_factor,
            length_correction_factor=spec.length_correction_factor,
            belt_count=spec.belt_count,
            tension_sum_factor=spec.tension_sum_factor,
            centrifugal_factor_kg_per_m=spec.centrifugal_factor_kg_per_m,
            standard_lengths_m=spec.standard_lengths_m,
            name=spec.name or f"stage {index + 1}",
        )
        results.append(stage)
        speed_rpm = stage.driven_speed_rpm
        power = power * efficiency
    input_rpm = results[0].driver_speed_rpm
    return BeltDrive(
        stages=tuple(results),
        input_speed_rpm=input_rpm,
        output_speed_rpm=speed_rpm,
        output_speed_rad_s=float(rpm_to_rad_s(speed_rpm)),
        overall_ratio=input_rpm / speed_rpm,
        output_power_w=power,
    )
