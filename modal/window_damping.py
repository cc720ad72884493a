"""Taking the exponential window's damping back out of an identified pole.

An exponential window exp(−t/τ) applied to force and response records makes
the measured FRF H(iω + 1/τ): every pole p = −ζωn + iωd moves to p − 1/τ and
the residues stay. So the true pole is the identified one moved right by 1/τ
(exact, not the first-order ζ − 1/(τωn)):

    σ = ζ_m ωn_m − 1/τ,   ωd = ωn_m √(1 − ζ_m²),   ωn = √(ωd² + σ²),   ζ = σ/ωn.

The window multiplies the signal the sensor recorded: for a receptance from displacements the
residues stay; an accelerometer's record windowed gives (s + 1/τ)² X(s + 1/τ), which near the
moved pole p' = p − 1/τ reads as s² R (p/p')² / (s − p'): the modal constant fitted to it is
the true one times (p/p')^q, q the power of iω of the kind (2 for accelerance, 1 for mobility),
a phase of about −q/(ωτ) and a magnitude of 1 + ... (1/(ωτ))²; :func:`window_constant_factor` gives
the factor that takes it back out. k and c follow from the corrected ωn and ζ. Covariances go
through the Jacobian of the map.

The correction acts on identified poles and their covariances, so it lives with
identification (:func:`modal.assemble.assemble_modes` applies it); the FRF only
carries the fact it needs, the window's τ (:attr:`modal.frf.FRF.exponential_decay_s`).
"""
from __future__ import annotations

import numpy as np

__all__ = ["remove_window_damping", "window_constant_factor"]


def remove_window_damping(omega_n: float, damping_ratio: float, cov: np.ndarray, std_omega_n: float,
                          std_damping_ratio: float, decay_s: float):
    """Move an identified pole right by 1/τ.

    Parameters
    ----------
    omega_n : float
        Identified natural frequency, rad/s.
    damping_ratio : float
        Identified damping ratio (window included).
    cov : ndarray, shape (n_channels, 4, 4)
        Covariance of (ωn, ζ, Re A, Im A) per channel.
    std_omega_n, std_damping_ratio : float
        Reported standard errors of ωn (rad/s) and ζ (may exceed ``cov``'s, e.g. with a method bias folded in).
    decay_s : float
        The window's time constant τ, s.

    Returns
    -------
    omega_n, damping_ratio, cov, std_omega_n, std_damping_ratio, window_damping_ratio, valid
        ``valid`` is False when the measured decay rate ζωn is not above 1/τ (the
        window made all of the damping): then the inputs come back unchanged.
    """
    rate = 1.0 / decay_s
    sigma = damping_ratio * omega_n - rate
    if not (np.isfinite(sigma) and sigma > 0):
        return omega_n, damping_ratio, cov, std_omega_n, std_damping_ratio, 0.0, False
    wn2 = omega_n**2 - 2.0 * damping_ratio * omega_n * rate + rate**2  # ωd² + σ²
    wn = float(np.sqrt(wn2))
    zeta = float(sigma / wn)
    d_wn = np.array([(omega_n - damping_ratio * rate) / wn, -omega_n * rate / wn])
    d_zeta = (np.array([damping_ratio, omega_n]) * wn - sigma * d_wn) / wn2
    jac = np.eye(4)
    jac[0, :2], jac[1, :2] = d_wn, d_zeta
    cov = jac @ cov @ jac.T
    reported = jac[:2, :2] @ np.diag([std_omega_n**2, std_damping_ratio**2]) @ jac[:2, :2].T
    return (wn, zeta, cov, float(np.sqrt(reported[0, 0])), float(np.sqrt(reported[1, 1])),
            float(damping_ratio - zeta), True)


def window_constant_factor(omega_n_measured: float, damping_ratio_measured: float, omega_n: float,
                           damping_ratio: float, power: int) -> complex:
    """(p'/p)^power: what a modal constant fitted to an exponentially windowed FRF is multiplied by to be the
    structure's, p' the measured (windowed) pole and p the corrected one (rad/s, dimensionless ratios), for an
    FRF whose kind's power of iω is ``power``, recorded as that quantity (see the module)."""
    def pole(wn, zeta):
        return complex(-zeta * wn, wn * np.sqrt(max(1.0 - zeta**2, 0.0)))

    return complex((pole(omega_n_measured, damping_ratio_measured) / pole(omega_n, damping_ratio)) ** int(power))
