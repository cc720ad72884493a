"""Plots of a global identification: the stabilisation diagram over the summed FRF, measured against
synthesised FRFs, and the MAC matrix. Each returns a Figure built without pyplot."""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..frf import FRF
from ..results import IdentificationResult

__all__ = ["plot_stabilisation", "plot_synthesis", "plot_mac"]


def plot_stabilisation(frf: FRF, result: IdentificationResult, figure: Figure | None = None) -> Figure:
    """Poles of every order (marker by stability) over the RMS of |H| across channels; chosen modes marked.

    Legend: ``o`` stable in frequency, damping and participation; ``d`` in frequency and damping;
    ``v`` in frequency and vector; ``f`` in frequency only; ``.`` new or unstable.
    """
    diagram = result.stabilisation
    if diagram is None:
        raise ValueError("plot_stabilisation needs a result of method 'global'")
    fig = figure if figure is not None else Figure(figsize=(11, 6), layout="constrained")
    ax = fig.add_subplot()
    kinds = [
        ("new or unstable", ~diagram.stable_frequency, ".", "0.6"),
        ("frequency", diagram.stable_frequency & ~diagram.stable_damping & ~diagram.stable_vector, "x", "tab:orange"),
        ("frequency + vector", diagram.stable_vector & ~diagram.stable_damping, "^", "tab:purple"),
        ("frequency + damping", diagram.stable_damping & ~diagram.stable_vector, "d", "tab:blue"),
        ("all stable", diagram.stable, "o", "tab:green"),
    ]
    for label, mask, marker, color in kinds:
        ax.plot(diagram.frequency_hz[mask], diagram.order[mask], marker, ms=3.5, color=color, ls="none", label=label)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    for mode in result:
        ax.axvline(mode.natural_frequency_hz, color="tab:red" if not mode.ok else "tab:green", lw=0.8, alpha=0.6)
    twin = ax.twinx()
    rms = np.sqrt(np.mean(np.abs(frf.channels) ** 2, axis=0))
    twin.semilogy(frf.frequency_hz, rms, color="k", lw=0.8, alpha=0.7)
    twin.set_ylabel(f"RMS |H| over channels [{frf.units}]")
    lo, hi = result.settings.get("band_hz", [frf.frequency_hz[0], frf.frequency_hz[-1]])
    ax.set_xlim(lo, hi)
    ax.legend(loc="upper left", fontsize="small", ncols=5)
    ax.set_title(f"stabilisation diagram ({len(result)} modes chosen: green lines clean, red flagged)",
                 fontsize="medium")
    return fig


def plot_synthesis(frf: FRF, result: IdentificationResult, channels=None, figure: Figure | None = None) -> Figure:
    """Measured (dots) and synthesised (lines) magnitude per channel (at most 6 by default)."""
    fig = figure if figure is not None else Figure(figsize=(11, 6), layout="constrained")
    ax = fig.add_subplot()
    synth = result.synthesize(frf.frequency_hz[frf.frequency_hz > 0])
    f = synth.frequency_hz
    measured = frf.channels[:, frf.frequency_hz > 0]
    chosen = range(min(frf.n_channels, 6)) if channels is None else channels
    for k in chosen:
        ax.semilogy(f, np.abs(measured[k]), ".", ms=2, color=f"C{k % 10}")
        ax.semilogy(f, np.abs(synth.channels[k]), "-", lw=0.9, color=f"C{k % 10}", label=f"channel {k + 1}")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"|H| [{frf.units}]")
    ax.legend(loc="best", fontsize="small", ncols=3)
    ax.set_title("measured (dots) and synthesised (lines)", fontsize="medium")
    return fig


def plot_mac(result: IdentificationResult, figure: Figure | None = None) -> Figure:
    """The MAC matrix of the identified modes."""
    fig = figure if figure is not None else Figure(figsize=(6, 5), layout="constrained")
    ax = fig.add_subplot()
    mac = result.mac()
    image = ax.imshow(mac, vmin=0, vmax=1, cmap="viridis")
    labels = [f"{m.natural_frequency_hz:.4g}" for m in result]
    ax.set_xticks(range(len(labels)), labels, rotation=90, fontsize="x-small")
    ax.set_yticks(range(len(labels)), labels, fontsize="x-small")
    ax.set_xlabel("mode [Hz]")
    ax.set_ylabel("mode [Hz]")
    fig.colorbar(image, ax=ax, label="MAC")
    return fig
