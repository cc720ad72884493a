"""Readings in the units users have, converted to SI at the edge.

Phase convention (stated once, used everywhere in :mod:`balancer.influence`)
--------------------------------------------------------------------------
* A vibration reading is the 1x (once-per-revolution) component of a sensor's
  signal: an amplitude and a **phase lag** in degrees, positive, measured from the
  keyphasor pulse to the next positive peak of the signal (the convention of most
  field analysers and of Bently Nevada's "phase lag").
* A mass's angular position is measured from the keyphasor mark on the rotor
  **against the direction of rotation**.  With phase lag this is the pair that keeps
  the relation linear without conjugation: moving a mass by +30 deg (against
  rotation) moves the reading's phase lag by +30 deg.
* Inside, a reading is the complex number ``amplitude_SI * exp(1j * phase_lag_rad)``
  and an unbalance ``mass * radius * exp(1j * angle_rad)`` (kg m).  Amplitudes are
  SI: m (displacement), m/s (velocity) or m/s^2 (acceleration).

Amplitudes are taken as the analyser reports them; peak, peak-to-peak or RMS does
not matter for balancing as long as every reading of one job uses the same.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError
from modal.units import STANDARD_GRAVITY_M_S2

from .._checks import finite_array

__all__ = [
    "READING_UNITS",
    "MASS_UNITS",
    "ReadingUnit",
    "reading_unit",
    "vibration",
    "amplitude_phase",
    "unbalance_kg_m",
    "mass_angle",
]



@dataclass(frozen=True, slots=True)
class ReadingUnit:
    """A unit of vibration readings: its quantity, SI unit and factor to SI."""

    name: str
    quantity: str  # "displacement" | "velocity" | "acceleration"
    si_unit: str  # "m" | "m/s" | "m/s^2"
    to_si: float
    symbol: str = ""  # how outputs write it, where that differs from the name (µm)

    @property
    def label(self) -> str:
        """The unit as every output (tables, JSON, plots) writes it: ``"µm"`` for ``"um"``, ``"m/s²"``."""
        return self.symbol or self.name


READING_UNITS: dict[str, ReadingUnit] = {
    u.name: u
    for u in (
        ReadingUnit("m", "displacement", "m", 1.0),
        ReadingUnit("mm", "displacement", "m", 1e-3),
        ReadingUnit("um", "displacement", "m", 1e-6, "µm"),
        ReadingUnit("mil", "displacement", "m", 25.4e-6),
        ReadingUnit("m/s", "velocity", "m/s", 1.0),
        ReadingUnit("mm/s", "velocity", "m/s", 1e-3),
        ReadingUnit("in/s", "velocity", "m/s", 25.4e-3),
        ReadingUnit("m/s^2", "acceleration", "m/s^2", 1.0, "m/s²"),
        ReadingUnit("g", "acceleration", "m/s^2", STANDARD_GRAVITY_M_S2),
    )
}
_ALIASES = {"µm": "um", "μm": "um", "micron": "um", "mils": "mil", "ips": "in/s", "m/s2": "m/s^2", "m/s**2": "m/s^2",
            "m/s²": "m/s^2"}

MASS_UNITS: dict[str, float] = {"kg": 1.0, "g": 1e-3}
"""Mass units accepted for trial and correction masses, with their factor to kg."""


def reading_unit(units: str, field: str = "units") -> ReadingUnit:
    """Look up a reading unit by name (``"um"``, ``"µm"``, ``"mm/s"``, ``"g"``, ...)."""
    key = _ALIASES.get(str(units).strip(), str(units).strip())
    if key not in READING_UNITS:
        raise ParameterError(f"{field} = {units!r}: expected one of {', '.join(READING_UNITS)} (or µm, mils, ips)")
    return READING_UNITS[key]


def vibration(amplitude, phase_lag_deg, units: str, field: str = "reading") -> np.ndarray:
    """Readings (amplitude in ``units``, phase lag in degrees) as complex SI values.

    Parameters
    ----------
    amplitude : array_like
        Amplitudes in ``units`` (>= 0).
    phase_lag_deg : array_like
        Phase lags (deg), same shape as ``amplitude``; see the module notes.
    units : str
        One of :data:`READING_UNITS` (``"um"``, ``"mil"``, ``"mm/s"``, ``"in/s"``, ``"g"``, ...).
    field : str
        Name used in error messages.

    Returns
    -------
    ndarray of complex
        ``amplitude * factor * exp(1j * radians(phase_lag_deg))`` in m, m/s or m/s^2.
    """
    unit = reading_unit(units)
    a = finite_array(amplitude, f"{field}.amplitude")
    p = finite_array(phase_lag_deg, f"{field}.phase_deg")
    if a.shape != p.shape:
        raise ParameterError(f"{field}.amplitude: {a.size} amplitudes but {p.size} phases; expected one phase per amplitude")
    if np.any(a < 0):
        raise ParameterError(f"{field}.amplitude: entry {int(np.flatnonzero(a < 0)[0])} is negative; expected >= 0")
    return a * unit.to_si * np.exp(1j * np.deg2rad(p))


def user_digits(values) -> np.ndarray:
    """Values in a user's unit rounded to 15 significant digits: a reading given as 3.8 and carried through SI and
    back (3.7999999999999994) is 3.8 again; 15 digits keep every digit a double holds for sure."""
    a = np.asarray(values, dtype=float)
    return np.array([float(f"{v:.15g}") for v in a.ravel()]).reshape(a.shape)


def amplitude_phase(values, units: str) -> tuple[np.ndarray, np.ndarray]:
    """Complex SI readings back to (amplitude in ``units``, phase lag in deg within [0, 360)), to 15 significant
    digits (:func:`user_digits`)."""
    unit = reading_unit(units)
    z = np.asarray(values, dtype=complex)
    return user_digits(np.abs(z) / unit.to_si), np.mod(user_digits(np.rad2deg(np.angle(z))), 360.0)


def unbalance_kg_m(mass, radius_m, angle_deg, mass_units: str = "kg", field: str = "mass") -> np.ndarray:
    """Masses at a radius and angle as complex unbalances (kg m).

    ``angle_deg`` is measured from the keyphasor mark against rotation (module notes).
    """
    if mass_units not in MASS_UNITS:
        raise ParameterError(f"{field}_units = {mass_units!r}: expected one of {', '.join(MASS_UNITS)}")
    m = finite_array(mass, f"{field}")
    r = finite_array(radius_m, "radius_m")
    a = finite_array(angle_deg, f"{field}.angle_deg")
    if np.any(r <= 0):
        raise ParameterError("radius_m: expected > 0")
    return m * MASS_UNITS[mass_units] * r * np.exp(1j * np.deg2rad(a))


def mass_angle(unbalance, radius_m, mass_units: str = "kg") -> tuple[np.ndarray, np.ndarray]:
    """Complex unbalances (kg m) to (mass in ``mass_units`` at ``radius_m``, angle in deg within [0, 360))."""
    if mass_units not in MASS_UNITS:
        raise ParameterError(f"mass_units = {mass_units!r}: expected one of {', '.join(MASS_UNITS)}")
    u = np.asarray(unbalance, dtype=complex)
    return np.abs(u) / np.asarray(radius_m, dtype=float) / MASS_UNITS[mass_units], np.mod(np.rad2deg(np.angle(u)), 360.0)
