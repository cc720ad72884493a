"""Splitting a correction onto fixed positions (holes, blades, bolts).

A correction ``u`` (kg m) whose angle falls between two adjacent positions
``theta_1 < angle < theta_2`` is the sum of non-negative amounts on those two:
``u = a exp(i theta_1) + b exp(i theta_2)`` with
``a = Im(u exp(-i theta_2)) / sin(theta_1 - theta_2)`` and
``b = Im(u exp(-i theta_1)) / sin(theta_2 - theta_1)`` (Cramer's rule).  Angles as in
:mod:`balancer.influence.readings` (degrees from the mark, against rotation).
"""
from __future__ import annotations

import numpy as np

from modal.errors import ParameterError

__all__ = ["split_correction", "equally_spaced_deg"]


def equally_spaced_deg(n_holes: int, first_deg: float = 0.0) -> np.ndarray:
    """``n_holes`` equally spaced positions (deg), the first at ``first_deg``."""
    if int(n_holes) != n_holes or n_holes < 3:
        raise ParameterError(f"holes = {n_holes!r}: expected an integer >= 3 (adjacent holes less than 180 deg apart)")
    return np.mod(first_deg + 360.0 * np.arange(int(n_holes)) / int(n_holes), 360.0)


def split_correction(unbalance, positions_deg) -> np.ndarray:
    """Amounts on the given positions that add up to ``unbalance``.

    Parameters
    ----------
    unbalance : complex or array_like of complex, shape (...)
        Correction(s) to realise (kg m, or any unit: amounts come out in the same one).
    positions_deg : array_like of float, shape (n_positions,)
        Available angular positions (deg), distinct modulo 360, in any order.

    Returns
    -------
    ndarray of float, shape (..., n_positions)
        Non-negative amounts, at most two non-zero and on adjacent positions, such
        that ``sum(amounts * exp(1j * radians(positions_deg)))`` equals ``unbalance``.

    Raises
    ------
    ParameterError
        Fewer than two positions, repeated or non-finite positions, or a correction
        whose angle lies in a gap of more than 180 deg between adjacent positions
        (it cannot be made from non-negative amounts there).
    """
    positions = np.asarray(positions_deg, dtype=float)
    if positions.ndim != 1 or positions.size < 2:
        raise ParameterError(f"positions_deg: {positions.size} position(s); expected at least two")
    if not np.all(np.isfinite(positions)):
        raise ParameterError("positions_deg: expected finite angles")
    wrapped = np.mod(positions, 360.0)
    order = np.argsort(wrapped, kind="stable")
    sorted_deg = wrapped[order]
    if np.any(np.diff(sorted_deg) <= 0) or sorted_deg[0] + 360.0 - sorted_deg[-1] <= 0:
        raise ParameterError("positions_deg: two positions coincide (modulo 360 deg); expected distinct positions")
    u = np.asarray(unbalance, dtype=complex)
    if not np.all(np.isfinite(u)):
        raise ParameterError("unbalance: expected finite values")
    angle = np.mod(np.rad2deg(np.angle(u)), 360.0)
    # index of the position at or before the angle (cyclic), and the next one
    lower = (np.searchsorted(sorted_deg, angle, side="right") - 1) % sorted_deg.size
    upper = (lower + 1) % sorted_deg.size
    gap = np.mod(sorted_deg[upper] - sorted_deg[lower], 360.0)
    gap = np.where(gap == 0, 360.0, gap)
    too_wide = (gap >= 180.0) & (np.mod(angle - sorted_deg[lower], 360.0) > 0) & (np.abs(u) > 0)
    if np.any(too_wide):
        k = np.flatnonzero(too_wide.ravel())[0]
        lo, hi = sorted_deg[lower.ravel()[k]], sorted_deg[upper.ravel()[k]]
        raise ParameterError(f"positions_deg: the correction at {angle.ravel()[k]:.1f} deg lies between positions {lo:g} and "
                             f"{hi:g} deg, {gap.ravel()[k]:g} deg apart; expected adjacent positions less than 180 deg apart")
    t1 = np.deg2rad(sorted_deg[lower])
    t2 = np.deg2rad(sorted_deg[upper])
    sin12 = np.sin(t1 - t2)
    exact = np.mod(angle - sorted_deg[lower], 360.0) == 0
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(exact, np.abs(u), (u * np.exp(-1j * t2)).imag / sin12)
        b = np.where(exact, 0.0, (u * np.exp(-1j * t1)).imag / -sin12)
    amounts_sorted = np.zeros(u.shape + (sorted_deg.size,))
    np.put_along_axis(amounts_sorted, lower[..., None], np.maximum(a, 0.0)[..., None], axis=-1)
    np.put_along_axis(amounts_sorted, upper[..., None], np.maximum(b, 0.0)[..., None], axis=-1)
    amounts = np.empty_like(amounts_sorted)
    amounts[..., order] = amounts_sorted
    return amounts
