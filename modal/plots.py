"""Plots of FRFs and fits. Functions return a ``matplotlib.figure.Figure``
built without pyplot (no global state, nothing shown)."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from .errors import ModalError
from .figures import gap_fraction, margins, minor_tick_marks, plain_log_ticks
from .frf import DEFAULT_UNITS, FRF, KIND_POWER
from .model import mode_basis
from .results import IdentificationResult

__all__ = ["plot_fit", "model_response", "modes_response", "nyquist_omega", "MAX_DRAWN_CHANNELS"]

#: Above this many channels the magnitude panel shows the RMS over channels only.
MAX_DRAWN_CHANNELS = 8
_NYQUIST_COLUMNS = 6
_STYLES = ("-", "--", ":", "-.")


def modes_response(omega_rad_s: np.ndarray, kind: str, result: IdentificationResult) -> np.ndarray:
    """The fitted modes (and residual terms, where fitted) summed on any lines.

    Parameters
    ----------
    omega_rad_s : ndarray
        Lines, rad/s.
    kind : str
        FRF kind of the result (its modal constants are receptance constants, 1/kg).
    result : IdentificationResult

    Returns
    -------
    ndarray of complex, shape (result.n_channels, n_lines)
    """
    omega = np.asarray(omega_rad_s, float)
    power = KIND_POWER[kind]
    total = np.zeros((result.n_channels, omega.size), dtype=complex)
    for mode in result:
        phi = mode_basis(omega, mode.omega_n_rad_s, mode.damping_ratio, power)[0]
        const = np.nan_to_num(np.atleast_1d(np.asarray(mode.modal_constant, complex)))
        total += const[:, None] * phi[None, :]
    if result.residuals is not None:
        upper, lower = np.asarray(result.residuals, complex).T
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = (1j * omega) ** power
            low = np.where(omega > 0, factor / np.where(omega > 0, omega, 1.0) ** 2, 0.0)
        total += upper[:, None] * factor[None, :] - lower[:, None] * low[None, :]
    return total


def model_response(frf: FRF, result: IdentificationResult) -> np.ndarray:
    """The fitted model on the FRF's lines, shape (n_channels, n_freq)."""
    return modes_response(frf.omega_rad_s, frf.kind, result)


def nyquist_omega(omega_n: float, zeta: float, low: float, high: float, n: int = 721) -> np.ndarray:
    """Lines (rad/s) in [low, high] that trace a mode's Nyquist circle evenly.

    Around a mode the circle's angle θ moves as ω = ωn (1 + ζ tan(θ/2)); equal
    steps in θ give a smooth circle however narrow the resonance is next to the
    band. Half of the points go there, the other half evenly over the band.
    """
    theta = np.linspace(-np.pi, np.pi, n // 2 + 2)[1:-1]
    near = omega_n * (1.0 + max(zeta, 1e-9) * np.tan(theta / 2))
    lines = np.concatenate([near, np.linspace(low, high, n - near.size)])
    lines = lines[(lines >= low) & (lines <= high)]
    return np.unique(lines)


def _as_results(result) -> list[IdentificationResult]:
    if isinstance(result, IdentificationResult):
        return [result]
    results = list(result)
    if not results:
        raise ModalError("plot_fit: no identification result to draw")
    return results


def _serious(mode) -> bool:
    """Whether a mode carries a flag a user should act on (not only driving-point bookkeeping)."""
    from .flags import serious_flags

    return bool(serious_flags(mode.flags))


def _model_name(result: IdentificationResult) -> str:
    """Legend name of a result's model: its method, and how many of its modes are flagged (a flagged
    model far from the data is then read as what it is, not as a drawing error)."""
    flagged = sum(_serious(m) for m in result.modes)
    return result.method + (f"; {flagged} of {len(result.modes)} modes flagged" if flagged else "")


def plot_fit(frf: FRF, result: IdentificationResult | Sequence[IdentificationResult], channel: int | None = None,
             figure: Figure | None = None) -> Figure:
    """Magnitude and phase with the fitted model(s) over the data, and each mode's Nyquist plot (mobility, the
    model drawn densely around the resonance, its value at the natural frequency marked).

    Parameters
    ----------
    frf : FRF
    result : IdentificationResult or sequence of them
        From :func:`modal.identify` on ``frf``; several (e.g. one per method) are
        drawn over each other, each method with its own line style.
    channel : int, optional
        Channel to draw (0-based; the figure numbers channels from 1, as the command line does). Default: every channel up to
        :data:`MAX_DRAWN_CHANNELS` (each with its model), and for more channels the
        RMS magnitude over channels of the data and of each model; the Nyquist
        plot of each mode shows the channel where that mode is strongest.
    figure : Figure, optional
        Figure to draw into (a new one by default).
    """
    results = _as_results(result)
    names = [_model_name(r) for r in results]
    if channel is not None and not 0 <= channel < frf.n_channels:
        raise ModalError(f"channel {channel} does not exist; the FRF has channels 0..{frf.n_channels - 1}")
    first = results[0]
    f = frf.frequency_hz
    omega = frf.omega_rad_s
    data = np.atleast_2d(frf.channels)
    models = [model_response(frf, r) for r in results]
    channels = [channel] if channel is not None else list(range(frf.n_channels))
    rms = len(channels) > MAX_DRAWN_CHANNELS

    n_modes = len(first)
    ncols = max(min(n_modes, _NYQUIST_COLUMNS), 2)
    nrows_nyq = max(-(-n_modes // _NYQUIST_COLUMNS), 1)
    if figure is None:
        # margins fixed in inches (a layout engine would measure every label twice before drawing)
        width, height = 11.0, 5.2 + 2.4 * nrows_nyq
        fig = Figure(figsize=(width, height))
        frame = margins(width, height, left=0.8, right=0.3, bottom=0.5, top=0.15)
        inner_w, inner_h = width - 1.1, height - 0.65
        # between the phase and the Nyquist rows: the phase's x label and a Nyquist title of two lines
        outer = fig.add_gridspec(2, 1, height_ratios=[2.4, 1.1 * nrows_nyq], hspace=gap_fraction(1.05, inner_h, 2),
                                 left=frame["left"], right=frame["right"], bottom=frame["bottom"], top=frame["top"])
        top_h = (inner_h - 1.05) * 2.4 / (2.4 + 1.1 * nrows_nyq)
        top = outer[0].subgridspec(2, 1, height_ratios=[1.4, 1.0], hspace=gap_fraction(0.3, top_h, 2))
        nyq = outer[1].subgridspec(nrows_nyq, ncols, wspace=gap_fraction(0.5, inner_w, ncols),
                                   hspace=gap_fraction(1.0, inner_h - 1.05 - top_h, nrows_nyq))
    else:
        fig = figure
        grid = fig.add_gridspec(2 + nrows_nyq, ncols, height_ratios=[1.4, 1.0] + [1.1] * nrows_nyq)
        top, nyq = grid[:2, :].subgridspec(2, 1, height_ratios=[1.4, 1.0]), grid[2:, :].subgridspec(nrows_nyq, ncols)
    ax_mag = fig.add_subplot(top[0, 0])
    ax_phase = fig.add_subplot(top[1, 0], sharex=ax_mag)
    colours = [f"C{i % 10}" for i in range(len(channels))]
    if rms:
        data_rms = np.sqrt(np.mean(np.abs(data) ** 2, axis=0))
        ax_mag.semilogy(f, data_rms, ".", ms=2, color="0.3", label=f"data, RMS of {len(channels)} channels")
        for k, (name, model) in enumerate(zip(names, models)):
            ax_mag.semilogy(f, np.sqrt(np.mean(np.abs(model) ** 2, axis=0)), _STYLES[k % 4], lw=1.2,
                            color="C3", label=f"model ({name}), RMS")
        strongest = int(np.argmax(np.sum(np.abs(data) ** 2, axis=1)))
        phase_channels = [strongest]
        ax_phase.set_title(f"phase of channel {strongest + 1} (the strongest)", fontsize="small")
    else:
        for colour, ch in zip(colours, channels):
            tag = f"ch {ch + 1} " if frf.n_channels > 1 else ""
            ax_mag.semilogy(f, np.abs(data[ch]), ".", ms=2, color=colour, label=f"{tag}data")
            for k, (name, model) in enumerate(zip(names, models)):
                ax_mag.semilogy(f, np.abs(model[ch]), _STYLES[k % 4], lw=1, color=colour,
                                label=f"{tag}model ({name})")
        phase_channels = channels
    for colour, ch in zip(colours if not rms else ["0.3"], phase_channels):
        ax_phase.plot(f, np.degrees(np.angle(data[ch])), ".", ms=2, color=colour)
        for k, model in enumerate(models):
            ax_phase.plot(f, np.degrees(np.angle(model[ch])), _STYLES[k % 4], lw=1, color=colour)
    plain_log_ticks(ax_mag.yaxis)
    minor_tick_marks(ax_mag.yaxis)  # some 50 unlabelled minor ticks as one artist: the same figure, drawn faster
    ax_mag.set_ylabel(f"|H| [{frf.units}]")
    ax_mag.legend(loc="best", fontsize="x-small", ncol=1 + (len(channels) * (1 + len(results)) > 6))
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_yticks([-180, -90, 0, 90, 180])
    ax_phase.set_xlabel("frequency [Hz]")
    for mode in first:
        for ax in (ax_mag, ax_phase):
            ax.axvline(mode.natural_frequency_hz, color="0.7", lw=0.6, zorder=0)

    power = KIND_POWER[frf.kind]
    unit = _mobility_unit(frf)
    for r, mode in enumerate(first):
        ax = fig.add_subplot(nyq[r // _NYQUIST_COLUMNS, r % _NYQUIST_COLUMNS])
        if channel is not None:
            ch = channel
        else:
            ch = int(np.nanargmax(np.abs(np.atleast_1d(np.nan_to_num(np.asarray(mode.modal_constant, complex))))))
        low, high = mode.band_hz
        keep = (f >= low) & (f <= high)
        if np.count_nonzero(keep) < 2:
            keep = np.abs(f - mode.natural_frequency_hz) <= max(3 * mode.damping_ratio * mode.natural_frequency_hz,
                                                                  2 * (f[1] - f[0]))
        w = omega[keep]
        to_mobility = (1j * w) ** (1 - power) if np.all(w > 0) else np.ones_like(w)
        y = data[ch, keep] * to_mobility
        traces = [("data", ".", "0.3", y, None)]
        for k, (res, name, model) in enumerate(zip(results, names, models)):
            match = min(res.modes, key=lambda m: abs(m.natural_frequency_hz - mode.natural_frequency_hz), default=None)
            if match is None:
                continue
            # the model on lines dense around the resonance (a smooth circle however few measured lines fall
            # there), and its value at the natural frequency marked
            dense = np.union1d(nyquist_omega(match.omega_n_rad_s, match.damping_ratio, w[0], w[-1]),
                               [match.omega_n_rad_s] if w[0] <= match.omega_n_rad_s <= w[-1] else [])
            ym = modes_response(dense, frf.kind, res)[ch] * ((1j * dense) ** (1 - power) if np.all(dense > 0) else 1)
            offset = np.mean(y - model[ch, keep] * to_mobility)  # what the model leaves out (other modes' tails)
            at_fn = np.flatnonzero(dense == match.omega_n_rad_s)
            traces.append((f"model ({res.method})", _STYLES[k % 4], "C3" if k == 0 else f"C{k + 3}", ym + offset,
                           at_fn[0] if at_fn.size else None))
        # the panel's scale goes into its axis labels (an offset text above the panel would run into the title)
        biggest = max(float(np.max(np.abs(np.concatenate([t[3].real, t[3].imag])))) for t in traces)
        exponent = int(np.floor(np.log10(biggest))) if np.isfinite(biggest) and biggest > 0 else 0
        exponent = 0 if 0 <= exponent <= 2 else exponent  # short tick labels: at most three digits before the point
        scale = 10.0 ** exponent
        for label, style, colour, values, mark in traces:
            z = values / scale
            if style == ".":
                ax.plot(z.real, z.imag, ".", ms=3, color=colour, label=label)
            else:
                ax.plot(z.real, z.imag, style, lw=1, color=colour, label=label)
                if mark is not None:
                    ax.plot(z.real[mark], z.imag[mark], "x", ms=5, mew=1.2, color=colour,
                            label="model at f_n" if r == 0 and label == traces[1][0] else None)
        ax.set_aspect("equal", adjustable="datalim")
        detail = ", ".join(([f"ch {ch + 1}"] if frf.n_channels > 1 else []) + (["flagged"] if _serious(mode) else []))
        ax.set_title(f"mode {r + 1}: {mode.natural_frequency_hz:.4g} Hz" + (f"\n{detail}" if detail else ""),
                     fontsize="small")
        ax.xaxis.set_major_locator(MaxNLocator(3))
        ax.yaxis.set_major_locator(MaxNLocator(4))
        ax.ticklabel_format(useOffset=False, style="plain")
        ax.tick_params(labelsize="x-small")
        factor = "" if exponent == 0 else f"10{str(exponent).translate(_SUPERSCRIPT)} "
        ax.set_xlabel(f"Re Y [{factor}{unit}]", fontsize="small")
        if r % _NYQUIST_COLUMNS == 0:
            ax.set_ylabel(f"Im Y [{factor}{unit}]", fontsize="small")
        if r == 0:
            ax.legend(loc="best", fontsize="xx-small", handlelength=1.5, framealpha=0.6)
    return fig


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _mobility_unit(frf: FRF) -> str:
    """The unit of the Nyquist panels' mobility Y = H (iω)^(1 - p): m/s/N from SI units, else the FRF's own unit
    times or over s."""
    if frf.units == DEFAULT_UNITS[frf.kind]:
        return DEFAULT_UNITS["mobility"]
    power = KIND_POWER[frf.kind]
    return frf.units if power == 1 else (f"{frf.units}·s" if power == 2 else f"({frf.units})/s")
