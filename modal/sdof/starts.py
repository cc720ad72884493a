"""Start values of the band-wise least-squares fit: one pole (ωn, ζ) per band.

The cheap start is a band's one-mode rational fit (:func:`quick_start`,
:func:`modal.sdof.rational.rational_pole`); the careful one the better of the
half-power and circle estimates (:func:`start_pole`), on the principal combination
of the strongest channels when there are many (:func:`principal_start`).
"""
from __future__ import annotations

import warnings

import numpy as np

from ..frf import FRF
from ..model import mode_basis, solve_linear
from ..units import TWO_PI
from .bands import band_lines, band_mask, strongest_channels
from .estimates import sdof_estimates
from .rational import rational_pole

__all__ = ["START_CHANNELS", "start_pole", "principal_start", "quick_start"]

#: channels (strongest first) used for the NLS start values
START_CHANNELS = 8


def _linear_constants(omega, h, power, wn, zeta):
    """Modal constant per channel for a given pole, with a band offset; and its variance."""
    phi = mode_basis(omega, wn, zeta, power)[0]
    Phi = np.column_stack([phi, np.ones_like(phi)])
    coef = solve_linear(Phi, h.T)
    res = h.T - Phi @ coef
    dof = max(omega.size - 2, 1)
    noise_var = np.sum(np.abs(res) ** 2, axis=0) / dof
    gram_inv = np.linalg.inv(Phi.conj().T @ Phi)
    return coef[0], noise_var * np.real(gram_inv[0, 0]), float(np.linalg.norm(res) ** 2)


def start_pole(frf, band, power, noise):
    """Best start of (ωn, ζ) among half-power and circle, by residual with A solved linearly."""
    omega, h = band_lines(frf, band)
    strongest = strongest_channels(frf, band, noise, START_CHANNELS)
    candidates = []
    for method in ("halfpower", "circle"):
        with np.errstate(all="ignore"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                wn, zeta, *_ = sdof_estimates(frf, band, power, noise, method, channels=strongest, errors=False)
        if np.isfinite(wn) and np.isfinite(zeta) and wn > 0 and zeta > 0:
            candidates.append((wn, zeta))
    if not candidates:
        i = np.argmax(np.abs(h).max(axis=0))
        candidates.append((omega[i], max(np.min(np.diff(omega)) / omega[i], 1e-6)))
    best = min(candidates, key=lambda c: _linear_constants(omega, h[strongest], power, *c)[2])
    return best


def principal_start(frf, band, power, noise):
    """:func:`start_pole` of a many-channel band on one curve: the principal combination of its
    ``START_CHANNELS`` strongest channels.

    Any linear combination of the channels is an FRF with the same poles. The channels,
    each divided by its noise σ, are combined with the first left singular vector of
    their band (the combination of most energy, unit norm: its noise σ is 1), and the
    start is searched on that one curve (:func:`start_pole` of a one-channel FRF): two
    single-channel estimates per band instead of two per channel.
    """
    keep = band_mask(frf, band)
    strongest = strongest_channels(frf, band, noise, START_CHANNELS)
    sigma = np.asarray(noise, float)[strongest]
    usable = np.isfinite(sigma) & (sigma > 0)
    if not usable.any():
        sigma = np.ones_like(sigma)
    else:  # a channel without a noise level counts as the quietest one
        sigma = np.where(usable, sigma, np.min(sigma[usable]))
    h = frf.channels[strongest][:, keep] / sigma[:, None]
    try:
        u, _, _ = np.linalg.svd(h, full_matrices=False)
    except np.linalg.LinAlgError:
        return start_pole(frf, band, power, noise)
    curve = u[:, 0].conj() @ h
    if not np.all(np.isfinite(curve)):
        return start_pole(frf, band, power, noise)
    one = FRF(frf.frequency_hz[keep], curve, kind=frf.kind, source=frf.source)
    wn, zeta = start_pole(one, band, power, np.ones(1))
    return wn, zeta


def quick_start(frf, band, power, noise):
    """(ωn, ζ) of a band's one-mode rational fit (:func:`modal.sdof.rational.rational_pole`) on its
    strongest channels, or None when it gives no pole inside the band."""
    keep = band_mask(frf, band)
    omega, h = frf.omega_rad_s[keep], frf.channels
    if h.shape[0] > START_CHANNELS:  # the strongest channels first: no copy of every channel's band
        strongest = strongest_channels(frf, band, noise, START_CHANNELS)
        h, noise = h[strongest], np.asarray(noise)[strongest]
    h = h[:, keep]
    with np.errstate(all="ignore"):
        pole = rational_pole(omega, h, noise)
    if pole is None or not (TWO_PI * band.low_hz <= pole[0] <= TWO_PI * band.high_hz and 0 < pole[1] < 1):
        return None
    return pole
