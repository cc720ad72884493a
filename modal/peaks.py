"""Noise level, mode indicator, automatic peak detection and fitting bands."""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .errors import IdentificationError
from .frf import FRF

__all__ = ["estimate_noise_std", "neighbour_noise_std", "local_noise_std", "mode_indicator", "find_modes", "ModeBand",
           "bands_from_hz", "channel_sample"]


#: neighbour weights within this of ½ count as an evenly spaced axis (``np.linspace`` lines differ from even by
#: rounding, 1e-13 relative): the straight line's misfit then changes by 1e-9 of the neighbours' difference
UNIFORM_WEIGHT_TOL = 1e-9


def _stencil(frequency: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Weights of each inner line's neighbours (left and right, each repeated for Re and Im) and the
    misfit's normalisation 1/(1 + w_l² + w_r²); None on an evenly spaced axis (weights ½, see
    :data:`UNIFORM_WEIGHT_TOL`)."""
    step = np.diff(np.asarray(frequency, float))
    w_left = step[1:] / (step[:-1] + step[1:])
    w_right = 1.0 - w_left
    if w_left.size and np.all(np.abs(w_left - 0.5) <= UNIFORM_WEIGHT_TOL):
        return None
    return np.repeat(w_left, 2), np.repeat(w_right, 2), 1.0 / (1.0 + w_left**2 + w_right**2)


_NOT_GIVEN = object()
#: the misfit's normalisation 1/(1 + w_l² + w_r²) on an evenly spaced axis (weights ½)
EVEN_NORM = 2.0 / 3.0


def _misfit_power(frequency: np.ndarray, values: np.ndarray, stencil=_NOT_GIVEN, scaled: bool = True) -> np.ndarray:
    """Each inner line's squared misfit to the straight line through its neighbours, over
    (1 + w_l² + w_r²), so that white noise of variance σ² gives E = σ²; ``values`` (n_rows, n_freq),
    the result (n_rows, n_freq − 2). ``stencil``: :func:`_stencil` of ``frequency``, when the caller
    has it (rows taken in blocks). ``scaled=False`` on an evenly spaced axis leaves out the factor
    2/3 (:data:`EVEN_NORM`) for the caller to apply to the order statistic it takes: a positive
    factor keeps the order, so that is the same number."""
    if stencil is _NOT_GIVEN:
        stencil = _stencil(frequency)
    values = np.asarray(values, dtype=complex)
    if values.strides[-1] != values.itemsize:  # the real view needs Re, Im side by side along the last axis
        values = np.ascontiguousarray(values)
    # on the real view (real and imaginary parts side by side, a line two numbers wide), in place:
    # 1000 channels × 2000 lines are 32 MB per temporary, and complex-by-real products cost twice as much
    parts = values.view(float)
    before, centre, after = parts[:, :-4], parts[:, 2:-2], parts[:, 4:]
    if stencil is None:
        # evenly spaced lines (to rounding): weights ½, factor 2/3, by scalars in place
        misfit = np.add(before, after)
        misfit *= -0.5
        misfit += centre
        norm = EVEN_NORM if scaled else None
    else:
        w_left, w_right, norm = stencil
        misfit = np.multiply(before, w_left)
        misfit += after * w_right
        np.subtract(centre, misfit, out=misfit)
    misfit *= misfit
    power = np.add(misfit[:, 0::2], misfit[:, 1::2])
    if norm is not None:
        power *= norm
    return power


#: rows of :func:`neighbour_noise_std` computed together (their misfit, 2 MB at 2000 lines, stays in the cache)
_ROWS_AT_ONCE = 128
#: rows of :func:`_indicator_and_peak` taken together: their data are read from memory once for |H| and, when
#: asked for, the misfit (64 channels of 2000 lines: 2 MB, in the cache for the second pass)
_INDICATOR_ROWS = 64


def _noise_medians(frequency: np.ndarray, values: np.ndarray, stencil) -> np.ndarray:
    """Each row's median misfit power (:func:`neighbour_noise_std` before its factors), without the even
    axis' 2/3 (applied by the caller to all rows at once)."""
    power = _misfit_power(frequency, values, stencil, scaled=False)
    mid = power.shape[1] // 2
    power.partition(mid, axis=1)  # in place: the misfit is ours
    return power[:, mid]


def _noise_from_medians(median: np.ndarray, stencil) -> np.ndarray:
    if stencil is None:  # the even axis' factor, on the medians (the same numbers: see _misfit_power)
        median *= EVEN_NORM
    return np.sqrt(median / np.log(2))


def neighbour_noise_std(frequency: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Noise standard deviation per row (E|n|² = σ²), from each line's misfit to its neighbours.

    Each inner line is compared with the straight line through its two
    neighbours, e = H_i − (w_l H_{i−1} + w_r H_{i+1}) with weights from the
    line spacing, so a linear trend cancels on any axis (a plain second
    difference on a jittered axis keeps the slope times the spacing change and
    takes it for noise). For white noise E|e|² = (1 + w_l² + w_r²)σ² and,
    being circular Gaussian, |e|² has median ln 2 times that. The median over
    the axis ignores the few lines where the signal itself curves. On a
    uniform axis this is the classical second-difference estimate.

    Parameters
    ----------
    frequency : ndarray, shape (n_freq,)
        Increasing axis (any unit).
    values : ndarray, shape (n_rows, n_freq)
        Complex data per row; at least 5 lines, else NaN.
    """
    values = np.atleast_2d(np.asarray(values, dtype=complex))
    if values.shape[1] < 5:
        return np.abs(values).max(axis=1) * np.nan
    median = np.empty(values.shape[0])
    stencil = _stencil(frequency)
    for start in range(0, values.shape[0], _ROWS_AT_ONCE):  # a block of rows stays in the cache
        median[start:start + _ROWS_AT_ONCE] = _noise_medians(frequency, values[start:start + _ROWS_AT_ONCE], stencil)
    return _noise_from_medians(median, stencil)


def neighbour_noise_rms(frequency: np.ndarray, values: np.ndarray) -> np.ndarray:
    """:func:`neighbour_noise_std` from the mean of the misfit powers instead of their median: the RMS noise
    over the lines when its level varies along them (a single hammer hit: noise on the force makes the FRF's
    error proportional to |H|, large at the peaks). Use it on a fit's residual, where no curvature of the
    signal is left to take for noise."""
    values = np.atleast_2d(np.asarray(values, dtype=complex))
    if values.shape[1] < 5:
        return np.abs(values).max(axis=1) * np.nan
    stencil = _stencil(frequency)
    power = _misfit_power(frequency, values, stencil, scaled=False).mean(axis=1)
    if stencil is None:
        power *= EVEN_NORM
    return np.sqrt(power)


def estimate_noise_std(frf: FRF) -> np.ndarray:
    """Noise standard deviation per channel (E|n|² = σ²) of the raw data.

    :func:`neighbour_noise_std` over the whole axis. Noise-free data give the
    (small) curvature floor of the resonances instead of zero; on an axis so
    coarse that most lines lie on a resonance this floor is the estimate.
    """
    return neighbour_noise_std(frf.frequency_hz, frf.channels)


def mode_indicator(frf: FRF) -> np.ndarray:
    """RMS over channels of |H| normalised by each channel's maximum (1-D, n_freq)."""
    return _indicator_and_peak(frf)[0]


def _indicator_and_peak(frf: FRF, noise: bool = False) -> tuple[np.ndarray, ...]:
    """:func:`mode_indicator` and each channel's max |H| (n_channels,), and with ``noise`` each channel's
    :func:`estimate_noise_std` as well, from one read of the data: blocks of rows, each block's |H| squared
    in place and its normalised squares summed over the channels by a matrix-vector product, its misfit
    medians taken while the block is in the cache."""
    channels = frf.channels
    n_ch, n_freq = channels.shape
    peak = np.empty(n_ch)
    total = np.zeros(n_freq)
    median = np.empty(n_ch) if noise and n_freq >= 5 else None
    stencil = _stencil(frf.frequency_hz) if median is not None else None
    for start in range(0, n_ch, _INDICATOR_ROWS):
        block = channels[start:start + _INDICATOR_ROWS]
        if median is not None:
            # data near over- or underflow (identify rescales them and measures again) square out of range
            with np.errstate(over="ignore", under="ignore"):
                median[start:start + _INDICATOR_ROWS] = _noise_medians(frf.frequency_hz, block, stencil)
        mag = np.abs(block)
        peak[start:start + _INDICATOR_ROWS] = block_peak = mag.max(axis=1)
        scale = np.where(block_peak > 0, block_peak, 1.0)
        if not 1e-150 < scale.min() <= scale.max() < 1e150:  # |H|² would leave the float range: normalise first
            mag /= scale[:, None]
            scale = np.ones_like(scale)
        mag *= mag
        total += (1.0 / scale**2) @ mag
    indicator = np.sqrt(total / n_ch)
    if not noise:
        return indicator, peak
    if median is None:  # fewer than 5 lines: no misfit (neighbour_noise_std's NaN)
        return indicator, peak, peak * np.nan
    return indicator, peak, _noise_from_medians(median, stencil)


@dataclass(frozen=True)
class ModeBand:
    """A peak and its fitting band."""

    peak_hz: float
    low_hz: float
    high_hz: float
    half_power_width_hz: float
    user_given: bool = False


def _half_power_width(freq, ind, i):
    level = ind[i] / np.sqrt(2)
    lo = i
    while lo > 0 and ind[lo] >= level:
        lo -= 1
    hi = i
    while hi < ind.size - 1 and ind[hi] >= level:
        hi += 1
    return freq[hi] - freq[lo]


def _range_tables(y: np.ndarray, op) -> list[np.ndarray]:
    """Sparse table of ``y``: entry k holds ``op`` over every run y[i:i + 2**k] (O(n log n), exact)."""
    tables = [y]
    while 2 ** len(tables) <= y.size:
        half = 2 ** (len(tables) - 1)
        tables.append(op(tables[-1][:-half], tables[-1][half:]))
    return tables


def _range_query(tables: list[np.ndarray], lo: np.ndarray, hi: np.ndarray, op) -> np.ndarray:
    """``op`` over y[lo:hi] for arrays of bounds (hi > lo): two overlapping runs of a power of two."""
    length = hi - lo
    k = np.floor(np.log2(length)).astype(int)
    k = np.where(2 ** (k + 1) <= length, k + 1, k)  # log2 rounded at a power of two
    k = np.where(2**k > length, k - 1, k)
    out = np.empty(lo.size)
    for level in np.unique(k):
        sel = k == level
        out[sel] = op(tables[level][lo[sel]], tables[level][hi[sel] - 2**level])
    return out


def _peaks_with_prominence(y: np.ndarray, min_prominence: float) -> np.ndarray:
    """Local maxima of ``y`` whose topographic prominence is at least ``min_prominence``.

    Prominence as in ``scipy.signal.peak_prominences``: the peak height minus the
    higher of the two lowest points between the peak and the nearest higher
    sample (or the end of the data) on each side. Vectorised over the peaks with
    sparse tables of running maxima and minima: the run of samples not above a
    peak on each side is found by descending powers of two (its length in binary).
    """
    n = y.size
    if n < 3:
        return np.zeros(0, dtype=int)
    inner = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:])) + 1
    if inner.size == 0:
        return inner
    top = _range_tables(y, np.maximum)
    low = _range_tables(y, np.minimum)
    level = y[inner]
    start = inner.copy()  # y[start:p] all <= y[p]
    stop = inner + 1  # y[p + 1:stop] all <= y[p]
    for k in range(len(top) - 1, -1, -1):
        width, t = 2**k, top[k]
        can = start - width >= 0
        move = can & (t[np.where(can, start - width, 0)] <= level)
        start = np.where(move, start - width, start)
        can = stop + width <= n
        move = can & (t[np.where(can, stop, 0)] <= level)
        stop = np.where(move, stop + width, stop)
    # the lowest point between the peak and the nearest higher sample (start − 1, or none) on the left,
    # and up to it (stop, or the end) on the right
    left_base = _range_query(low, start, inner + 1, np.minimum)
    right_base = _range_query(low, inner, stop, np.minimum)
    return inner[level - np.maximum(left_base, right_base) >= min_prominence]


#: statistics per channel that only enter a mean or a median over the channels (a peak's signal-to-noise
#: ratio, the fit's chi-square) are measured on at most this many channels, a fixed random sample
SAMPLE_CHANNELS = 128


def channel_sample(n_channels: int, size: int | None = None) -> slice | np.ndarray:
    """The channels a mean or median over all channels is estimated from: all of them (``slice(None)``)
    up to ``size`` (default :data:`SAMPLE_CHANNELS`), else ``size`` of them drawn at random without
    replacement (a fixed seed, so a result does not change from run to run), in increasing order.

    A mean or median over a random sample estimates the one over all channels without bias (each channel
    is as likely to be drawn), with a sampling error 1/sqrt(``size``) of the spread over the channels (times
    sqrt(1 − size/n)). An evenly strided sample would not serve: channels are often ordered by point and
    direction, and a stride that is a multiple of the number of directions sees one direction only.
    """
    size = SAMPLE_CHANNELS if size is None else size
    if n_channels <= size:
        return slice(None)
    return _random_sample(n_channels, size)


@functools.lru_cache(maxsize=16)
def _random_sample(n_channels: int, size: int) -> np.ndarray:
    """:func:`channel_sample`'s draw (read-only: one array serves every call with these sizes)."""
    rows = np.sort(np.random.default_rng(0x5EED).choice(n_channels, size, replace=False))
    rows.flags.writeable = False
    return rows


#: half-width (lines) of the window in which the local noise level around a peak is measured
LOCAL_NOISE_LINES = 64
#: with a noise per line (an estimate from time data), a peak must stand this many of its own σ above zero
PEAK_SIGMAS = 3.0
#: line steps of the neighbour stencils whose largest noise level counts (correlated noise)
STENCIL_STEPS = (1, 2, 4)


def _row_median(values: np.ndarray) -> np.ndarray:
    """``np.median(values, axis=1)`` of a finite 2-D array by one sort of the rows (the same values;
    numpy's median partitions a copy around two indices, ten times slower on a few hundred columns)."""
    if not np.all(np.isfinite(values)):
        return np.median(values, axis=1)
    ordered = np.sort(values, axis=1)
    n = ordered.shape[1]
    if n % 2:
        return ordered[:, n // 2]
    return (ordered[:, n // 2 - 1] + ordered[:, n // 2]) / 2


def local_noise_std(frequency: np.ndarray, values: np.ndarray, lines, exclude,
                    half_width: int = LOCAL_NOISE_LINES, rows=slice(None)) -> np.ndarray:
    """Noise standard deviation beside each of ``lines``, per row: shape (n_rows, n_lines).

    The neighbour misfit (:func:`neighbour_noise_std`) on ``half_width`` lines
    either side of the resonance region ``line ± exclude`` (whose curvature is
    signal, not noise). Noise is often far from white over a wide band (an
    impact hammer's force falls off above its band, so an H1 estimate's noise
    rises there by orders of magnitude); the whole axis' median then calls
    noise peaks modes. Noise correlated over a few lines (an exponential window
    smooths the spectrum over 1/(πτ) Hz) hides from neighbours one line apart,
    so stencils of lines 2 and 4 apart are used too and the largest level counts.
    NaN where fewer than 5 lines lie beside the region. ``rows``: the rows of ``values`` to measure
    (an index array or a slice; only the windows are taken out of them, not every line).
    """
    values = np.atleast_2d(np.asarray(values, dtype=complex))
    n = values.shape[1]
    n_rows = len(range(values.shape[0])[rows]) if isinstance(rows, slice) else len(rows)
    out = np.full((n_rows, np.size(lines)), np.nan)
    for k, (line, gap) in enumerate(zip(np.atleast_1d(lines), np.atleast_1d(exclude))):
        sides = [(max(0, int(line) - int(gap) - half_width), max(0, int(line) - int(gap))),
                 (min(n, int(line) + int(gap) + 1), min(n, int(line) + int(gap) + 1 + half_width))]
        levels = []
        for step in STENCIL_STEPS:
            powers = [_misfit_power(frequency[lo:hi:step], values[rows, lo:hi:step])
                      for lo, hi in sides if (hi - lo) // step >= 5]
            if powers:
                levels.append(_row_median(np.concatenate(powers, axis=1)) / np.log(2))
        if levels:
            out[:, k] = np.sqrt(np.max(levels, axis=0))
    return out


def find_modes(frf: FRF, min_prominence_db: float = 6.0, noise_factor: float = 10.0,
               bandwidths: float = 3.0, max_modes: int | None = None,
               noise_std: np.ndarray | None = None, line_noise_std: np.ndarray | None = None,
               indicator: tuple[np.ndarray, np.ndarray] | None = None) -> list[ModeBand]:
    """Find resonance peaks and give each a fitting band.

    A peak of the mode indicator counts when it stands ``min_prominence_db``
    above its surroundings and ``noise_factor`` times above the noise level,
    both the whole axis' and the local one around the peak (RMS over the
    channels of |H|/σ_local, :func:`local_noise_std`, or ``line_noise_std``
    when the FRF carries its own noise per line, e.g. an estimate from time
    data); the RMS over more than :data:`SAMPLE_CHANNELS` channels is taken on a sample of them
    (:func:`channel_sample`). Its band is ±``bandwidths`` half-power widths (at least ±5 lines),
    clipped halfway to the neighbouring peaks and to the data, with its edges
    moved halfway between lines (see :func:`_edges_between_lines`). ``indicator``: the mode
    indicator and each channel's max |H| (:func:`_indicator_and_peak`), when the caller has them.
    """
    freq = frf.frequency_hz
    ind, peak_mag = _indicator_and_peak(frf) if indicator is None else indicator
    noise = estimate_noise_std(frf) if noise_std is None else noise_std
    with np.errstate(invalid="ignore", divide="ignore"):
        noise_rel = float(np.sqrt(np.nanmean((noise / peak_mag) ** 2)))
    floor = noise_factor * noise_rel if np.isfinite(noise_rel) else 0.0
    db = 20 * np.log10(np.maximum(ind, np.finfo(float).tiny))
    idx = _peaks_with_prominence(db, min_prominence_db)
    keep = ind[idx] > floor
    idx = idx[keep]
    if idx.size:
        # the tests below take a mean over the channels: many channels are sampled (channel_sample)
        rows = channel_sample(frf.n_channels)
        mag = np.abs(frf.channels[:, idx][rows])  # the peaks' lines of the sampled rows (no copy of every line)
        if line_noise_std is None:
            spacing = np.min(np.diff(freq))
            region = [max(5, int(np.ceil(bandwidths * _half_power_width(freq, ind, i) / spacing))) for i in idx]
            local = local_noise_std(freq, frf.channels, idx, region, rows=rows)
        else:
            # a per-line noise estimated from few averages scatters: its median over the same
            # window is the level (the noise of an estimate varies smoothly with frequency) ...
            line_noise = np.atleast_2d(np.asarray(line_noise_std, float))
            line_noise = line_noise[rows] if line_noise.shape[0] == frf.n_channels else line_noise
            local = np.empty(mag.shape)
            near = np.empty(mag.shape)
            for k, line in enumerate(idx):
                lo, hi = max(0, line - LOCAL_NOISE_LINES), line + LOCAL_NOISE_LINES + 1
                local[:, k] = np.median(line_noise[:, lo:hi], axis=1)
                near[:, k] = np.median(line_noise[:, max(0, line - 2):line + 3], axis=1)
            # ... and the peak must stand PEAK_SIGMAS of its own noise above zero: a zero of the force
            # spectrum (a hammer pulse of length T has them at k/T) makes H1 peak where its noise peaks
            # (1 ms pulse: |H|/σ 0.9-3.3 at 1.5-4.5 kHz, the window's median 200x lower), while a mode
            # beyond the hammer's band with force noise stands 4.3σ (tests/modal/estimate/test_estimate_identify.py)
            with np.errstate(invalid="ignore", divide="ignore"):
                own = np.sqrt(np.nanmean((mag / near) ** 2, axis=0))
            standing = ~(own <= PEAK_SIGMAS)
            idx, mag, local = idx[standing], mag[:, standing], local[:, standing]
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio2 = (mag / local) ** 2
        measured = np.isfinite(ratio2)
        # channels where the noise beside the peak could be measured; none (too few lines beside the
        # resonance): the peak is kept, the whole axis' test above decides
        snr = np.sqrt(np.where(measured, ratio2, 0.0).sum(axis=0) / np.maximum(measured.sum(axis=0), 1))
        idx = idx[~measured.any(axis=0) | (snr > noise_factor)]
    if max_modes is not None and idx.size > max_modes:
        strongest = np.argsort(ind[idx])[::-1][:max_modes]
        idx = np.sort(idx[strongest])
    if idx.size == 0:
        window = ""
        if frf.exponential_decay_s:  # the window adds ζ = 1/(ωτ): 10 % or more below 1/(0.2 π τ) Hz
            below_hz = 1.0 / (0.2 * np.pi * frf.exponential_decay_s)
            window = (f"; the exponential window (tau = {frf.exponential_decay_s:g} s) adds a damping ratio of "
                      f"1/(2 pi f tau), 10 % or more below {below_hz:.4g} Hz, which flattens the peaks there: a longer "
                      "tau")
        raise IdentificationError(
            f"{frf.source}: no resonance peak found ({min_prominence_db} dB prominence, "
            f"{noise_factor}x above noise); give the bands explicitly{window}"
        )
    out = []
    df_min = np.min(np.diff(freq))
    for j, i in enumerate(idx):
        width = max(_half_power_width(freq, ind, i), df_min)
        half = max(bandwidths * width, 5 * df_min)
        low, high = freq[i] - half, freq[i] + half
        if j > 0:
            low = max(low, 0.5 * (freq[idx[j - 1]] + freq[i]))
        if j < idx.size - 1:
            high = min(high, 0.5 * (freq[idx[j + 1]] + freq[i]))
        low, high = _edges_between_lines(freq, low, high)
        out.append(ModeBand(float(freq[i]), low, high, float(width)))
    return out


def _edges_between_lines(freq: np.ndarray, low: float, high: float) -> tuple[float, float]:
    """Move band edges halfway to the next line out, so no line sits on an edge.

    Edges often fall on a line (±3 half-power widths is often a whole number of
    spacings); whether ``freq >= low`` keeps that line would then depend on
    rounding, e.g. of an axis rescaled from Hz to kHz. A line within 1e-3 of a
    spacing of an edge counts as inside.
    """
    tol = 1e-3 * float(np.min(np.diff(freq)))
    first = int(np.searchsorted(freq, low - tol, side="left"))
    last = int(np.searchsorted(freq, high + tol, side="right")) - 1
    low = freq[0] if first == 0 else 0.5 * (freq[first - 1] + freq[first])
    high = freq[-1] if last == freq.size - 1 else 0.5 * (freq[last] + freq[last + 1])
    return float(low), float(high)


def bands_from_hz(frf: FRF, bands_hz, indicator: np.ndarray | None = None) -> list[ModeBand]:
    """Turn user bands ``[(f_low, f_high), ...]`` (Hz) into :class:`ModeBand` objects (``indicator``: the
    :func:`mode_indicator`, when the caller has it)."""
    out = []
    try:
        pairs = [(float(a), float(b)) for a, b in bands_hz]
    except (TypeError, ValueError):
        raise IdentificationError(
            f"bands_hz must be a list of (f_low, f_high) pairs in Hz, got {bands_hz!r}"
        ) from None
    ind = mode_indicator(frf) if indicator is None else indicator
    freq = frf.frequency_hz
    for low, high in pairs:
        if not (np.isfinite(low) and np.isfinite(high) and low < high):
            raise IdentificationError(f"band ({low}, {high}) Hz: expected finite f_low < f_high")
        tol = 1e-3 * float(np.min(np.diff(freq)))  # as _edges_between_lines
        inside = np.flatnonzero((freq >= low - tol) & (freq <= high + tol))
        if inside.size < 3:
            raise IdentificationError(
                f"{frf.source}: band ({low}, {high}) Hz holds {inside.size} lines; expected at least 3 "
                f"(data cover {freq[0]:g}–{freq[-1]:g} Hz)"
            )
        i = inside[np.argmax(ind[inside])]
        width = max(_half_power_width(freq, ind, i), np.min(np.diff(freq)))
        out.append(ModeBand(float(freq[i]), *_edges_between_lines(freq, low, high), float(width), user_given=True))
    return sorted(out, key=lambda b: b.peak_hz)
