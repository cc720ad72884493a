"""The slider-crank mechanism: its masses and geometry, the rod's two-mass split and the
piston-acceleration and rod-couple factors (exact or harmonic series); the model is
described in :mod:`balancer.compressor.crank`."""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from modal.errors import ParameterError
from modal.units import rpm_to_rad_s

from ..._checks import bounded

__all__ = [
    "SliderCrank",
    "RodSplit",
    "PAPER_RULES",
    "OBJECTIVES",
    "two_mass_split",
    "slider_crank_from_components",
    "balance_fraction",
    "counterweight_mass",
    "counterweight_moment",
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

def _speed_rad_s(speed_rpm) -> float:
    speed = bounded("speed_rpm", speed_rpm, minimum=0.0, strict=True)
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
        radius = bounded("crank_radius_m", self.crank_radius_m, minimum=0.0, strict=True)
        length = bounded("rod_length_m", self.rod_length_m, minimum=0.0, strict=True)
        if not length > radius:
            raise ParameterError(
                f"rod_length_m = {length!r} with crank_radius_m = {radius!r}: the rod must be "
                "longer than the crank (rod_length_m > crank_radius_m)")
        m_rot = bounded("rotating_mass_kg", self.rotating_mass_kg, minimum=0.0)
        m_rec = bounded("reciprocating_mass_kg", self.reciprocating_mass_kg, minimum=0.0)
        j_ab = bounded("rod_inertia_correction_kg_m2", self.rod_inertia_correction_kg_m2)
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
    length = bounded("rod_length_m", rod_length_m, minimum=0.0, strict=True)
    m_g = bounded("rod_mass_kg", rod_mass_kg, minimum=0.0)
    a = bounded("rod_cg_to_crank_pin_m", rod_cg_to_crank_pin_m, minimum=0.0,
                      maximum=length)
    m_a = bounded("crank_pin_mass_kg", crank_pin_mass_kg, minimum=0.0)
    m_b = bounded("piston_mass_kg", piston_mass_kg, minimum=0.0)
    j_g = bounded("rod_inertia_about_cg_kg_m2", rod_inertia_about_cg_kg_m2, minimum=0.0)
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
    mass = bounded("counterweight_mass_kg", counterweight_mass_kg, minimum=0.0)
    radius = bounded("counterweight_radius_m", counterweight_radius_m, minimum=0.0)
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
    fraction = bounded("k", k, minimum=0.0, maximum=1.0)
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
    alpha = bounded("balance_fraction", balance_fraction_value)
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
