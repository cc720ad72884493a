"""The exponential window's factor on a windowed velocity or acceleration, out of the FRF before a global fit.

An exponential window exp(−t/τ) on force and response records moves every pole left by 1/τ
(:mod:`modal.window_damping`). On a record of a velocity or an acceleration (an FRF of power q of iω:
mobility 1, accelerance 2) it does more: the windowed record's transform is (s + 1/τ)^q X(s + 1/τ), so the
measured FRF is ((iω + 1/τ)/(iω))^q times the modal model s^q Σ R/(s − p′) at the moved poles p′. Near a pole
that factor is nearly a constant, which the modal constant takes up (:func:`modal.window_damping.window_constant_factor`
turns it back); over a global fit's whole band it is not: (1 − i/(ωτ))² changes by 13 % in magnitude between
5 and 40 Hz at τ = 0.5 s, a misfit no mode or residual term describes. On noise-free records of the chain's
two-mode structure (3 accelerometers, 6 hits, τ = 0.5 s) it moved the 40 Hz mode by −3.4e-4 Hz (0.35 of its
standard error at 0.2 % noise; −1.4e-4 Hz at τ = 1 s, −3.7e-5 Hz at τ = 2 s). Divided out of the data, the
FRF is the modal model at the moved poles with the structure's own constants.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..frf import FRF, KIND_POWER

__all__ = ["window_factor", "without_window_factor"]


def window_factor(frf: FRF) -> np.ndarray | None:
    """((iω + 1/τ)/(iω))^q on the FRF's lines (q its kind's power of iω, τ its ``exponential_decay_s``), or None
    where there is none to take out (no exponential window, a receptance, or a line at 0 Hz)."""
    power = KIND_POWER[frf.kind]
    if frf.exponential_decay_s is None or power == 0 or np.any(frf.omega_rad_s <= 0):
        return None
    iw = 1j * frf.omega_rad_s
    return ((iw + 1.0 / frf.exponential_decay_s) / iw) ** power


def without_window_factor(frf: FRF) -> tuple[FRF, bool]:
    """The FRF divided by :func:`window_factor`, its noise with it, and whether it was.

    ``noise_std`` is divided by |factor|, the noise model's variance by |factor|² and each line pair's
    correlation turned by the factor's phases (e_k/g_k and e_{k+m}/g_{k+m} correlate by ρ conj(u_k) u_{k+m},
    u = g/|g|); the records' influences are divided by the factor as the data are.
    """
    factor = window_factor(frf)
    if factor is None:
        return frf, False
    magnitude = np.abs(factor)
    noise = None if frf.noise_std is None else frf.noise_std / magnitude
    model = frf.noise_model
    if model is not None:
        model = model.scaled(1.0 / magnitude**2, 1.0 / factor)
        if model.line_correlation is not None:
            turn = factor / magnitude
            corr = np.array(model.line_correlation)
            for m in range(1, corr.shape[0] + 1):
                corr[m - 1, :-m] *= np.conj(turn[:-m]) * turn[m:]
            model = replace(model, line_correlation=corr)
    return replace(frf, response=frf.response / factor, noise_std=noise, noise_model=model), True
