"""Plots of FRFs and fits. Functions return a ``matplotlib.figure.Figure``
built without pyplot (no global state, nothing shown)."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .frf import FRF, KIND_POWER
from .model import mode_basis
from .results import IdentificationResult

__all__ = ["plot_fit", "model_response"]


def model_response(frf: FRF, result: IdentificationResult) -> np.ndarray:
    """The fitted modes summed on the FRF's lines, shape (n_channels, n_freq)."""
    omega = frf.omega_rad_s
    power = KIND_POWER[frf.kind]
    total = np.zeros((frf.n_channels, frf.n_freq), dtype=complex)
    for mode in result:
        phi = mode_basis(omega, mode.omega_n_rad_s, mode.damping_ratio, power)[0]
        const = np.atleast_1d(np.asarray(mode.modal_constant, complex))
        total += np.nan_to_num(const)[:, None] * phi[None, :]
    return total


def plot_fit(frf: FRF, result: IdentificationResult, channel: int = 0, figure: Figure | None = None) -> Figure:
    """Magnitude and phase with the fitted model over the data, and each mode's Nyquist plot.

    Parameters
    ----------
    frf : FRF
    result : IdentificationResult
        From :func:`modal.identify` on ``frf``.
    channel : int
        Channel to draw.
    figure : Figure, optional
        Figure to draw into (a new one by default).
    """
    fig = figure if figure is not None else Figure(figsize=(11, 7), layout="constrained")
    n_modes = max(len(result), 1)
    grid = fig.add_gridspec(3, max(n_modes, 2))
    ax_mag = fig.add_subplot(grid[0, :])
    ax_phase = fig.add_subplot(grid[1, :], sharex=ax_mag)
    f = frf.frequency_hz
    data = frf.channels[channel]
    model = model_response(frf, result)[channel]
    ax_mag.semilogy(f, np.abs(data), ".", ms=2, label="data")
    ax_mag.semilogy(f, np.abs(model), "-", lw=1, label=f"model ({result.method})")
    ax_mag.set_ylabel(f"|H| [{frf.units}]")
    ax_mag.legend(loc="best", fontsize="small")
    ax_phase.plot(f, np.degrees(np.angle(data)), ".", ms=2)
    ax_phase.plot(f, np.degrees(np.angle(model)), "-", lw=1)
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_xlabel("frequency [Hz]")
    for mode in result:
        for ax in (ax_mag, ax_phase):
            ax.axvline(mode.natural_frequency_hz, color="0.7", lw=0.6, zorder=0)
    power = KIND_POWER[frf.kind]
    for r, mode in enumerate(result):
        ax = fig.add_subplot(grid[2, r])
        low, high = mode.band_hz
        keep = (f >= low) & (f <= high)
        omega = frf.omega_rad_s[keep]
        to_mobility = (1j * omega) ** (1 - power) if not np.any(omega == 0) else np.ones_like(omega)
        y = data[keep] * to_mobility
        dense = np.linspace(omega[0], omega[-1], 400)
        ym = model_response(FRF(dense / (2 * np.pi), np.zeros(dense.size), kind=frf.kind), result)[channel]
        ym = ym * ((1j * dense) ** (1 - power) if not np.any(dense == 0) else 1)
        offset = np.mean(y - model[keep] * to_mobility)
        ax.plot(y.real, y.imag, ".", ms=3)
        ax.plot((ym + offset).real, (ym + offset).imag, "-", lw=1)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"mode {r + 1}: {mode.natural_frequency_hz:.4g} Hz", fontsize="small")
        ax.set_xlabel("Re Y")
        if r == 0:
            ax.set_ylabel("Im Y (mobility)")
    return fig
