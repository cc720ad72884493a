"""Shaking force and rod couple of a slider-crank over a revolution, their harmonics, and
their exact maxima over crank angle."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

from ..._checks import bounded
from .model import (
    _MAX_SERIES_ORDER,
    _N_FFT,
    _N_GRID_HALF_TURN,
    OBJECTIVES,
    Objective,
    SliderCrank,
    _angles,
    _counterweight_moment,
    _factors,
    _force_xy,
    _require_reciprocating,
    _speed_rad_s,
    counterweight_moment,
)

__all__ = [
    "ShakingForce",
    "ShakingHarmonics",
    "shaking_force",
    "shaking_harmonics",
    "max_shaking_force",
    "shaking_objective",
]


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
        top = int(bounded("max_order", max_order, minimum=1.0, maximum=_MAX_SERIES_ORDER))
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
    angles, peaks = _zoom(lambda trial: fun(trial.ravel()).reshape(trial.shape), grid[is_peak], values[is_peak],
                          grid[1] - grid[0], lower, upper)
    order = np.argsort(peaks)[::-1]
    return float(peaks[order[0]]), angles[order], peaks[order]


def _zoom(values_at, angles: np.ndarray, peaks: np.ndarray, half_width: float, lower: float,
          upper: float) -> tuple[np.ndarray, np.ndarray]:
    """The zoom passes of :func:`_refined_max` on every bracketed peak at once: each pass samples 11
    points across ±``half_width`` around each peak's best angle so far (``values_at(trial)`` gives the
    values at the angles ``trial``, (n_peaks, 11)) and shrinks the width by 5, down to 1e-10 rad.
    Returns the refined angles and values."""
    offsets = np.linspace(-1.0, 1.0, 11)
    index = np.arange(angles.size)
    while half_width > 1e-10:
        trial = np.clip(angles[:, None] + half_width * offsets, lower, upper)
        trial_values = values_at(trial)
        best = np.argmax(trial_values, axis=1)
        improved = trial_values[index, best] >= peaks
        angles = np.where(improved, trial[index, best], angles)
        peaks = np.where(improved, trial_values[index, best], peaks)
        half_width /= 5.0
    return angles, peaks


def _refined_max_rows(fun, n_rows: int, lower: float = 0.0, upper: float = np.pi,
                      n_grid: int = _N_GRID_HALF_TURN) -> np.ndarray:
    """:func:`_refined_max` of ``n_rows`` functions at once: ``fun(theta, rows)`` evaluates row ``rows[i]``'s
    function at ``theta[i]`` (broadcast).  The same grid, brackets and zoom passes as :func:`_refined_max`,
    element for element, on all rows' peaks together (one numpy call per pass instead of one per row).
    Returns each row's maximum."""
    grid = np.linspace(lower, upper, n_grid)
    values = fun(grid[None, :], np.arange(n_rows)[:, None])
    edge = np.full((n_rows, 1), -np.inf)
    padded = np.concatenate((edge, values, edge), axis=1)
    is_peak = (padded[:, 1:-1] >= padded[:, :-2]) & (padded[:, 1:-1] >= padded[:, 2:])
    rows, columns = np.nonzero(is_peak)
    _, peaks = _zoom(lambda trial: fun(trial, rows[:, None]), grid[columns], values[rows, columns],
                     grid[1] - grid[0], lower, upper)
    best = np.full(n_rows, -np.inf)
    np.maximum.at(best, rows, peaks)
    return best


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
    moments = np.array([counterweight_moment(mech, a) for a in alphas.ravel()])
    if objective == "max" and moments.size > 1:  # the papers' objective: every alpha's peak search at once
        return _refined_max_rows(lambda t, rows: np.hypot(*_force_xy(mech, omega, moments[rows], t)),
                                 moments.size).reshape(alphas.shape)
    values = [_objective_value(mech, omega, moment, objective) for moment in moments]
    return np.asarray(values).reshape(alphas.shape)
