"""Checking and preparing an ambient record: one place for the errors a user sees about the input.

Every problem is one :class:`~modal.errors.ParameterError` naming the record (the file, when it
came from one), the field and what was expected.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..parallel import split_over_threads
from .correlations import decimate, decimation_factor, decimation_filter
from .screen import check_held, check_units, screen_samples

__all__ = ["Prepared", "prepare", "prepare_unscreened", "check_band", "channel_statistics"]

#: a channel whose standard deviation is below this fraction of the largest channel's is constant
CONSTANT_CHANNEL = 1e-12
#: a piece of a channel whose sum of squares about its mean is below this fraction of its sum of squares about
#: zero (a mean above about 30 RMS) is centred before its squares are summed: their difference would keep fewer
#: than 13 of double precision's 16 digits
CANCELLATION = 1e-3
#: the record must hold at least this many times the longest correlation lag
MIN_LAGS_IN_RECORD = 40
#: the input check reads each channel this many samples at a time: each piece is summed and squared while it
#: stays in cache (and copied to double precision or centred first, where needed, in a 512 kB buffer)
CHUNK_SAMPLES = 1 << 16


@dataclass(frozen=True)
class Prepared:
    """A record checked and brought to the band, with each channel's mean and RMS; the samples themselves are
    neither centred nor scaled (a centred, scaled single-precision copy of a 10⁶ × 64 record would take 256 MB):
    the correlations centre them as they read them and scale the correlation matrices
    (:func:`modal.operational.correlations.correlations`), and :meth:`channel` gives one channel centred and
    scaled where a method needs samples.

    Attributes
    ----------
    signals : ndarray, shape (n_channels, n_samples)
        The samples as recorded (single or double precision, not copied), or decimated to the band (double
        precision, centred before the filter).
    sample_rate_hz : float
        After decimation.
    mean : ndarray, shape (n_channels,)
        Each channel's mean in the units of ``signals`` (double precision).
    scale : ndarray, shape (n_channels,)
        Each channel's RMS about its mean in the input's units (shapes are scaled back by it).
    band_hz : (float, float)
    decimation : int
    original_rate_hz : float
    quantity : str or None
    names : tuple of str
    source : str
    """

    signals: np.ndarray
    sample_rate_hz: float
    mean: np.ndarray
    scale: np.ndarray
    band_hz: tuple[float, float]
    decimation: int
    original_rate_hz: float
    quantity: str | None
    names: tuple[str, ...]
    source: str

    @property
    def n_channels(self) -> int:
        return self.signals.shape[0]

    @property
    def n_samples(self) -> int:
        return self.signals.shape[1]

    @property
    def duration_s(self) -> float:
        return self.signals.shape[1] / self.sample_rate_hz

    def channel(self, ch: int) -> np.ndarray:
        """Channel ``ch`` less its mean (in double precision) and divided by its RMS, stored in single precision."""
        centred = np.asarray(self.signals[ch], dtype=np.float64) - self.mean[ch]
        centred /= self.scale[ch]
        return centred.astype(np.float32)


def _record(data, sample_rate_hz):
    """(signals, rate, quantity, names, source) from an array, a TimeRecord or a path."""
    from ..io.timedata import TimeRecord, read_time

    if isinstance(data, (str, os.PathLike)):
        data = read_time(data)
    if isinstance(data, TimeRecord):
        if sample_rate_hz is not None and not np.isclose(float(sample_rate_hz), data.sample_rate_hz):
            raise ParameterError(f"{data.source}: sample_rate_hz={sample_rate_hz!r} contradicts the file's "
                                 f"{data.sample_rate_hz:g} Hz; leave it out")
        quantities = {q for q in data.quantities if q is not None}
        if "force" in quantities:
            forces = ", ".join(str(k + 1) for k in data.force_channels())
            raise ParameterError(f"{data.source}: channel(s) {forces} measured force; expected responses only "
                                 "(with a force channel, estimate FRFs: python -m modal fit)")
        quantity = check_units(data)
        return _real_samples(data.signals), data.sample_rate_hz, quantity, tuple(data.names), data.source
    arr = np.asarray(data)
    if arr.dtype.kind not in "biuf":
        raise ParameterError(f"<array>: 'data' has dtype {arr.dtype}; expected real numbers (n_channels, n_samples)")
    if sample_rate_hz is None:
        raise ParameterError("<array>: 'sample_rate_hz' is missing; expected the sampling rate in Hz for an array")
    names = tuple(str(k) for k in range(arr.shape[0])) if arr.ndim == 2 else ()
    _warn_low_rate(sample_rate_hz)
    return _real_samples(arr), float(sample_rate_hz), None, names, "<array>"


def _warn_low_rate(sample_rate_hz) -> None:
    """Name an array's rate below what vibration tests sample at (:data:`modal.io.timedata.LOW_RATE_HZ`, as for a
    file's rate field): a rate in kHz given as Hz divides every frequency by 1000, and the modes still come out
    stable and within their errors."""
    from ..errors import QualityWarning, warn
    from ..io.timedata import LOW_RATE_HZ

    try:
        rate = float(sample_rate_hz)
    except (TypeError, ValueError):
        return  # refused by prepare, naming the value
    if np.isfinite(rate) and 0 < rate < LOW_RATE_HZ:
        warn(f"<array>: 'sample_rate_hz' is {rate:.6g} Hz, below what vibration tests sample at ({LOW_RATE_HZ:g} Hz); "
             f"every frequency scales with it: if it is in kHz, give {1000 * rate:.6g} (Hz)", QualityWarning)


def _real_samples(signals) -> np.ndarray:
    """The samples as stored when they are single or double precision (a record of 64 channels × 10⁶ samples in
    single precision is 256 MB, and a double copy 512 MB more), else in double precision."""
    arr = np.asarray(signals)
    return arr if arr.dtype in (np.float32, np.float64) else arr.astype(float)


def check_band(band_hz, nyquist_hz: float, src: str) -> tuple[float, float]:
    """The band as two floats with 0 ≤ low < high ≤ Nyquist (default: up to 80 % of Nyquist)."""
    if band_hz is None:
        return 0.0, 0.8 * nyquist_hz
    try:
        low, high = (float(v) for v in band_hz)
    except (TypeError, ValueError):
        raise ParameterError(f"{src}: 'band_hz' is {band_hz!r}; expected two frequencies (FMIN, FMAX) in Hz") from None
    if not (np.isfinite(low) and np.isfinite(high) and 0 <= low < high <= nyquist_hz):
        raise ParameterError(f"{src}: 'band_hz' is ({low:g}, {high:g}); expected 0 <= FMIN < FMAX <= "
                             f"{nyquist_hz:g} Hz (the Nyquist frequency)")
    return low, high


def channel_statistics(signals: np.ndarray, src: str, names=(), workers=None) -> tuple[np.ndarray, np.ndarray]:
    """Each channel's mean and RMS about it, checking that there are two or more channels of finite samples,
    none constant.

    The record is read from memory once, :data:`CHUNK_SAMPLES` of a channel at a time: each piece's sum and
    sum of squares (in double precision, the piece still in cache for the second), their difference the sum of
    squares about the piece's mean, unless a large offset would cancel digits there (:func:`_moments`); the
    pieces' means and sums of squares are then pooled exactly (Chan, Golub & LeVeque). A record whose channels'
    samples are not contiguous in memory (an array of shape (n_samples, n_channels) transposed) is read a stretch
    of samples of every channel at a time instead (:func:`_moments_by_samples`): channel by channel, each read
    would touch the whole record. The channels are shared among ``workers`` threads (default: every usable
    core, :mod:`modal.parallel`).

    Returns
    -------
    (mean, rms) : ndarray (n_channels,), ndarray (n_channels,)
        Double precision, in the units of ``signals``.
    """
    _check_shape(signals, src)
    n_channels, n = signals.shape
    mean = np.empty(n_channels)
    rms = np.empty(n_channels)
    if signals.strides[1] != signals.itemsize:  # e.g. (n_samples, n_channels).T: read a stretch of samples at a time
        mean, squares, finite = _moments_by_samples(signals)
        if not finite.all():
            _refuse_non_finite(signals, int(np.flatnonzero(~finite)[0]), src, names)
    else:
        squares = np.empty(n_channels)

        def channels_moments(first: int, stop: int) -> None:
            buffer = np.empty(min(n, CHUNK_SAMPLES))
            for ch in range(first, stop):
                moments = _moments(signals[ch], buffer)
                if moments is None:
                    _refuse_non_finite(signals, ch, src, names)
                mean[ch], squares[ch] = moments

        split_over_threads(channels_moments, n_channels, workers)
    for ch, row in enumerate(signals):
        rms[ch] = np.sqrt(squares[ch] / n)
        if not np.isfinite(rms[ch]):
            raise ParameterError(f"{src}: channel {ch + 1}{_name(names, ch)}: samples up to {np.abs(row).max():g}; "
                                 "expected values whose squares fit double precision (rescale the record)")
    constant = np.flatnonzero(~(rms > CONSTANT_CHANNEL * rms.max()))
    if constant.size:
        listing = ", ".join(f"{k + 1}{_name(names, k)}" for k in constant)
        raise ParameterError(f"{src}: channel(s) {listing} constant; expected a varying response on every channel "
                             "(drop dead channels)")
    return mean, rms


@np.errstate(over="ignore", invalid="ignore")  # (squares that overflow are refused by the caller)
def _moments(row: np.ndarray, buffer: np.ndarray):
    """(mean, sum of squares about it) of one channel, piece by piece (see :func:`channel_statistics`), in
    double precision; None when a piece's mean is not finite.

    Each piece's sum and sum of squares come from one read of it; where its mean is large against its spread
    (the sum of squares about the mean below :data:`CANCELLATION` of the sum of squares about zero), the
    difference would lose digits, and the piece is centred (in ``buffer``, which also holds a single-precision
    piece converted to double) and its squares summed again."""
    pooled_mean, pooled_squares, count = 0.0, 0.0, 0
    for start in range(0, row.size, CHUNK_SAMPLES):
        piece = row[start:start + CHUNK_SAMPLES]
        m = piece.size
        if piece.dtype != np.float64:  # summed in double precision
            buffer[:m] = piece
            piece = buffer[:m]
        total_sum = float(piece.sum())
        piece_mean = total_sum / m
        if not np.isfinite(piece_mean):
            return None
        squares = float(np.dot(piece, piece))
        about_mean = squares - total_sum * piece_mean
        if not about_mean > CANCELLATION * squares:
            centred = buffer[:m]
            np.subtract(piece, piece_mean, out=centred)
            about_mean = float(np.dot(centred, centred))
        total = count + m
        delta = piece_mean - pooled_mean
        pooled_squares += about_mean + delta * delta * count * m / total
        pooled_mean += delta * m / total
        count = total
    return pooled_mean, pooled_squares


@np.errstate(over="ignore", invalid="ignore")
def _moments_by_samples(signals: np.ndarray):
    """(means, sums of squares about them, finite) of every channel, as :func:`_moments` but a stretch of samples
    of every channel at a time (:data:`CHUNK_SAMPLES` samples in all), copied into a double-precision buffer."""
    n_channels, n = signals.shape
    width = max(CHUNK_SAMPLES // n_channels, 1)
    buffer = np.empty((n_channels, min(n, width)))
    pooled_mean, pooled_squares, count = np.zeros(n_channels), np.zeros(n_channels), 0
    finite = np.ones(n_channels, bool)
    for start in range(0, n, width):
        piece = buffer[:, :min(width, n - start)]
        piece[...] = signals[:, start:start + width]
        m = piece.shape[1]
        total_sum = piece.sum(axis=1)
        piece_mean = total_sum / m
        finite &= np.isfinite(piece_mean)
        squares = np.einsum("ij,ij->i", piece, piece)
        about_mean = squares - total_sum * piece_mean
        cancelled = ~(about_mean > CANCELLATION * squares)
        if cancelled.any():
            centred = piece[cancelled] - piece_mean[cancelled, None]
            about_mean[cancelled] = np.einsum("ij,ij->i", centred, centred)
        total = count + m
        delta = piece_mean - pooled_mean
        pooled_squares += about_mean + delta * delta * count * m / total
        pooled_mean += delta * m / total
        count = total
    return pooled_mean, pooled_squares, finite


def _check_shape(signals: np.ndarray, src: str) -> None:
    if signals.ndim != 2:
        raise ParameterError(f"{src}: 'data' has shape {signals.shape}; expected (n_channels, n_samples)")
    if signals.shape[0] < 2:
        raise ParameterError(f"{src}: {signals.shape[0]} channel; operational modal analysis needs at least 2 "
                             "response channels (data of shape (n_channels, n_samples))")


def _finite_mean(signals: np.ndarray, ch: int, src: str, names) -> float:
    """Channel ``ch``'s mean in double precision, whatever it is stored in; refused (:func:`_refuse_non_finite`)
    when it is not finite."""
    mean = signals[ch].mean(dtype=np.float64)
    if not np.isfinite(mean):
        _refuse_non_finite(signals, ch, src, names)
    return mean


def _refuse_non_finite(signals: np.ndarray, ch: int, src: str, names) -> None:
    """Refuse a record whose channel ``ch`` sums to a non-finite number: naming the first NaN or infinite sample
    of the record, or the channel when its finite samples' sum overflows."""
    bad = ~np.isfinite(signals)
    if bad.any():
        ch, i = (int(v) for v in np.argwhere(bad)[0])
        raise ParameterError(f"{src}: channel {ch + 1}{_name(names, ch)}, sample {i}: {signals[ch, i]}; "
                             f"expected finite samples ({int(bad.sum())} are not)")
    raise ParameterError(f"{src}: channel {ch + 1}{_name(names, ch)}: samples up to {np.abs(signals[ch]).max():g}; "
                         "expected values whose sum fits double precision (rescale the record)")


def _centred_decimated(signals: np.ndarray, factor: int, src: str, names, workers=None) -> np.ndarray:
    """Each channel less its mean (in double precision), decimated by ``factor`` (:func:`decimate`): one channel
    at a time, so that no double-precision copy of the whole record is made (a 10⁶ × 64 record's would be
    512 MB); the channels shared among ``workers`` threads, the filter designed once."""
    _check_shape(signals, src)
    n_channels, n = signals.shape
    taps = decimation_filter(factor)
    out = np.empty((n_channels, -(-n // factor)))

    def decimate_channels(first: int, stop: int) -> None:
        means = [_finite_mean(signals, ch, src, names) for ch in range(first, stop)]
        decimate(signals[first:stop], factor, taps, mean=means, out=out[first:stop])

    split_over_threads(decimate_channels, n_channels, workers)
    return out


def _name(names, ch) -> str:
    return f" ({names[ch]})" if names and ch < len(names) and names[ch] != str(ch) else ""


def prepare(data, sample_rate_hz=None, band_hz=None, quantity: str | None = None, screen: bool = True,
            workers=None) -> Prepared:
    """Check a record, bring it to a rate suited to the band and find each channel's mean and RMS.

    Parameters
    ----------
    data : ndarray (n_channels, n_samples), TimeRecord or path
    sample_rate_hz : float, optional
        Required for an array; taken from a record or file.
    band_hz : (float, float), optional
        Band of interest, Hz (default: 0 to 80 % of the Nyquist frequency). The record is decimated
        (linear-phase FIR) so that the band's upper edge lies at or below half of the new Nyquist frequency.
    quantity : str, optional
        What the channels measured, for an array (a record says it itself).
    screen : bool
        Warn of dropouts and clipping (:func:`modal.operational.screen.screen_samples`); False for a record
        prepared again (a plot of a record identified already).
    workers : int, optional
        Threads for the channels' decimation and statistics (default: every usable core).
    """
    prepared, recorded = prepare_unscreened(data, sample_rate_hz, band_hz, quantity, workers)
    if screen:  # on the samples as recorded, known finite by now
        screen_samples(recorded, prepared.original_rate_hz, names=prepared.names, source=prepared.source)
    return prepared


def prepare_unscreened(data, sample_rate_hz=None, band_hz=None, quantity: str | None = None,
                       workers=None) -> tuple[Prepared, np.ndarray]:
    """:func:`prepare` without the screen for dropouts and clipping: (the record prepared, its samples as recorded,
    which the screen reads; known finite)."""
    signals, rate, file_quantity, names, src = _record(data, sample_rate_hz)
    if not (np.isfinite(rate) and rate > 0):
        raise ParameterError(f"{src}: 'sample_rate_hz' is {rate!r}; expected a positive number of samples per second")
    low, high = check_band(band_hz, rate / 2, src)
    check_held(signals, rate, (low, high), src, names)
    factor = decimation_factor(rate, high)
    # a record to be decimated is centred (an offset would ring in the filter) and filtered in double precision,
    # channel by channel; any other is used as it is stored (see Prepared)
    if factor > 1:
        work = _centred_decimated(signals, factor, src, names, workers)
        if work.shape[1] < 2:
            raise ParameterError(f"{src}: {signals.shape[1]} samples; too short a record for the band up to "
                                 f"{high:g} Hz")
    else:
        work = signals
    mean, scale = channel_statistics(work, src, names, workers)
    return Prepared(work, rate / factor, mean, scale, (low, high), factor, rate, quantity or file_quantity, names,
                    src), signals
