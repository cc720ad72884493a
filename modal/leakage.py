"""The bias a window puts into an FRF estimated from time records, for a model of modes.

An estimate from windowed records is, in expectation, the transform of the impulse
response times the estimate's lag window ρ(τ) (:mod:`modal.noise_model`): the
spectrum smoothed by the window (leakage). For a mode that decays slowly against the
record, this broadens the peak: a Hann window on 8192-sample segments raised ζ by
0.6 % of its value, 2.8 standard errors over a 240 s record; a rectangular window on
random excitation adds ≈ 1/T to the decay rate.

:func:`window_bias` gives, for modes (ωn, ζ, modal constant) and the FRF's kind, the
difference E[Ĥ] − H at any line: with the pole form of a mode,
A/((s − p)(s − p̄)) = A/(p − p̄) · [1/(s − p) − 1/(s − p̄)], each term 1/(s − q) of the
kind (s^k/(s − q) = q^k/(s − q) + a polynomial, which the window leaves alone) is
sampled as T Σ_τ e^{qτT} e^{−iωτT}, and the window changes it by

    Δ(ω; q) = T Σ_{τ=0}^{N−1} (ρ(τ) − 1) z^τ − T z^N / (1 − z),   z = e^{(q − iω)T},

the first sum the smoothing inside the record, the second the decay cut off at its end.
The identification fits the data less this bias of its own modes (a fixed point: the
model convolved with the lag window), so the residual holds noise, not the window.
"""
from __future__ import annotations

import numpy as np

__all__ = ["window_bias", "bias_matters"]

#: the window's bias is taken out when ρ(τ) departs from 1 by more than this anywhere a mode's decay
#: has not died away (to 1e-6 of its start)
RHO_TOLERANCE = 1e-9


def _pole_terms(omega: np.ndarray, pole: complex, lag_window: np.ndarray, interval_s: float) -> np.ndarray:
    """Δ(ω; q) of the module for one pole q (rad/s) at the lines ``omega`` (rad/s)."""
    n = lag_window.size
    step = np.exp((pole - 1j * omega) * interval_s)  # z per line
    deviation = lag_window - 1.0
    # only the lags where the pole's decay still matters (|z|^τ above 1e-17 of 1)
    decay = -pole.real * interval_s
    last = n if decay <= 0 else min(n, int(np.ceil(39.0 / decay)) + 1)
    bins = omega * n * interval_s / (2 * np.pi)  # the lines as multiples of the records' line spacing
    index = np.rint(bins).astype(int)
    if np.all(np.abs(bins - index) <= 1e-6 * np.maximum(1.0, np.abs(bins))) and np.all((index >= 0) & (index < n)):
        # the lines of the records' transform: one FFT of the lags gives every line
        sequence = np.zeros(n, complex)
        sequence[:last] = deviation[:last] * np.exp(pole * interval_s * np.arange(last))
        inside = np.fft.fft(sequence)[index]
    else:
        inside = np.zeros(omega.size, complex)
        rate = (pole - 1j * omega) * interval_s
        for first in range(0, last, 2048):  # blocks of lags: a bounded array whatever the record length
            tau = np.arange(first, min(first + 2048, last))
            inside += deviation[tau] @ np.exp(np.outer(tau, rate))
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        tail = np.where(n * decay > 745, 0.0, step**n / (1.0 - step))
    return interval_s * (inside - tail)


def window_bias(omega: np.ndarray, power: int, omega_n, damping_ratio, modal_constant, lag_window: np.ndarray,
                interval_s: float) -> np.ndarray:
    """E[Ĥ] − H of modes measured through a lag window, at the lines ``omega``.

    Parameters
    ----------
    omega : ndarray, shape (n_lines,)
        Lines, rad/s.
    power : int
        Kind of the FRF (0 receptance, 1 mobility, 2 accelerance).
    omega_n, damping_ratio : array_like, shape (n_modes,)
        rad/s, and dimensionless (0 < ζ < 1).
    modal_constant : array_like, shape (n_modes, n_channels)
        Receptance modal constants, 1/kg.
    lag_window : ndarray, shape (n_samples,)
        ρ(τ) of :class:`modal.noise_model.NoiseModel`.
    interval_s : float
        Sample interval, s.

    Returns
    -------
    ndarray, shape (n_channels, n_lines), complex
    """
    omega = np.asarray(omega, float)
    constants = np.atleast_2d(np.asarray(modal_constant, complex))
    out = np.zeros((constants.shape[1], omega.size), complex)
    for wn, zeta, const in zip(np.atleast_1d(omega_n), np.atleast_1d(damping_ratio), constants):
        if not (np.isfinite(wn) and np.isfinite(zeta) and 0 < zeta < 1 and wn > 0):
            continue
        pole = complex(-zeta * wn, wn * np.sqrt(1 - zeta**2))
        pole_c = pole.conjugate()
        shape = (pole**power * _pole_terms(omega, pole, lag_window, interval_s)
                 - pole_c**power * _pole_terms(omega, pole_c, lag_window, interval_s)) / (pole - pole_c)
        out += const[:, None] * shape[None, :]
    return out


def bias_matters(lag_window: np.ndarray | None, interval_s: float, omega_n, damping_ratio) -> bool:
    """Whether ρ(τ) departs from 1 (by more than :data:`RHO_TOLERANCE`) over the decay of the slowest mode."""
    if lag_window is None:
        return False
    rate = np.asarray(omega_n, float) * np.asarray(damping_ratio, float)
    rate = rate[np.isfinite(rate) & (rate > 0)]
    if rate.size == 0:
        return False
    last = min(lag_window.size, int(np.ceil(np.log(1e6) / (rate.min() * interval_s))) + 1)
    return bool(np.max(np.abs(lag_window[:last] - 1.0)) > RHO_TOLERANCE or last >= lag_window.size)
