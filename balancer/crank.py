"""Slider-crank shaking forces and the crank counterweight that minimises them.

Model (seed 000, eqs. 1 and 9-11; seed 004, eqs. 3-5)
-----------------------------------------------------
A crank of radius ``r`` turns at a constant angular speed ``omega``; the crank
angle ``theta`` is measured from top dead centre, the piston moves along ``y``
and ``x`` is perpendicular to the stroke in the plane of the crank.  The rod is
split into two lumped masses (:func:`two_mass_split`), so the mechanism is a
rotating mass ``m_rot`` at the crank pin and a reciprocating mass ``m_rec`` at
the wrist pin.  A counterweight of mass ``m_c`` at radius ``r_c`` sits opposite
the crank pin.  The shaking force on the frame is::

    F_x = (m_c r_c - m_rot r) omega**2 sin(theta)
    F_y = (m_rot r - m_c r_c) omega**2 cos(theta) + m_rec r omega**2 A(theta)

with the piston's acceleration factor ``A`` (``-r omega**2 A`` is the piston
acceleration).  Exactly, with ``lam = r / l`` and ``D = sqrt(1 - lam**2 sin**2)``::

    A = cos(theta) + lam cos(2 theta) / D + lam**3 sin(2 theta)**2 / (4 D**3)

or as a harmonic series ``A = sum_h a_h cos(h theta)``.  The papers keep
``h = 1, 2`` with the leading coefficients ``a_1 = 1, a_2 = lam``
(``a_4 = -lam**3/4``, ``a_6 = 9 lam**5/128``).  The rod-inertia couple of the
two-mass model is ``M_z = -J_AB lam omega**2 B(theta)`` with
``B = (1 - lam**2) sin(theta) / D**3`` exactly, or the series
``sin(theta) - (3 lam**2/8) sin(3 theta) + (15 lam**4/128) sin(5 theta)``.

The force depends on the counterweight only through ``u = m_c r_c``.  The
*balance fraction* ``alpha`` is defined by ``u = (m_rot + alpha m_rec) r``.  The
resultant scaled by ``m_rec r omega**2`` depends only on ``alpha`` and
``lam``, so the optimal ``alpha`` does not depend on speed.  The peak resultant
force over a revolution is convex in ``alpha`` (a maximum of norms of affine
maps), so :func:`optimal_counterweight` solves it exactly.

Everything is SI inside (m, kg, N, rad, rad/s); rpm appears only in argument
names ``speed_rpm``.  ``|F|`` is even in ``theta`` for every model here, so
maxima over a revolution are searched on ``[0, pi]``.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy import optimize

from modal.errors import ParameterError
from modal.units import rpm_to_rad_s

__all__ = [
    "SliderCrank",
    "RodSplit",
    "ShakingForce",
    "ShakingHarmonics",
    "CounterweightEvaluation",
    "OptimalCurve",
    "OptimalCounterweight",
    "Counterweight",
    "GridSearchResult",
    "PAPER_RULES",
    "two_mass_split",
    "slider_crank_from_components",
    "balance_fraction",
    "counterweight_mass",
    "counterweight_moment",
    "shaking_force",
    "shaking_harmonics",
    "max_shaking_force",
    "shaking_objective",
    "evaluate_counterweight",
    "evaluate_balance_fraction",
    "optimal_counterweight",
    "counterweight_on_curve",
    "grid_search_counterweight",
]

Objective = Literal["max", "rms", "max_x", "max_y"]
OBJECTIVES: tuple[str, ...] = ("max", "rms", "max_x", "max_y")

#: Balance fractions of the papers' rules (seed 004, section 3.1): the rotating
#: mass only (``m_dt r = m_tq R``) and the rotating mass plus half of the
#: reciprocating mass (``m_dt r = R (m_tq + 0.5 m_ct)``).
PAPER_RULES: dict[str, float] = {
    "rotating": 0.0,
    "rotating_plus_half_reciprocating": 0.5,
}

_MAX_SERIES_ORDER = 32
_LEADING_ORDERS = (1, 2, 3, 4, 5, 6)
_N_FFT = 512
# Grid on [0, pi] that brackets every local maximum before refinement; peaks of
# |F| for lam < 1 are tens of degrees apart, far wider than this step.
_N_GRID_HALF_TURN = 721


# --------------------------------------------------------------------------- input checks
def _finite_float(name: str, value, *, minimum: float | None = None,
                  strict: bool = False, maximum: float | None = None) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r}: expected a real number") from None
    if not math.isfinite(number):
        raise ParameterError(f"{name} = {value!r}: expected a finite number")
    if minimum is not None:
        if strict and not number > minimum:
            raise ParameterError(f"{name} = {number!r}: expected a value > {minimum}")
        if not strict and not number >= minimum:
            raise ParameterError(f"{name} = {number!r}: expected a value >= {minimum}")
    if maximum is not None and number > maximum:
        raise ParameterError(f"{name} = {number!r}: expected a value <= {maximum}")
    return number


def _speed_rad_s(speed_rpm) -> float:
    speed = _finite_float("speed_rpm", speed_rpm, minimum=0.0, strict=True)
    return float(rpm_to_rad_s(speed))


def _angles(values, name: str = "crank_angles_rad", unit: str = "rad") -> np.ndarray:
    """A finite, non-empty 1-D float array (crank angles by default)."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {values!r}: expected an array of numbers in {unit}") from None
    if array.ndim > 1 or array.size == 0:
        raise ParameterError(f"{name} has shape {array.shape}: expected a non-empty 1-D array")
    if not np.all(np.isfinite(array)):
        raise ParameterError(f"{name} contains NaN or infinity: expected finite values in {unit}")
    return np.atleast_1d(array)


# --------------------------------------------------------------------------- mechanism
@dataclass(frozen=True)
class SliderCrank:
    """A single-cylinder slider-crank reduced to two lumped masses.

    Parameters
    ----------
    crank_radius_m : float
        Crank radius ``r`` [m], > 0.
    rod_length_m : float
        Connecting-rod length ``l`` between the pin centres [m], > ``r``.
    rotating_mass_kg : float
        Mass lumped at the crank pin, ``m_rot`` [kg], >= 0.
    reciprocating_mass_kg : float
        Mass lumped at the wrist pin, ``m_rec`` [kg], >= 0.
    harmonics : tuple of int or "exact"
        Harmonic orders kept in the series (the papers keep ``(1, 2)``), or
        ``"exact"`` for the exact piston acceleration and rod couple.
    rod_inertia_correction_kg_m2 : float
        ``J_AB = J_G - m_G a b`` [kg m^2], the rod inertia the two-mass model
        misses; only the couple ``M_z`` uses it.  May be negative.
    series : {"leading", "fourier"}
        Series coefficients: ``"leading"`` takes the leading term in ``lam``
        of each harmonic (the papers' eq. 1); ``"fourier"`` takes the exact
        Fourier coefficients of the exact kinematics.  Ignored for ``"exact"``.
    """

    crank_radius_m: float
    rod_length_m: float
    rotating_mass_kg: float
    reciprocating_mass_kg: float
    harmonics: tuple[int, ...] | str = (1, 2)
    rod_inertia_correction_kg_m2: float = 0.0
    series: str = "leading"

    def __post_init__(self) -> None:
        radius = _finite_float("crank_radius_m", self.crank_radius_m, minimum=0.0, strict=True)
        length = _finite_float("rod_length_m", self.rod_length_m, minimum=0.0, strict=True)
        if not length > radius:
            raise ParameterError(
                f"rod_length_m = {length!r} with crank_radius_m = {radius!r}: the rod must be "
                "longer than the crank (rod_length_m > crank_radius_m)")
        m_rot = _finite_float("rotating_mass_kg", self.rotating_mass_kg, minimum=0.0)
        m_rec = _finite_float("reciprocating_mass_kg", self.reciprocating_mass_kg, minimum=0.0)
        j_ab = _finite_float("rod_inertia_correction_kg_m2", self.rod_inertia_correction_kg_m2)
        if self.series not in ("leading", "fourier"):
            raise ParameterError(
                f"series = {self.series!r}: expected 'leading' or 'fourier'")
        harmonics = self.harmonics
        if isinstance(harmonics, str):
            if harmonics != "exact":
                raise ParameterError(
                    f"harmonics = {harmonics!r}: expected 'exact' or a tuple of orders such as (1, 2)")
        else:
            try:
                orders = sorted({int(h) for h in harmonics})
                exact_ints = all(float(h) == int(h) for h in harmonics)
            except (TypeError, ValueError):
                raise ParameterError(
                    f"harmonics = {harmonics!r}: expected 'exact' or a tuple of positive integers"
                ) from None
            limit = 6 if self.series == "leading" else _MAX_SERIES_ORDER
            if not orders or not exact_ints or orders[0] < 1 or orders[-1] > limit:
                raise ParameterError(
                    f"harmonics = {harmonics!r}: expected a non-empty tuple of integer orders "
                    f"1..{limit} for series = {self.series!r}")
            harmonics = tuple(orders)
        for name, value in (("crank_radius_m", radius), ("rod_length_m", length),
                            ("rotating_mass_kg", m_rot), ("reciprocating_mass_kg", m_rec),
                            ("rod_inertia_correction_kg_m2", j_ab), ("harmonics", harmonics)):
            object.__setattr__(self, name, value)

    @property
    def crank_rod_ratio(self) -> float:
        """``lam = r / l`` (dimensionless)."""
        return self.crank_radius_m / self.rod_length_m

    @property
    def is_exact(self) -> bool:
        """True when the exact kinematics are used."""
        return self.harmonics == "exact"


@dataclass(frozen=True)
class RodSplit:
    """Two-mass split of a connecting rod (Genta), all in SI units.

    Attributes
    ----------
    rotating_mass_kg, reciprocating_mass_kg : float
        ``m_A + m_G b/l`` and ``m_B + m_G a/l`` [kg].
    rod_inertia_correction_kg_m2 : float
        ``J_AB = J_G - m_G a b`` [kg m^2].
    """

    rotating_mass_kg: float
    reciprocating_mass_kg: float
    rod_inertia_correction_kg_m2: float


def two_mass_split(rod_length_m: float, rod_mass_kg: float, rod_cg_to_crank_pin_m: float,
                   crank_pin_mass_kg: float = 0.0, piston_mass_kg: float = 0.0,
                   rod_inertia_about_cg_kg_m2: float = 0.0) -> RodSplit:
    """Lump a connecting rod and its neighbours into rotating and reciprocating masses.

    Parameters
    ----------
    rod_length_m : float
        Pin-centre distance ``l = a + b`` [m], > 0.
    rod_mass_kg : float
        Rod mass ``m_G`` [kg], >= 0.
    rod_cg_to_crank_pin_m : float
        ``a``, the distance from the rod's centre of gravity to the crank pin [m],
        in ``[0, l]``.
    crank_pin_mass_kg : float
        ``m_A``, the crank's mass reduced to the crank pin [kg], >= 0.
    piston_mass_kg : float
        ``m_B``, piston plus wrist pin [kg], >= 0.
    rod_inertia_about_cg_kg_m2 : float
        ``J_G`` [kg m^2], >= 0.

    Returns
    -------
    RodSplit
    """
    length = _finite_float("rod_length_m", rod_length_m, minimum=0.0, strict=True)
    m_g = _finite_float("rod_mass_kg", rod_mass_kg, minimum=0.0)
    a = _finite_float("rod_cg_to_crank_pin_m", rod_cg_to_crank_pin_m, minimum=0.0,
                      maximum=length)
    m_a = _finite_float("crank_pin_mass_kg", crank_pin_mass_kg, minimum=0.0)
    m_b = _finite_float("piston_mass_kg", piston_mass_kg, minimum=0.0)
    j_g = _finite_float("rod_inertia_about_cg_kg_m2", rod_inertia_about_cg_kg_m2, minimum=0.0)
    b = length - a
    return RodSplit(rotating_mass_kg=m_a + m_g * b / length,
                    reciprocating_mass_kg=m_b + m_g * a / length,
                    rod_inertia_correction_kg_m2=j_g - m_g * a * b)


def slider_crank_from_components(crank_radius_m: float, rod_length_m: float, rod_mass_kg: float,
                                 rod_cg_to_crank_pin_m: float, crank_pin_mass_kg: float,
                                 piston_mass_kg: float, rod_inertia_about_cg_kg_m2: float = 0.0,
                                 harmonics: tuple[int, ...] | str = (1, 2),
                                 series: str = "leading") -> SliderCrank:
    """Build a :class:`SliderCrank` from component masses via :func:`two_mass_split`.

    Parameters
    ----------
    crank_radius_m : float
        Crank radius ``r`` [m].
    rod_length_m : float
        Pin-centre distance ``l`` [m], > ``r``.
    rod_mass_kg : float
        Rod mass ``m_G`` [kg].
    rod_cg_to_crank_pin_m : float
        ``a``, rod centre of gravity to crank pin [m].
    crank_pin_mass_kg : float
        ``m_A``, crank mass reduced to the crank pin [kg].
    piston_mass_kg : float
        ``m_B``, piston plus wrist pin [kg].
    rod_inertia_about_cg_kg_m2 : float
        ``J_G`` [kg m^2]; gives ``J_AB = J_G - m_G a b``.
    harmonics : tuple of int or "exact"
        See :class:`SliderCrank`.
    series : {"leading", "fourier"}
        See :class:`SliderCrank`.

    Returns
    -------
    SliderCrank
    """
    split = two_mass_split(rod_length_m, rod_mass_kg, rod_cg_to_crank_pin_m, crank_pin_mass_kg,
                           piston_mass_kg, rod_inertia_about_cg_kg_m2)
    return SliderCrank(crank_radius_m, rod_length_m, split.rotating_mass_kg,
                       split.reciprocating_mass_kg, harmonics=harmonics,
                       rod_inertia_correction_kg_m2=split.rod_inertia_correction_kg_m2,
                       series=series)


# --------------------------------------------------------------------------- kinematics
def _exact_factors(lam: float, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact piston-acceleration factor A and rod-couple factor B."""
    s, c = np.sin(theta), np.cos(theta)
    d2 = 1.0 - (lam * s) ** 2
    d = np.sqrt(d2)
    accel = c + lam * np.cos(2.0 * theta) / d + lam ** 3 * np.sin(2.0 * theta) ** 2 / (4.0 * d2 * d)
    couple = (1.0 - lam ** 2) * s / (d2 * d)
    return accel, couple


@functools.lru_cache(maxsize=64)
def _series_coefficients(mech: SliderCrank) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orders h, cosine coefficients a_h of A and sine coefficients b_h of B."""
    lam = mech.crank_rod_ratio
    orders = np.asarray(mech.harmonics, dtype=int)
    if mech.series == "leading":
        a_lead = {1: 1.0, 2: lam, 4: -lam ** 3 / 4.0, 6: 9.0 * lam ** 5 / 128.0}
        b_lead = {1: 1.0, 3: -3.0 * lam ** 2 / 8.0, 5: 15.0 * lam ** 4 / 128.0}
        a = np.array([a_lead.get(int(h), 0.0) for h in orders])
        b = np.array([b_lead.get(int(h), 0.0) for h in orders])
        return _read_only(orders, a, b)
    theta = np.arange(_N_FFT) * (2.0 * np.pi / _N_FFT)
    accel, couple = _exact_factors(lam, theta)
    spec_a = np.fft.rfft(accel) * (2.0 / _N_FFT)
    spec_b = np.fft.rfft(couple) * (2.0 / _N_FFT)
    return _read_only(orders, spec_a.real[orders], -spec_b.imag[orders])


def _read_only(*arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """Freeze cached arrays so no caller can change the cache."""
    for array in arrays:
        array.setflags(write=False)
    return arrays


def _factors(mech: SliderCrank, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if mech.is_exact:
        return _exact_factors(mech.crank_rod_ratio, theta)
    orders, a, b = _series_coefficients(mech)
    phase = np.multiply.outer(theta, orders)
    return np.cos(phase) @ a, np.sin(phase) @ b


def _force_xy(mech: SliderCrank, omega: float, moment_kg_m: float,
              theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    accel, _ = _factors(mech, theta)
    r, w2 = mech.crank_radius_m, omega ** 2
    unbalance = mech.rotating_mass_kg * r - moment_kg_m
    fx = -unbalance * w2 * np.sin(theta)
    fy = unbalance * w2 * np.cos(theta) + mech.reciprocating_mass_kg * r * w2 * accel
    return fx, fy


def _counterweight_moment(mech: SliderCrank, counterweight_mass_kg, counterweight_radius_m) -> float:
    mass = _finite_float("counterweight_mass_kg", counterweight_mass_kg, minimum=0.0)
    radius = _finite_float("counterweight_radius_m", counterweight_radius_m, minimum=0.0)
    if radius > mech.crank_radius_m * (1.0 + 1e-12):
        raise ParameterError(
            f"counterweight_radius_m = {radius!r}: expected 0 <= r_c <= crank_radius_m = "
            f"{mech.crank_radius_m!r} (the counterweight sits within the crank radius)")
    return mass * radius


def counterweight_mass(mech: SliderCrank, k: float) -> float:
    """The papers' counterweight mass ``m_c = m_rot + k m_rec`` [kg] (seed 000 eq. 8).

    Parameters
    ----------
    mech : SliderCrank
    k : float
        Fraction of the reciprocating mass, in ``[0, 1]`` (seed 000 eq. 15).

    Returns
    -------
    float
    """
    fraction = _finite_float("k", k, minimum=0.0, maximum=1.0)
    return mech.rotating_mass_kg + fraction * mech.reciprocating_mass_kg


def counterweight_moment(mech: SliderCrank, balance_fraction_value: float) -> float:
    """Counterweight moment ``u = m_c r_c = (m_rot + alpha m_rec) r`` [kg m] of a balance fraction.

    Parameters
    ----------
    mech : SliderCrank
    balance_fraction_value : float
        ``alpha`` (dimensionless).

    Returns
    -------
    float
    """
    alpha = _finite_float("balance_fraction", balance_fraction_value)
    return (mech.rotating_mass_kg + alpha * mech.reciprocating_mass_kg) * mech.crank_radius_m


def balance_fraction(mech: SliderCrank, counterweight_mass_kg: float,
                     counterweight_radius_m: float) -> float:
    """Effective balance fraction ``alpha = (m_c r_c / r - m_rot) / m_rec`` of a counterweight.

    Parameters
    ----------
    mech : SliderCrank
        Needs ``reciprocating_mass_kg > 0``.
    counterweight_mass_kg : float
        ``m_c`` [kg], >= 0.
    counterweight_radius_m : float
        ``r_c`` [m], in ``[0, r]``.

    Returns
    -------
    float
    """
    _require_reciprocating(mech)
    moment = _counterweight_moment(mech, counterweight_mass_kg, counterweight_radius_m)
    return (moment / mech.crank_radius_m - mech.rotating_mass_kg) / mech.reciprocating_mass_kg


def _require_reciprocating(mech: SliderCrank) -> None:
    if not mech.reciprocating_mass_kg > 0.0:
        raise ParameterError(
            f"reciprocating_mass_kg = {mech.reciprocating_mass_kg!r}: expected > 0 to define a "
            "balance fraction (with no reciprocating mass, m_c r_c = m_rot r cancels the force)")


# --------------------------------------------------------------------------- forces
@dataclass(frozen=True)
class ShakingForce:
    """Shaking force on the frame over crank angle.

    Attributes
    ----------
    crank_angle_rad : ndarray
        Crank angle from top dead centre [rad].
    force_x_n, force_y_n : ndarray
        Components across and along the stroke [N].
    resultant_n : ndarray
        ``hypot(force_x_n, force_y_n)`` [N].
    couple_z_n_m : ndarray
        Rod-inertia couple about the crank axis [N m].
    speed_rad_s : float
        Crank speed [rad/s].
    counterweight_moment_kg_m : float
        ``m_c r_c`` [kg m].
    """

    crank_angle_rad: np.ndarray
    force_x_n: np.ndarray
    force_y_n: np.ndarray
    resultant_n: np.ndarray
    couple_z_n_m: np.ndarray
    speed_rad_s: float
    counterweight_moment_kg_m: float


def shaking_force(mech: SliderCrank, speed_rpm: float, crank_angles_rad=None,
                  counterweight_mass_kg: float = 0.0,
                  counterweight_radius_m: float = 0.0) -> ShakingForce:
    """Shaking force and rod couple over crank angle (vectorised).

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    crank_angles_rad : array_like, optional
        Crank angles [rad]; default 361 angles over one revolution (1 deg step).
    counterweight_mass_kg : float
        ``m_c`` [kg].
    counterweight_radius_m : float
        ``r_c`` [m], in ``[0, r]``.

    Returns
    -------
    ShakingForce
    """
    omega = _speed_rad_s(speed_rpm)
    theta = np.linspace(0.0, 2.0 * np.pi, 361) if crank_angles_rad is None else _angles(
        crank_angles_rad)
    moment = _counterweight_moment(mech, counterweight_mass_kg, counterweight_radius_m)
    fx, fy = _force_xy(mech, omega, moment, theta)
    _, couple = _factors(mech, theta)
    mz = -mech.rod_inertia_correction_kg_m2 * mech.crank_rod_ratio * omega ** 2 * couple
    return ShakingForce(theta, fx, fy, np.hypot(fx, fy), mz, omega, moment)


@dataclass(frozen=True)
class ShakingHarmonics:
    """Harmonic content of the shaking force: ``f(t) = Re(sum_h X_h exp(i h omega t))``.

    Attributes
    ----------
    orders : ndarray of int
        Harmonic orders ``h``.
    speed_rad_s : float
        Crank speed ``omega`` [rad/s].
    force_n : ndarray, complex, shape (n_orders, 3)
        Force amplitudes (x, y, z) [N]; z is zero.
    couple_n_m : ndarray, complex, shape (n_orders, 3)
        Couple amplitudes about x, y, z [N m]; only z is non-zero.
    """

    orders: np.ndarray
    speed_rad_s: float
    force_n: np.ndarray
    couple_n_m: np.ndarray


def shaking_harmonics(mech: SliderCrank, speed_rpm: float, counterweight_mass_kg: float = 0.0,
                      counterweight_radius_m: float = 0.0,
                      max_order: int = 6) -> ShakingHarmonics:
    """Complex harmonic amplitudes of the shaking force and couple.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    counterweight_mass_kg, counterweight_radius_m : float
        Counterweight [kg], [m].
    max_order : int
        Highest order returned for exact kinematics (series models return
        their own orders).

    Returns
    -------
    ShakingHarmonics
    """
    if mech.is_exact:
        top = int(_finite_float("max_order", max_order, minimum=1.0, maximum=_MAX_SERIES_ORDER))
        orders = np.arange(1, top + 1)
    else:
        orders = np.asarray(mech.harmonics, dtype=int)
    theta = np.arange(_N_FFT) * (2.0 * np.pi / _N_FFT)
    sampled = shaking_force(mech, speed_rpm, theta, counterweight_mass_kg, counterweight_radius_m)
    spectra = [np.fft.fft(sig)[orders] * (2.0 / _N_FFT)
               for sig in (sampled.force_x_n, sampled.force_y_n, sampled.couple_z_n_m)]
    force = np.zeros((orders.size, 3), dtype=complex)
    couple = np.zeros((orders.size, 3), dtype=complex)
    force[:, 0], force[:, 1], couple[:, 2] = spectra
    return ShakingHarmonics(orders, sampled.speed_rad_s, force, couple)


# --------------------------------------------------------------------------- exact maxima
def _refined_max(fun, lower: float = 0.0, upper: float = np.pi,
                 n_grid: int = _N_GRID_HALF_TURN) -> tuple[float, np.ndarray, np.ndarray]:
    """Global maximum of a smooth vectorised ``fun`` on ``[lower, upper]``.

    Brackets every local maximum on a grid, then zooms in on all of them at
    once: each pass samples 11 points across +-h around the best point so far
    and shrinks h by 5 (the maximum of a smooth peak lies within one sample
    spacing of the best sample), down to h < 1e-10 rad, where the value error
    (~h^2 |f''| / 2) is below rounding.  Returns the maximum and all refined
    local maxima (angles, values), largest first.
    """
    grid = np.linspace(lower, upper, n_grid)
    values = fun(grid)
    padded = np.concatenate(([-np.inf], values, [-np.inf]))
    is_peak = (padded[1:-1] >= padded[:-2]) & (padded[1:-1] >= padded[2:])
    angles = grid[is_peak]
    peaks = values[is_peak]
    half_width = grid[1] - grid[0]
    offsets = np.linspace(-1.0, 1.0, 11)
    while half_width > 1e-10:
        trial = np.clip(angles[:, None] + half_width * offsets, lower, upper)
        trial_values = fun(trial.ravel()).reshape(trial.shape)
        best = np.argmax(trial_values, axis=1)
        rows = np.arange(angles.size)
        improved = trial_values[rows, best] >= peaks
        angles = np.where(improved, trial[rows, best], angles)
        peaks = np.where(improved, trial_values[rows, best], peaks)
        half_width /= 5.0
    order = np.argsort(peaks)[::-1]
    return float(peaks[order[0]]), angles[order], peaks[order]


def _objective_value(mech: SliderCrank, omega: float, moment: float, objective: str) -> float:
    if objective == "max":
        return _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))[0]
    if objective == "max_x":
        return abs(mech.rotating_mass_kg * mech.crank_radius_m - moment) * omega ** 2
    if objective == "max_y":
        return _refined_max(lambda t: np.abs(_force_xy(mech, omega, moment, t)[1]))[0]
    # RMS over a revolution: the periodic trapezoid rule is exact for a trig
    # polynomial of degree < _N_FFT and spectrally accurate for the exact model.
    theta = np.arange(_N_FFT) * (2.0 * np.pi / _N_FFT)
    fx, fy = _force_xy(mech, omega, moment, theta)
    return float(np.sqrt(np.mean(fx ** 2 + fy ** 2)))


def _check_objective(objective: str) -> None:
    if objective not in OBJECTIVES:
        raise ParameterError(f"objective = {objective!r}: expected one of {OBJECTIVES}")


def max_shaking_force(mech: SliderCrank, speed_rpm: float, counterweight_mass_kg: float = 0.0,
                      counterweight_radius_m: float = 0.0, crank_angles_rad=None) -> float:
    """Peak resultant shaking force over a revolution [N] (the papers' objective).

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    counterweight_mass_kg : float
        ``m_c`` [kg], >= 0.
    counterweight_radius_m : float
        ``r_c`` [m], in ``[0, r]``.
    crank_angles_rad : array_like, optional
        None: the exact maximum over the revolution (every local maximum refined
        to 1e-10 rad).  An array: the maximum over those angles only, as the
        papers' 1 deg grid.

    Returns
    -------
    float
    """
    omega = _speed_rad_s(speed_rpm)
    moment = _counterweight_moment(mech, counterweight_mass_kg, counterweight_radius_m)
    if crank_angles_rad is not None:
        fx, fy = _force_xy(mech, omega, moment, _angles(crank_angles_rad))
        return float(np.max(np.hypot(fx, fy)))
    return _objective_value(mech, omega, moment, "max")


def shaking_objective(mech: SliderCrank, speed_rpm: float, balance_fraction_value,
                      objective: Objective = "max") -> np.ndarray:
    """Objective against balance fraction: peak, RMS or per-direction peak force [N].

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    balance_fraction_value : float or array_like
        ``alpha`` values.
    objective : {"max", "rms", "max_x", "max_y"}
        Peak resultant (the papers'), RMS resultant over a revolution, or the
        peak of one component.

    Returns
    -------
    ndarray
        Objective values [N], the shape of ``balance_fraction_value``.
    """
    _check_objective(objective)
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    alphas = np.asarray(balance_fraction_value, dtype=float)
    if not np.all(np.isfinite(alphas)):
        raise ParameterError("balance_fraction_value contains NaN or infinity: expected finite")
    values = [_objective_value(mech, omega, counterweight_moment(mech, a), objective)
              for a in alphas.ravel()]
    return np.asarray(values).reshape(alphas.shape)


# --------------------------------------------------------------------------- evaluation
@dataclass(frozen=True)
class CounterweightEvaluation:
    """One counterweight (or none) evaluated over a revolution.

    Attributes
    ----------
    balance_fraction : float
        ``alpha``.
    counterweight_moment_kg_m : float
        ``m_c r_c`` [kg m].
    max_force_n : float
        Peak resultant [N].
    max_force_angle_rad : float
        Crank angle of the peak in ``[0, pi]`` [rad] (``|F|`` is even).
    rms_force_n : float
        RMS resultant over a revolution [N].
    force_x_range_n, force_y_range_n : tuple of float
        (min, max) of each component [N].
    force_x_span_n, force_y_span_n : float
        Peak-to-peak spans [N].
    reduction : float
        ``1 - max_force_n / (peak without counterweight)``.
    """

    balance_fraction: float
    counterweight_moment_kg_m: float
    max_force_n: float
    max_force_angle_rad: float
    rms_force_n: float
    force_x_range_n: tuple[float, float]
    force_y_range_n: tuple[float, float]
    force_x_span_n: float
    force_y_span_n: float
    reduction: float


def _evaluate_moment(mech: SliderCrank, omega: float, moment: float) -> CounterweightEvaluation:
    peak, angles, _ = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))
    x_max = abs(mech.rotating_mass_kg * mech.crank_radius_m - moment) * omega ** 2
    y_max = _refined_max(lambda t: _force_xy(mech, omega, moment, t)[1])[0]
    y_min = -_refined_max(lambda t: -_force_xy(mech, omega, moment, t)[1])[0]
    unbalanced = _objective_value(mech, omega, 0.0, "max")
    alpha = (moment / mech.crank_radius_m - mech.rotating_mass_kg) / mech.reciprocating_mass_kg
    return CounterweightEvaluation(
        balance_fraction=float(alpha), counterweight_moment_kg_m=moment, max_force_n=peak,
        max_force_angle_rad=float(angles[0]),
        rms_force_n=_objective_value(mech, omega, moment, "rms"),
        force_x_range_n=(-x_max, x_max), force_y_range_n=(y_min, y_max),
        force_x_span_n=2.0 * x_max, force_y_span_n=y_max - y_min,
        reduction=1.0 - peak / unbalanced if unbalanced > 0 else 0.0)


def evaluate_counterweight(mech: SliderCrank, speed_rpm: float, counterweight_mass_kg: float = 0.0,
                           counterweight_radius_m: float = 0.0) -> CounterweightEvaluation:
    """Peak, RMS, component ranges and peak-to-peak spans for a given counterweight.

    Parameters
    ----------
    mech : SliderCrank
        Needs ``reciprocating_mass_kg > 0`` (the result reports ``alpha``).
    speed_rpm : float
        Crank speed [rev/min], > 0.
    counterweight_mass_kg : float
        ``m_c`` [kg], >= 0.
    counterweight_radius_m : float
        ``r_c`` [m], in ``[0, r]``.

    Returns
    -------
    CounterweightEvaluation
    """
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    moment = _counterweight_moment(mech, counterweight_mass_kg, counterweight_radius_m)
    return _evaluate_moment(mech, omega, moment)


def evaluate_balance_fraction(mech: SliderCrank, speed_rpm: float,
                              balance_fraction_value: float | str) -> CounterweightEvaluation:
    """Evaluate a balance fraction, or one of the papers' rules by name.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    balance_fraction_value : float or str
        ``alpha``, or a key of :data:`PAPER_RULES` (``"rotating"``:
        ``m_dt r = m_tq R``; ``"rotating_plus_half_reciprocating"``:
        ``m_dt r = R (m_tq + 0.5 m_ct)``).

    Returns
    -------
    CounterweightEvaluation
    """
    if isinstance(balance_fraction_value, str):
        if balance_fraction_value not in PAPER_RULES:
            raise ParameterError(
                f"balance_fraction_value = {balance_fraction_value!r}: expected a number or one "
                f"of {tuple(PAPER_RULES)}")
        balance_fraction_value = PAPER_RULES[balance_fraction_value]
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    return _evaluate_moment(mech, omega, counterweight_moment(mech, balance_fraction_value))


# --------------------------------------------------------------------------- optimum
@dataclass(frozen=True)
class OptimalCurve:
    """All counterweights ``(k, r_c)`` with the optimal moment, ``m_c = m_rot + k m_rec``.

    Attributes
    ----------
    k : ndarray
        The papers' fraction ``k`` in ``[max(alpha*, 0), 1]``.
    counterweight_mass_kg : ndarray
        ``m_c`` [kg].
    counterweight_radius_m : ndarray
        ``r_c = m_c* r_c* / m_c`` [m], <= ``r``.
    radius_ratio : ndarray
        ``r_c / r``.
    """

    k: np.ndarray
    counterweight_mass_kg: np.ndarray
    counterweight_radius_m: np.ndarray
    radius_ratio: np.ndarray


@dataclass(frozen=True)
class OptimalCounterweight:
    """Exact optimum of the counterweight over the papers' feasible box.

    Attributes
    ----------
    balance_fraction : float
        Optimal ``alpha*`` (speed-independent).
    max_force_n : float
        Peak resultant force at the optimum [N].
    objective : str
        Objective minimised (``"max"``, ``"rms"``, ``"max_x"``, ``"max_y"``).
    objective_value_n : float
        Its value at the optimum [N].
    counterweight_moment_kg_m : float
        ``m_c r_c`` at the optimum [kg m].
    peak_angles_rad : ndarray
        Crank angles in ``[0, pi]`` of the active peaks at the optimum [rad]
        (two equal peaks when the optimum is an equal-peak point).
    peak_forces_n : ndarray
        Resultant at those angles [N].
    unbalanced_max_force_n : float
        Peak resultant without counterweight [N].
    reduction : float
        ``1 - max_force_n / unbalanced_max_force_n``.
    speed_rpm : float
        Speed the forces refer to [rev/min] (forces scale with its square).
    method : str
        ``"equal-peak root"`` or ``"bounded Brent"``.
    curve : OptimalCurve
        The whole family of optimal ``(k, r_c)``.
    """

    balance_fraction: float
    max_force_n: float
    objective: str
    objective_value_n: float
    counterweight_moment_kg_m: float
    peak_angles_rad: np.ndarray
    peak_forces_n: np.ndarray
    unbalanced_max_force_n: float
    reduction: float
    speed_rpm: float
    method: str
    curve: OptimalCurve


def _local_peak(mech: SliderCrank, omega: float, moment: float, angle: float,
                half_width: float) -> tuple[float, float]:
    """Refined local maximum of |F| within ``angle +- half_width``: (angle, value)."""
    lo, hi = max(0.0, angle - half_width), min(np.pi, angle + half_width)
    _, angles, peaks = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)),
                                    lo, hi, n_grid=41)
    return float(angles[0]), float(peaks[0])


def _optimal_curve(mech: SliderCrank, alpha: float, moment: float, n_points: int) -> OptimalCurve:
    k = np.linspace(max(alpha, 0.0), 1.0, n_points)
    mass = mech.rotating_mass_kg + k * mech.reciprocating_mass_kg
    with np.errstate(divide="ignore"):
        radius = np.where(mass > 0, moment / np.where(mass > 0, mass, 1.0), 0.0)
    radius = np.minimum(radius, mech.crank_radius_m)
    return OptimalCurve(k, mass, radius, radius / mech.crank_radius_m)


def optimal_counterweight(mech: SliderCrank, speed_rpm: float, objective: Objective = "max",
                          n_curve_points: int = 101) -> OptimalCounterweight:
    """Exact optimal counterweight: minimise the objective over ``alpha``.

    The feasible box of the papers (``0 <= k <= 1``, ``0 <= r_c <= r``) is
    ``-m_rot/m_rec <= alpha <= 1``.  The convex objective is minimised by
    bounded Brent (inner maxima refined to 1e-10 rad); for ``"max"`` the
    result is then polished by solving the equal-peak condition with
    ``brentq`` when two peaks are active.

    Parameters
    ----------
    mech : SliderCrank
        Needs ``reciprocating_mass_kg > 0``.
    speed_rpm : float
        Crank speed [rev/min], > 0 (the optimal ``alpha`` does not depend on it).
    objective : {"max", "rms", "max_x", "max_y"}
        See :func:`shaking_objective`.
    n_curve_points : int
        Points on the optimal ``(k, r_c)`` curve, >= 2.

    Returns
    -------
    OptimalCounterweight
    """
    _check_objective(objective)
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    n_points = int(_finite_float("n_curve_points", n_curve_points, minimum=2.0))
    m_rot, m_rec, r = mech.rotating_mass_kg, mech.reciprocating_mass_kg, mech.crank_radius_m
    lower, upper = -m_rot / m_rec, 1.0

    def phi(alpha: float) -> float:
        return _objective_value(mech, omega, (m_rot + alpha * m_rec) * r, objective)

    # For "max" a coarse bracket suffices: the equal-peak root polishes it.
    res = optimize.minimize_scalar(phi, bounds=(lower, upper), method="bounded",
                                   options={"xatol": 1e-7 if objective == "max" else 1e-10})
    alpha, method = float(res.x), "bounded Brent"
    # Compare with the bounds: the bounded method never evaluates them.
    for bound in (lower, upper):
        if phi(bound) < phi(alpha):
            alpha = bound
    if objective == "max":
        polished, how = _polish_equal_peak(mech, omega, alpha, lower, upper, method)
        # keep the root only if it is at least as good (it is the optimum when
        # the two peaks move in opposite directions with alpha, as they must
        # when both are active at the minimum of a convex maximum)
        if phi(polished) <= phi(alpha) * (1.0 + 1e-14):
            alpha, method = polished, how
    moment = (m_rot + alpha * m_rec) * r
    _, angles, peaks = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))
    active = peaks >= peaks[0] * (1.0 - 1e-7)
    unbalanced = _objective_value(mech, omega, 0.0, "max")
    peak = float(peaks[0])
    return OptimalCounterweight(
        balance_fraction=alpha, max_force_n=peak, objective=objective,
        objective_value_n=_objective_value(mech, omega, moment, objective),
        counterweight_moment_kg_m=moment, peak_angles_rad=np.sort(angles[active]),
        peak_forces_n=peaks[active][np.argsort(angles[active])],
        unbalanced_max_force_n=unbalanced, reduction=1.0 - peak / unbalanced if unbalanced > 0 else 0.0,
        speed_rpm=float(speed_rpm), method=method,
        curve=_optimal_curve(mech, alpha, moment, n_points))


def _polish_equal_peak(mech: SliderCrank, omega: float, alpha: float, lower: float, upper: float,
                       method: str) -> tuple[float, str]:
    """Solve P_a(alpha) = P_b(alpha) for the two largest distinct peaks."""
    m_rot, m_rec, r = mech.rotating_mass_kg, mech.reciprocating_mass_kg, mech.crank_radius_m
    moment = (m_rot + alpha * m_rec) * r
    _, angles, peaks = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))
    if peaks.size < 2 or peaks[1] < peaks[0] * (1.0 - 1e-5):
        return alpha, method
    angle_a, angle_b = angles[0], angles[1]
    half_width = 0.25 * abs(angle_a - angle_b)

    def gap(a: float) -> float:
        u = (m_rot + a * m_rec) * r
        return _local_peak(mech, omega, u, angle_a, half_width)[1] - _local_peak(
            mech, omega, u, angle_b, half_width)[1]

    step = 1e-6
    for _ in range(20):
        lo, hi = max(lower, alpha - step), min(upper, alpha + step)
        g_lo, g_hi = gap(lo), gap(hi)
        if g_lo * g_hi < 0:
            return float(optimize.brentq(gap, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)), \
                "equal-peak root"
        step *= 4.0
    return alpha, method


@dataclass(frozen=True)
class Counterweight:
    """One counterweight on the optimal curve.

    Attributes
    ----------
    k : float
        ``(m_c - m_rot) / m_rec``.
    mass_kg : float
        ``m_c`` [kg].
    radius_m : float
        ``r_c`` [m].
    radius_ratio : float
        ``r_c / r``.
    rule : str
        How it was picked.
    """

    k: float
    mass_kg: float
    radius_m: float
    radius_ratio: float
    rule: str


def counterweight_on_curve(mech: SliderCrank, optimum: OptimalCounterweight, *,
                           k: float | None = None,
                           radius_m: float | None = None) -> Counterweight:
    """Pick one optimal counterweight: the lightest (``r_c = r``), a given ``k`` or a given ``r_c``.

    The lightest counterweight and ``r_c = r`` are the same point, since
    ``m_c r_c`` is fixed on the curve.

    Parameters
    ----------
    mech : SliderCrank
    optimum : OptimalCounterweight
    k : float, optional
        Given ``k`` in ``[max(alpha*, 0), 1]``.
    radius_m : float, optional
        Given ``r_c`` [m] in ``(0, r]``.

    Returns
    -------
    Counterweight
    """
    if k is not None and radius_m is not None:
        raise ParameterError("give k or radius_m, not both")
    moment = optimum.counterweight_moment_kg_m
    m_rot, m_rec, r = mech.rotating_mass_kg, mech.reciprocating_mass_kg, mech.crank_radius_m
    if radius_m is not None:
        radius = _finite_float("radius_m", radius_m, minimum=0.0, strict=True, maximum=r)
        mass, rule = moment / radius, "given radius"
        kk = (mass - m_rot) / m_rec
        if kk > 1.0 + 1e-12:
            raise ParameterError(
                f"radius_m = {radius!r}: needs k = {kk:.6g} > 1; expected radius_m >= "
                f"{moment / (m_rot + m_rec)!r}")
        return Counterweight(kk, mass, radius, radius / r, rule)
    k_low = max(optimum.balance_fraction, 0.0)
    if k is None:
        kk, rule = k_low, "lightest (r_c = r)"
    else:
        kk = _finite_float("k", k, minimum=k_low - 1e-12, maximum=1.0)
        rule = "given k"
    mass = m_rot + kk * m_rec
    radius = min(moment / mass, r) if mass > 0 else 0.0
    return Counterweight(kk, mass, radius, radius / r, rule)


# --------------------------------------------------------------------------- brute force
@dataclass(frozen=True)
class GridSearchResult:
    """Best point of an exhaustive ``(k, r_c)`` search (the papers' method).

    Attributes
    ----------
    k : float
    counterweight_radius_m : float
        [m]
    max_force_n : float
        Peak resultant on the angle grid [N].
    n_evaluations : int
        ``(k, r_c)`` pairs times angles evaluated.
    """

    k: float
    counterweight_radius_m: float
    max_force_n: float
    n_evaluations: int


def grid_search_counterweight(mech: SliderCrank, speed_rpm: float, k_values, radius_values_m,
                              crank_angles_rad, chunk_size: int = 200_000) -> GridSearchResult:
    """Exhaustive search over ``(k, r_c)`` with the force maximised on an angle grid.

    Kept as the papers' reference method and for benchmarks; use
    :func:`optimal_counterweight` for answers.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    k_values : array_like
        ``k`` values.
    radius_values_m : array_like
        ``r_c`` values [m], in ``[0, r]``.
    crank_angles_rad : array_like
        Angle grid [rad].
    chunk_size : int
        Approximate number of force evaluations per vectorised block.

    Returns
    -------
    GridSearchResult
    """
    omega = _speed_rad_s(speed_rpm)
    theta = _angles(crank_angles_rad)
    ks = _angles(k_values, "k_values", "units of m_rec")
    radii = _angles(radius_values_m, "radius_values_m", "m")
    if radii.min() < 0 or radii.max() > mech.crank_radius_m * (1 + 1e-12):
        raise ParameterError(
            f"radius_values_m spans [{radii.min()!r}, {radii.max()!r}]: expected values in "
            f"[0, crank_radius_m = {mech.crank_radius_m!r}]")
    kk, rr = np.meshgrid(ks, radii, indexing="ij")
    k_flat, r_flat = kk.ravel(), rr.ravel()
    moments = (mech.rotating_mass_kg + k_flat * mech.reciprocating_mass_kg) * r_flat
    accel, _ = _factors(mech, theta)
    w2, r = omega ** 2, mech.crank_radius_m
    s, c = np.sin(theta), np.cos(theta)
    rec = mech.reciprocating_mass_kg * r * w2 * accel
    rows = max(1, int(chunk_size) // theta.size)
    best = np.empty(moments.size)
    for start in range(0, moments.size, rows):
        unbalance = (mech.rotating_mass_kg * r - moments[start:start + rows, None]) * w2
        best[start:start + rows] = np.max(np.hypot(unbalance * s, unbalance * c + rec), axis=1)
    index = int(np.argmin(best))
    return GridSearchResult(float(k_flat[index]), float(r_flat[index]), float(best[index]),
                            int(moments.size * theta.size))

