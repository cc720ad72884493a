"""The bands of a band-wise fit: their lines, the channels that count, and linear solves on them.

Each mode has a band (:class:`modal.peaks.ModeBand`, Hz); overlapping bands merge
into one region with its own complex offset. The helpers here take the bands'
lines out of an FRF, rank channels by their signal-to-noise at a mode's peak,
and solve the modal constants of every channel for known poles.
"""
from __future__ import annotations

import numpy as np

from ..model import mode_basis, solve_linear
from ..whitening import LineWhitening
from ..peaks import ModeBand
from ..units import TWO_PI

__all__ = ["POLE_CHANNELS", "band_mask", "band_run", "band_lines", "regions", "band_data", "band_influence",
           "band_relative_error", "band_peaks",
           "channel_weights", "strongest_channels", "band_noise", "line_weight", "line_whitening",
           "weight_on_lines", "whitening_on_lines",
           "constants_at_poles"]

#: half-power and circle fits: the pole comes from at most this many strongest channels;
#: the other channels' modal constants are solved linearly with that pole
POLE_CHANNELS = 32


def band_mask(frf, band: ModeBand) -> np.ndarray:
    """The lines of a band (bool over the FRF's lines)."""
    return (frf.frequency_hz >= band.low_hz) & (frf.frequency_hz <= band.high_hz)


def band_run(omega: np.ndarray, band: ModeBand) -> slice:
    """A band's lines on the lines ``omega`` (rad/s) of the bands' :func:`band_data`, where they are a run
    (every line between its edges is in it; the edges lie halfway between lines,
    :func:`modal.peaks._edges_between_lines`, so no rounding of 2π f moves a line across one)."""
    lines = np.flatnonzero((omega >= TWO_PI * band.low_hz) & (omega <= TWO_PI * band.high_hz))
    return slice(lines[0], lines[-1] + 1) if lines.size else slice(0, 0)


def band_lines(frf, band: ModeBand):
    keep = band_mask(frf, band)
    return frf.omega_rad_s[keep], frf.channels[:, keep]


def regions(bands: list[ModeBand], freq):
    """Lines in any band, and a region index per line (overlapping bands merge)."""
    keep = np.zeros(freq.size, bool)
    for b in bands:
        keep |= (freq >= b.low_hz) & (freq <= b.high_hz)
    idx = np.flatnonzero(keep)
    region = np.zeros(idx.size, int)
    breaks = np.flatnonzero(np.diff(idx) > 1)
    for br in breaks:
        region[br + 1:] += 1
    return keep, region


def band_data(frf, bands, channels=None):
    """Lines of the bands (rad/s), the FRF there (all or some channels) and each line's region."""
    keep, region = regions(bands, frf.frequency_hz)
    rows = slice(None) if channels is None else channels
    lines = np.flatnonzero(keep)
    starts = np.concatenate([[0], np.flatnonzero(np.diff(lines) > 1) + 1, [lines.size]])
    response = frf.channels[rows]
    # each band's run of lines copied as a block (half the time of a masked copy of every channel)
    runs = [response[:, lines[a]:lines[b - 1] + 1] for a, b in zip(starts[:-1], starts[1:]) if b > a]
    return frf.omega_rad_s[keep], (np.concatenate(runs, axis=1) if runs else response[:, keep]), region


def band_peaks(bands, data) -> np.ndarray:
    """max |H| of each channel on each band's lines, (n_bands, n_channels), from the bands' :func:`band_data`
    (|H| of every channel once: the fit scales each channel by its largest, the misfit check ranks by them)."""
    omega, response, _ = data
    magnitude = np.abs(response)
    out = np.zeros((len(bands), response.shape[0]))
    for b, band in enumerate(bands):
        run = band_run(omega, band)
        if run.stop > run.start:
            out[b] = magnitude[:, run].max(axis=1)
    return out


def channel_weights(frf, band, noise):
    """Signal-to-noise power of each channel at the mode's peak line."""
    i = int(np.argmin(np.abs(frf.frequency_hz - band.peak_hz)))
    peak = np.abs(frf.channels[:, i])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(noise > 0, (peak / noise) ** 2, peak**2)


def strongest_channels(frf, band, noise, count: int) -> np.ndarray:
    """The ``count`` channels of highest :func:`channel_weights` in a band, strongest first."""
    return np.argsort(channel_weights(frf, band, noise))[::-1][:count]


def band_noise(frf, bands, line_noise):
    """Per channel, the RMS over the bands' lines of a known noise per line."""
    line_noise = np.atleast_2d(np.asarray(line_noise, float))
    lines, _ = regions(bands, frf.frequency_hz)
    return np.sqrt(np.mean(line_noise[:, lines] ** 2, axis=1))


#: the weights' noise level rests on at least this many degrees of freedom (relative error √(2/dof) = 0.2)
NOISE_DOF_TARGET = 50
#: ... averaged over at most this many lines
MAX_SMOOTHING_LINES = 41


def smoothing_lines(model) -> int:
    """Odd number of neighbouring lines over which a noise variance of ``model.degrees_of_freedom`` is averaged
    to reach :data:`NOISE_DOF_TARGET` (the lines' correlation counted), at most :data:`MAX_SMOOTHING_LINES`."""
    lines = 1
    while lines < MAX_SMOOTHING_LINES and (model.degrees_of_freedom * lines / model.smoothing_inflation(lines)
                                           < NOISE_DOF_TARGET):
        lines += 2
    return lines


def _smoothed(values: np.ndarray, lines: int) -> np.ndarray:
    """Moving average over ``lines`` (odd) neighbouring lines, over fewer at the ends."""
    if lines <= 1 or values.size < 2:
        return values
    half = lines // 2
    total = np.concatenate([[0.0], np.cumsum(values)])
    index = np.arange(values.size)
    lo, hi = np.clip(index - half, 0, values.size), np.clip(index + half + 1, 0, values.size)
    return (total[hi] - total[lo]) / (hi - lo)


def line_weight(frf, bands):
    """Weights σ_ref/σ_line of the bands' lines for an FRF that carries its noise per line, else None.

    σ_line is the RMS over channels of the FRF's ``noise_std`` and σ_ref its RMS over the lines, so the
    weighted noise variance is σ_ref² on every line: the noise level :func:`band_noise` gives the fit.
    An estimate's noise spikes at the zeros of the force spectrum (a 1 ms hammer pulse: 1, 2, 3 kHz);
    unweighted, those few lines pulled the 1450 and 2600 Hz poles of a hammer test to 1500 and 2500 Hz.
    A line claimed quieter than 1e-3 σ_ref counts as 1e-3 σ_ref (no line weighs more than 1000).
    A noise level resting on few averages (its :class:`~modal.noise_model.NoiseModel` says how many degrees
    of freedom) is averaged over neighbouring lines first (:func:`smoothing_lines`): weights from a variance
    of 2 degrees of freedom scatter by a factor of ten between lines, and the fit then trusts a few lines
    that came out quiet by chance.
    """
    return weight_on_lines(frf, regions(bands, frf.frequency_hz)[0])


def weight_on_lines(frf, keep):
    """:func:`line_weight` of the lines ``keep`` (bool over the FRF's lines), for a fit over lines that are no
    bands' (the global method's, every line of its band)."""
    line_noise = frf.noise_std
    if line_noise is None:
        return None
    variance = np.mean(np.atleast_2d(np.asarray(line_noise, float)) ** 2, axis=0)
    model = frf.noise_model
    if model is not None and 0 < model.degrees_of_freedom < NOISE_DOF_TARGET:
        lines = smoothing_lines(model)
        plain = _smoothed(variance, lines)
        shape = model.variance_model
        several = np.ndim(line_noise) > 1 and np.shape(line_noise)[0] > 1
        if shape is not None and several:
            # several channels: the shape every channel's noise shares (the response noise over the excitation's
            # power), at the level of theirs; the excitation noise's part differs per channel and is nearly a
            # gain across a band, which the modal constants take up: weighing lines down for it would drop the
            # lines that carry the poles
            holds = np.isfinite(shape) & (shape > 0) & keep
            if np.any(holds):
                level = np.mean(plain[holds]) / np.mean(shape[holds])
                variance = np.where(np.isfinite(shape) & (shape > 0), shape * level, plain)
            else:
                variance = plain
        elif shape is not None:
            # where the model holds, the variance's own shape (it rises as |H|² at the peaks where the
            # excitation's noise dominates) is kept and only its ratio to it, which scatters from line to
            # line, is averaged (over the neighbours where it holds)
            holds = np.isfinite(shape) & (shape > 0)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = _smoothed(np.where(holds, variance / shape, 0.0), lines) / _smoothed(holds * 1.0, lines)
            variance = np.where(holds, shape * ratio, plain)
        else:
            variance = plain
    sigma = np.sqrt(variance[keep])
    ref = float(np.sqrt(np.mean(sigma**2))) if sigma.size else 0.0
    if not (np.all(np.isfinite(sigma)) and ref > 0):
        return None
    return ref / np.maximum(sigma, 1e-3 * ref)


def line_whitening(frf, bands):
    """:class:`modal.whitening.LineWhitening` of the bands' lines for an FRF whose noise model carries the
    correlation of neighbouring lines (an estimate from time data), else None."""
    return whitening_on_lines(frf, regions(bands, frf.frequency_hz)[0])


def whitening_on_lines(frf, keep):
    """:func:`line_whitening` of the lines ``keep`` (bool over the FRF's lines)."""
    model = frf.noise_model
    if model is None or model.line_correlation is None or model.n_lags == 0 or frf.noise_std is None:
        return None
    lines = np.flatnonzero(keep)
    key = (id(model), lines.size, hash(lines.tobytes()))
    cached = _WHITENINGS.get(key)
    if cached is not None and cached[0] is model:  # the same model and lines: the fits of one identify
        return cached[1]
    whitening = LineWhitening(model.correlation_band(lines))
    if len(_WHITENINGS) >= 8:
        _WHITENINGS.clear()
    _WHITENINGS[key] = (model, whitening)
    return whitening


def band_influence(frf, bands, channels=None):
    """Each record's share of the error on the bands' lines and the records each overlaps, for an FRF whose noise
    model carries them (:mod:`modal.estimate.record_influence`): (n_records, n_lines) for one channel,
    (n_channels, n_records, n_lines) of the ``channels`` fitted for several; else (None, 0)."""
    model = frf.noise_model
    if model is None or model.record_influence is None:
        return None, 0
    influence = model.record_influence
    if influence.ndim == 2 and frf.n_channels == 1:
        keep, _ = regions(bands, frf.frequency_hz)
        return influence[:, keep], model.overlapping_records
    if influence.ndim != 3 or influence.shape[0] != frf.n_channels:  # not this FRF's channels (one taken out)
        return None, 0
    keep, _ = regions(bands, frf.frequency_hz)
    influence = influence[:, :, keep] if channels is None else influence[channels][:, :, keep]
    return (influence[0] if influence.shape[0] == 1 else influence), model.overlapping_records


def band_relative_error(frf, bands, channels=None):
    """The factor of the channels' errors relative to their FRF (the excitation noise's) on the bands' lines,
    (n_factors, n_lines) or, per channel, (n_channels, n_factors, n_lines) of the ``channels`` fitted, for an
    FRF whose noise model carries it (:class:`~modal.noise_model.NoiseModel`'s ``relative_error``, formed on
    these lines: :meth:`~modal.shared_error.CommonError.factor`); else None.
    Several channels share it (their poles' covariance takes it); one channel's modal constants take it as a
    gain error of every line near a mode."""
    model = frf.noise_model
    if model is None or model.relative_error is None:
        return None
    keep, _ = regions(bands, frf.frequency_hz)
    factor = model.relative_error.factor(keep)
    return factor if factor is None or factor.ndim == 2 or channels is None else factor[channels]


#: the last whitenings made (the fits of one identification share them), by noise model and lines
_WHITENINGS: dict = {}


def constants_at_poles(frf, bands, power, omega_n, damping_ratio):
    """Modal constants of every channel for known poles: one linear least-squares solve
    (all modes together, one complex offset per band region) over the lines of the bands."""
    omega, response, region = band_data(frf, bands)
    ok = np.isfinite(omega_n) & np.isfinite(damping_ratio)
    phi = mode_basis(omega, np.asarray(omega_n)[ok], np.asarray(damping_ratio)[ok], power).T
    offsets = np.zeros((omega.size, region.max() + 1), dtype=complex)
    offsets[np.arange(omega.size), region] = 1.0
    coef = solve_linear(np.hstack([phi, offsets]), response.T)
    out = np.full((len(bands), frf.n_channels), np.nan, dtype=complex)
    out[ok] = coef[:ok.sum()]
    return out
