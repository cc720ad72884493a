"""Field balancing of a simulated Jeffcott rotor, next to the model alpha and the ball balancer.

The study a scene's ``[balance.simulate]`` runs: a Jeffcott rotor (the truth: given
k, c, M, or by default the ``[rotor]`` stage's) is "measured" at a few speeds by a
displacement sensor, once as it is and once with a trial mass, with relative reading
noise; the influence coefficients measured so and the Jeffcott model's
(:func:`~balancer.influence.jeffcott_influence` from the k, c, M identified from an
FRF) are compared with the truth, the
rotor is balanced by least squares and by min-max, and the vibration the corrections
really leave (exact Jeffcott response; equal to the ``balancer.adb`` equations without
balls, see the tests) is set against the one-shot correction from the model alpha (no
trial run at all) and the ball balancer's residual amplitude.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

from .job import BalanceJob, BalanceReport, balance
from .jeffcott import jeffcott_influence
from .readings import MASS_UNITS, reading_unit

__all__ = ["FieldBalancingStudy", "simulated_job", "field_balancing_study"]


def simulated_job(M: float, k: float, c: float, e: float, speeds_rad_s, trial_mass: float, trial_angle_deg: float,
                  radius_m: float, noise: float, seed: int, units: str = "um", mass_units: str = "g") -> BalanceJob:
    """Initial and trial readings of a Jeffcott rotor (unbalance ``M e`` at angle 0), with noise.

    ``noise`` is the relative standard deviation of a circular complex Gaussian error
    on every reading (0.05: 5 %).
    """
    speeds = np.atleast_1d(np.asarray(speeds_rad_s, dtype=float))
    if speeds.size < 1 or np.any(speeds <= 0):
        raise ParameterError("speeds_rad_s: expected speeds > 0")
    if noise < 0:
        raise ParameterError(f"noise = {noise!r}: expected >= 0")
    unit = reading_unit(units)
    if unit.quantity != "displacement":
        raise ParameterError(f"units = {units!r}: the simulated sensor reads displacement; expected um, mm, mil or m")
    alpha = jeffcott_influence(k, c, M, speeds)
    rotor_unbalance = M * e
    trial = trial_mass * MASS_UNITS[mass_units] * radius_m * np.exp(1j * math.radians(trial_angle_deg))
    rng = np.random.default_rng(seed)

    def measured(z):
        return z * (1 + noise * (rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape)) / math.sqrt(2))

    initial = measured(alpha * rotor_unbalance)
    run = measured(alpha * (rotor_unbalance + trial))
    labels = tuple(f"x @ {w:.4g} rad/s" for w in speeds)
    return BalanceJob(initial=initial, trial_runs=run[None, :], trial_unbalance_kg_m=np.array([trial]),
                      after=np.zeros(0, dtype=complex), units=units, mass_units=mass_units,
                      radius_m=np.array([float(radius_m)]), sensors=labels)


@dataclass(frozen=True, slots=True)
class FieldBalancingStudy:
    """Model against measurement, both methods, and the ball balancer.

    Attributes
    ----------
    speeds_rad_s : ndarray
        Balancing speeds (rad/s).
    alpha_true, alpha_model, alpha_measured : ndarray of complex
        Influence coefficients (m per kg m): the simulated rotor's, the Jeffcott model's
        from the identified k, c, M, and the one measured by the noisy trial runs.
    alpha_model_error, alpha_measured_error : ndarray
        ``|alpha_model - alpha_true| / |alpha_true|`` and the same for the measured one, per speed.
    unbalance_kg_m : complex
        The rotor's own unbalance ``M e`` (kg m; angle 0).
    least_squares, minmax : BalanceReport
    amplitude_before_m : ndarray
        True 1x amplitude before correction at each speed (m).
    amplitude_least_squares_m, amplitude_minmax_m, amplitude_model_only_m : ndarray
        True amplitude left by each correction (model only: correction computed from
        ``alpha_model`` and the initial readings, without a trial run).
    adb_speed_rad_s, adb_residual_amplitude_m, adb_amplitude_without_balls_m : float
        The ball balancer's run at constant speed (nan when the scene has none).
    """

    speeds_rad_s: np.ndarray
    alpha_true: np.ndarray
    alpha_model: np.ndarray
    alpha_measured: np.ndarray
    alpha_model_error: np.ndarray
    alpha_measured_error: np.ndarray
    unbalance_kg_m: complex
    least_squares: BalanceReport
    minmax: BalanceReport
    amplitude_before_m: np.ndarray
    amplitude_least_squares_m: np.ndarray
    amplitude_minmax_m: np.ndarray
    amplitude_model_only_m: np.ndarray
    adb_speed_rad_s: float
    adb_residual_amplitude_m: float
    adb_amplitude_without_balls_m: float

    def archive_units(self) -> dict[str, str]:
        """Units the field names cannot say (for the archive)."""
        return {"alpha_true": "m/(kg m)", "alpha_model": "m/(kg m)", "alpha_measured": "m/(kg m)",
                "alpha_model_error": "1", "alpha_measured_error": "1"}


def field_balancing_study(M: float, k: float, c: float, e: float, speeds_rad_s, *, trial_mass: float,
                          trial_angle_deg: float = 0.0, radius_m: float, noise: float = 0.05, seed: int = 0,
                          units: str = "um", mass_units: str = "g", adb=None,
                          model_k_c_M: tuple[float, float, float] | None = None) -> FieldBalancingStudy:
    """Run the study (module notes).

    ``M, k, c, e`` are the simulated rotor's truth; ``model_k_c_M`` the identified
    (k, c, M) that predict ``alpha_model`` (default: the truth); ``adb`` a
    :class:`~balancer.adb.SimulationResult` at constant speed, or None.
    """
    job = simulated_job(M, k, c, e, speeds_rad_s, trial_mass, trial_angle_deg, radius_m, noise, seed, units, mass_units)
    speeds = np.atleast_1d(np.asarray(speeds_rad_s, dtype=float))
    alpha_true = jeffcott_influence(k, c, M, speeds)
    alpha_model = jeffcott_influence(*(model_k_c_M or (k, c, M)), speeds)
    ls = balance(job, "least_squares")
    mm = balance(job, "minmax")
    u0 = M * e

    def true_amplitude(correction_kg_m):
        return np.abs(alpha_true * (u0 + correction_kg_m))

    model_only = np.linalg.lstsq(alpha_model[:, None], -job.initial, rcond=None)[0][0]
    adb_speed = adb_residual = adb_without = math.nan
    if adb is not None and adb.speed_rad_s.size and np.ptp(adb.speed_rad_s) == 0:
        adb_speed = float(adb.speed_rad_s[0])
        adb_residual = float(adb.residual_amplitude_m)
        adb_without = float(adb.residual_amplitude_without_balls_m)
    measured = ls.alpha[:, 0]
    return FieldBalancingStudy(
        speeds_rad_s=speeds, alpha_true=alpha_true, alpha_model=alpha_model, alpha_measured=measured,
        alpha_model_error=np.abs(alpha_model - alpha_true) / np.abs(alpha_true),
        alpha_measured_error=np.abs(measured - alpha_true) / np.abs(alpha_true), unbalance_kg_m=complex(u0),
        least_squares=ls, minmax=mm, amplitude_before_m=np.abs(alpha_true * u0),
        amplitude_least_squares_m=true_amplitude(ls.correction_kg_m[0]),
        amplitude_minmax_m=true_amplitude(mm.correction_kg_m[0]),
        amplitude_model_only_m=true_amplitude(model_only),
        adb_speed_rad_s=adb_speed, adb_residual_amplitude_m=adb_residual, adb_amplitude_without_balls_m=adb_without,
    )
