"""Plots of time records and of FRFs estimated from them.

Functions build a :class:`matplotlib.figure.Figure` without pyplot (no global
state, nothing shown); the caller saves or shows it.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .core import EstimatedFRF

__all__ = ["plot_hits", "plot_estimate"]


def plot_hits(force: np.ndarray, response: np.ndarray, sample_rate_hz: float, estimate: EstimatedFRF,
              figure: Figure | None = None) -> Figure:
    """The force and response records with each hit: accepted ones shaded, rejected ones marked with their reason.

    Parameters
    ----------
    force : ndarray, shape (n_samples,)
        Force record, N.
    response : ndarray, shape (n_samples,) or (n_outputs, n_samples)
        Response record(s); the first is drawn.
    sample_rate_hz : float
    estimate : EstimatedFRF
        From :func:`modal.estimate_frf` with ``impact=True`` on these records.
    """
    fig = figure if figure is not None else Figure(figsize=(11, 5.5), layout="constrained")
    ax_f, ax_y = fig.subplots(2, 1, sharex=True)
    t = np.arange(np.size(force)) / sample_rate_hz
    resp = np.atleast_2d(response)[0]
    ax_f.plot(t, force, lw=0.6, color="C0")
    ax_y.plot(t, resp, lw=0.6, color="C1")
    length_s = (estimate.segment_length or 0) / sample_rate_hz
    for number, start in enumerate(estimate.hit_times_s):
        for ax in (ax_f, ax_y):
            ax.axvspan(start, start + length_s, color="tab:green", alpha=0.12, lw=0,
                       label="accepted record" if (number == 0 and ax is ax_f) else None)
    for item in estimate.rejected:
        for ax in (ax_f, ax_y):
            ax.axvline(item["time_s"], color="tab:red", lw=1.0, ls="--")
        ax_f.annotate(f"hit {item['hit']}: {item['reason']}", (item["time_s"], 1.0), xycoords=("data", "axes fraction"),
                      rotation=90, va="top", ha="right", fontsize="x-small", color="tab:red")
    ax_f.set_ylabel("force [N]")
    ax_y.set_ylabel(f"response [{_quantity_unit(estimate)}]")
    ax_y.set_xlabel("time [s]")
    ax_f.set_title(f"{estimate.source}: {estimate.averages} hit(s) used, {len(estimate.rejected)} rejected",
                   fontsize="medium")
    if estimate.hit_times_s:
        ax_f.legend(loc="upper right", fontsize="small")
    return fig


def _quantity_unit(estimate: EstimatedFRF) -> str:
    units = estimate.units or ""
    return units[:-2] if units.endswith("/N") else "as measured"


def plot_estimate(estimate: EstimatedFRF, channels=None, figure: Figure | None = None) -> Figure:
    """Magnitude with its ±2σ random-error band, phase, and coherence below.

    Parameters
    ----------
    estimate : EstimatedFRF
    channels : sequence of int, optional
        Channels to draw (default: all, at most 8).
    """
    fig = figure if figure is not None else Figure(figsize=(11, 7.5), layout="constrained")
    ax_mag, ax_phase, ax_coh = fig.subplots(3, 1, sharex=True, height_ratios=[3, 1.5, 1.2])
    f = estimate.frequency_hz
    h = estimate.channels
    chosen = range(min(estimate.n_channels, 8)) if channels is None else channels
    noise = None if estimate.noise_std is None else np.atleast_2d(estimate.noise_std)
    coherence = None if estimate.coherence is None else np.atleast_2d(estimate.coherence)
    for k in chosen:
        color = f"C{k % 10}"
        label = _label(estimate, k)
        mag = np.abs(h[k])
        ax_mag.semilogy(f, mag, lw=0.9, color=color, label=label)
        if noise is not None:
            # |Ĥ| ± 2σ: the band that holds the true |H| about 95 % of the time (σ per line, Bendat & Piersol);
            # on a log axis a band reaching 0 is unbounded: its lower edge stops at |Ĥ|/10
            lower = np.maximum(mag - 2 * noise[k], mag / 10)
            ax_mag.fill_between(f, lower, mag + 2 * noise[k], color=color, alpha=0.2, lw=0)
        ax_phase.plot(f, np.degrees(np.angle(h[k])), lw=0.7, color=color)
        if coherence is not None:
            ax_coh.plot(f, coherence[k], lw=0.7, color=color)
    ax_mag.set_ylabel(f"|H| [{estimate.units}]")
    title = f"{estimate.estimator}, {estimate.averages} average(s), window {estimate.window}"
    if estimate.exponential_decay_s:
        title += f" (τ = {estimate.exponential_decay_s:g} s)"
    ax_mag.set_title(title + ("; band: ±2σ random error (lower edge at most a decade down)" if noise is not None
                              else ""), fontsize="medium")
    ax_mag.legend(loc="best", fontsize="small", ncols=2)
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_ylim(-190, 190)
    ax_phase.set_yticks([-180, -90, 0, 90, 180])
    ax_coh.set_ylabel("coherence")
    ax_coh.set_ylim(0, 1.05)
    ax_coh.set_xlabel("frequency [Hz]")
    ax_coh.set_xlim(f[0], f[-1])
    return fig


def _label(estimate: EstimatedFRF, k: int) -> str:
    if estimate.response_points is None:
        return f"channel {k + 1}"
    ref = estimate.reference_points[k] if estimate.reference_points is not None else "?"
    return f"{estimate.response_points[k]} / {ref}"
