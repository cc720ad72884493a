"""What the readings' repeatability does to a balancing job: the job redrawn, and the correction's spread.

Every reading (initial and trial runs) is redrawn with a relative circular Gaussian error of
``reading_noise`` (0.05: 5 % of its amplitude, about 3 deg of phase, a field analyser's repeatability on a
steady machine), and the influence coefficients and a least-squares correction are computed again from each
draw (:data:`BOOTSTRAP_DRAWS` draws, seeded: the same job gives the same numbers). The readings as measured
stand in for the truth (a parametric bootstrap).

From the draws: how much the correction's mass and angle would scatter between repeats of the same job
(:func:`correction_spread`), and how much vibration a correction computed from such readings leaves on the
machine (``worst_residual_p90``, the 90th percentile of the worst reading): the prediction from the readings
themselves (``initial + alpha @ u``) cannot be lower than the readings' errors allow, however small it prints.
:mod:`~balancer.influence.checkrun` uses the same draws to judge a check run.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BOOTSTRAP_DRAWS", "redraw", "redrawn_jobs", "CorrectionSpread", "correction_spread"]

#: bootstrap draws (a 99th percentile then rests on about four draws above it)
BOOTSTRAP_DRAWS = 400


def redraw(values: np.ndarray, noise: float, rng: np.random.Generator, per_draw: bool = False) -> np.ndarray:
    """``values`` with a relative circular Gaussian error of standard deviation ``noise`` on each, once per
    draw (``per_draw``: ``values`` already holds one set per draw along its first axis)."""
    shape = values.shape if per_draw else (BOOTSTRAP_DRAWS,) + values.shape
    return values * (1 + noise * (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / np.sqrt(2))


def redrawn_jobs(initial, trial_runs, trial_unbalance_kg_m, reading_noise: float, weights=None, seed: int = 0):
    """The job's readings redrawn, with each draw's influence coefficients and least-squares correction.

    Returns
    -------
    (initial, alpha, correction, rng) : ndarray (draws, n_readings), (draws, n_readings, n_planes),
        (draws, n_planes), and the generator (to draw more from the same stream).
    """
    v0 = np.asarray(initial, dtype=complex)
    runs = np.asarray(trial_runs, dtype=complex)
    trials = np.asarray(trial_unbalance_kg_m, dtype=complex)
    w = np.ones(v0.size) if weights is None else np.asarray(weights, dtype=float)
    rng = np.random.default_rng(seed)
    v0_b = redraw(v0, reading_noise, rng)
    runs_b = redraw(runs, reading_noise, rng)
    alpha_b = np.swapaxes(runs_b - v0_b[:, None, :], 1, 2) / trials
    # least squares of every draw at once, through the stacked pseudo-inverses (lstsq does not stack)
    u_b = -np.einsum("bpn,bn->bp", np.linalg.pinv(alpha_b * w[:, None]), v0_b * w)
    return v0_b, alpha_b, u_b, rng


@dataclass(frozen=True, slots=True)
class CorrectionSpread:
    """How the correction and what it leaves scatter with the readings' repeatability.

    Attributes
    ----------
    reading_noise : float
        Relative standard deviation of a reading assumed (1).
    mass_std_kg : ndarray, shape (n_planes,)
        Standard deviation of each plane's correction mass at its radius (kg).
    angle_std_deg : ndarray, shape (n_planes,)
        Standard deviation of each plane's correction angle (deg).
    worst_residual_p90 : float
        90th percentile of the worst reading a correction computed from such readings leaves (readings' SI unit).
    si_units : str
        The readings' SI unit.
    """

    reading_noise: float
    mass_std_kg: np.ndarray
    angle_std_deg: np.ndarray
    worst_residual_p90: float
    si_units: str = "m"

    def archive_units(self) -> dict[str, str]:
        """Units the field names cannot say (for the archive)."""
        return {"reading_noise": "1", "worst_residual_p90": self.si_units}


def correction_spread(initial, trial_runs, trial_unbalance_kg_m, radius_m, reading_noise: float, weights=None,
                      si_units: str = "m", seed: int = 0, draws=None) -> CorrectionSpread:
    """The correction's scatter and the vibration it leaves under ``reading_noise`` (module notes).

    Parameters
    ----------
    initial, trial_runs, trial_unbalance_kg_m
        The job as :func:`~balancer.influence.influence_matrix` takes it (SI readings, kg m).
    radius_m : array_like, shape (n_planes,)
        Radius of each plane's masses (m).
    reading_noise : float
        Relative standard deviation of a reading.
    weights : array_like, optional
        Per-reading weights of the least-squares correction.
    draws : tuple, optional
        :func:`redrawn_jobs` of the same job, noise and seed, when already made.
    """
    v0 = np.asarray(initial, dtype=complex)
    alpha = (np.asarray(trial_runs, dtype=complex) - v0).T / np.asarray(trial_unbalance_kg_m, dtype=complex)
    if draws is None:
        draws = redrawn_jobs(v0, trial_runs, trial_unbalance_kg_m, reading_noise, weights, seed)
    u_b = draws[2]
    centre = np.mean(u_b, axis=0)
    angle = np.rad2deg(np.angle(u_b / np.where(centre != 0, centre, 1.0)))
    left = np.max(np.abs(v0[None, :] + u_b @ alpha.T), axis=1)  # on the machine the readings describe
    return CorrectionSpread(reading_noise=float(reading_noise),
                            mass_std_kg=np.std(np.abs(u_b), axis=0) / np.asarray(radius_m, dtype=float),
                            angle_std_deg=np.sqrt(np.mean(angle ** 2, axis=0)),
                            worst_residual_p90=float(np.quantile(left, 0.9)), si_units=si_units)
