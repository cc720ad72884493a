"""Figures of an operational identification: the stabilisation diagram over the first singular value of
the output half-spectra, and the mode shapes. Each returns a Figure built without pyplot."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..results import IdentificationResult

__all__ = ["plot_stabilisation", "plot_shapes"]


def plot_stabilisation(result: IdentificationResult, spectrum=None, figure: Figure | None = None) -> Figure:
    """Poles of every order (stable ones filled), the chosen modes (green lines; red when flagged) and the tones
    (grey dashed), over ``spectrum`` = (frequency Hz, first singular value) when given."""
    diagram = result.stabilisation
    if diagram is None:
        raise ValueError("plot_stabilisation needs a result of method 'ssi' or 'plscf' (FDD has no diagram)")
    fig = figure if figure is not None else Figure(figsize=(11, 6), layout="constrained")
    ax = fig.add_subplot()
    loose = ~diagram.stable
    ax.plot(diagram.frequency_hz[loose], diagram.order[loose], ".", ms=2.5, color="0.65", label="new or unstable")
    stable = diagram.stable & (diagram.cluster < 0) & ~diagram.tone
    ax.plot(diagram.frequency_hz[stable], diagram.order[stable], "x", ms=3.5, color="tab:orange",
            label="stable, not a mode (chain too short, noise pole)")
    in_mode = diagram.stable & (diagram.cluster >= 0)
    ax.plot(diagram.frequency_hz[in_mode], diagram.order[in_mode], "o", ms=3.5, color="tab:blue",
            label="stable, in a mode's cluster")
    tone = diagram.stable & diagram.tone
    ax.plot(diagram.frequency_hz[tone], diagram.order[tone], "s", ms=3.5, color="tab:purple", label="machine tone")
    chosen = diagram.chosen
    ax.plot(diagram.frequency_hz[chosen], diagram.order[chosen], "*", ms=10, color="k", label="reported pole")
    for mode in result:
        ax.axvline(mode.natural_frequency_hz, color="tab:red" if not mode.ok else "tab:green", lw=0.8, alpha=0.6)
    for f in result.harmonics_hz:
        ax.axvline(f, color="0.4", lw=0.8, ls="--", alpha=0.6)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    if spectrum is not None:
        twin = ax.twinx()
        twin.semilogy(spectrum[0], spectrum[1], color="k", lw=0.8, alpha=0.7)
        twin.set_ylabel("first singular value of the half-spectra (channels at unit RMS)")
    lo, hi = result.settings.get("band_hz", [np.min(diagram.frequency_hz), np.max(diagram.frequency_hz)])
    ax.set_xlim(lo, hi)
    ax.legend(loc="upper left", fontsize="small", ncols=3)
    ax.set_title(f"stabilisation diagram, {result.method}: {len(result)} modes (green clean, red flagged), "
                 f"{len(result.harmonics_hz)} tones (dashed)", fontsize="medium")
    return fig


def plot_shapes(result: IdentificationResult, figure: Figure | None = None) -> Figure:
    """Each mode's shape over the channels (real part of the shape turned to its dominant phase), with error bars."""
    fig = figure if figure is not None else Figure(figsize=(11, 2.2 * max(len(result), 1)), layout="constrained")
    axes = fig.subplots(max(len(result), 1), 1, squeeze=False)[:, 0]
    for ax, mode in zip(axes, result):
        shape = np.asarray(mode.mode_shape, complex)
        turn = np.exp(-1j * np.angle(np.sum(shape**2)) / 2)
        ax.bar(np.arange(shape.size), (shape * turn).real, yerr=mode.std.mode_shape, color="tab:blue")
        ax.axhline(0, color="k", lw=0.6)
        ax.set_ylabel(f"{mode.natural_frequency_hz:.4g} Hz")
    axes[-1].set_xlabel("channel (0-based)")
    return fig
