"""Analysis of simulated ball angles: settling time and final-state class.

Settling (``adb.md`` section 5): for two balls, the last time a ball is more than
``settle_tolerance * |phi*|`` from the nearest balanced configuration; otherwise the last
time the unbalance residual ``|M e + m R sum e^(i phi)|`` exceeds ``settle_tolerance * M e``.
"""
from __future__ import annotations

import math

import numpy as np

from .equilibria import balanced_ball_angles, unbalanced_states
from .parameters import ADBParameters

__all__ = ["FINAL_STATES", "LOCK_TOLERANCE_RAD", "settling_time", "classify_final_state"]

FINAL_STATES = ("balanced", "locked", "whirl", "transient")
LOCK_TOLERANCE_RAD = 0.05
"""Largest distance (rad) of a ball from an unbalanced equilibrium for a "locked" state."""



def _wrap(angle):
    return np.angle(np.exp(1j * angle))


def _outside_tolerance(params: ADBParameters, angles: np.ndarray, tolerance: float) -> np.ndarray:
    """Per sample: whether the balls are outside the settling tolerance. angles: (T, n)."""
    if params.n == 2 and params.can_balance:
        target = balanced_ball_angles(params)
        limit = tolerance * abs(target[0])
        straight = np.max(np.abs(_wrap(angles - target)), axis=-1)
        swapped = np.max(np.abs(_wrap(angles - target[::-1])), axis=-1)
        return np.minimum(straight, swapped) > limit
    a = params.unbalance_ratio
    residual = np.abs(a + np.sum(np.exp(1j * angles), axis=-1))
    return residual > tolerance * (a if a > 0 else 1.0)


def settling_time(params: ADBParameters, time_s, ball_angles_rad, tolerance: float = 0.01) -> float:
    """Time after which the balls stay within ``tolerance`` of a balanced configuration (s).

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    time_s : ndarray, shape (T,)
        Sample times (s).
    ball_angles_rad : ndarray, shape (T, n)
        Ball angles relative to the unbalance (rad).
    tolerance : float
        Relative tolerance (see the module notes).

    Returns
    -------
    float
        The last exit time, interpolated linearly between samples; 0 if never outside;
        ``inf`` if still outside at the last sample or if balancing is impossible.
    """
    if not params.can_balance:
        return math.inf
    outside = _outside_tolerance(params, np.asarray(ball_angles_rad), tolerance)
    if outside[-1]:
        return math.inf
    if not np.any(outside):
        return 0.0
    last = int(np.nonzero(outside)[0][-1])
    return float(0.5 * (time_s[last] + time_s[last + 1]))


def classify_final_state(params: ADBParameters, time_s, ball_angles_rad, ball_rates_rad_s,
                         *, window_start_s: float, final_speed_rad_s: float, tolerance: float = 0.01
                         ) -> tuple[str, np.ndarray]:
    """Classify the end of a run and return the balls' mean slip rates over the window.

    Classes: ``"balanced"`` (within ``tolerance`` of a balanced configuration throughout
    the window); ``"whirl"`` (non-synchronous: some ball slips by more than 0.5 rad over
    the window at a steady rate: its mean rates over the two halves of the window of one
    sign and within a factor 2); ``"locked"`` (throughout the window every
    ball is within ``LOCK_TOLERANCE_RAD`` of an unbalanced equilibrium at the final speed,
    balls together on the deflection line, and ``|phi'| < 0.05 omega_n``); else
    ``"transient"`` (still settling: lengthen the run).

    Parameters
    ----------
    params : ADBParameters
        Parameters.
    time_s : ndarray, shape (T,)
        Sample times (s).
    ball_angles_rad, ball_rates_rad_s : ndarray, shape (T, n)
        Relative ball angles (rad) and rates (rad/s).
    window_start_s : float
        Start of the final window (s).
    final_speed_rad_s : float
        Shaft speed at the end of the run (rad/s), for the unbalanced equilibria.
    tolerance : float
        Settling tolerance.

    Returns
    -------
    (str, ndarray)
        Class name and mean relative rate of each ball over the window (rad/s).
    """
    window = time_s >= window_start_s
    if np.count_nonzero(window) < 2:
        window = np.zeros_like(window)
        window[-2:] = True
    angles, rates, t = ball_angles_rad[window], ball_rates_rad_s[window], time_s[window]
    drift = angles[-1] - angles[0]
    slip = drift / (t[-1] - t[0])
    if params.can_balance and not np.any(_outside_tolerance(params, angles, tolerance)):
        return "balanced", slip
    middle = len(t) // 2
    first = (angles[middle] - angles[0]) / (t[middle] - t[0])
    second = (angles[-1] - angles[middle]) / (t[-1] - t[middle])
    steady = (first * second > 0) & (np.abs(second) >= 0.5 * np.abs(first)) & (np.abs(second) <= 2 * np.abs(first))
    if np.any((np.abs(drift) > 0.5) & steady):
        return "whirl", slip
    if final_speed_rad_s and np.max(np.abs(rates)) < 0.05 * params.natural_frequency_rad_s:
        for state, p in unbalanced_states(params, abs(final_speed_rad_s)):
            gamma = state[2]
            near_gamma = np.abs(_wrap(angles - gamma)) < LOCK_TOLERANCE_RAD
            near_opposite = np.abs(_wrap(angles - gamma - math.pi)) < LOCK_TOLERANCE_RAD
            if np.all(near_gamma | near_opposite) and np.all(np.sum(near_gamma, axis=-1) == p):
                return "locked", slip
    return "transient", slip
