"""Output correlations of an ambient record: decimation to the band, reference channels, and the
correlation functions by FFT, kept per block of the record for the error bars.

The correlation ``R_k = E[y(t + kΔt) y_ref(t)ᵀ]`` (outputs × references) is estimated from segments
of the record: each segment of ``n_seg`` samples of the references is correlated, by one FFT product,
with the same stretch of every output extended by the longest lag (overlap-save), so that every pair
of samples up to the longest lag is counted exactly once. The cross-spectra are summed over the
segments of a block with one matrix product per frequency line; the block sums, transformed back,
are the blocks' unbiased correlations and their mean the record's. The blocks are independent: each
thread (:mod:`modal.parallel`) takes a contiguous share of them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..parallel import split_over_threads

__all__ = ["Correlations", "correlations", "decimation_factor", "decimation_filter", "decimate", "choose_references"]

#: after decimation the band's upper edge lies at or below this fraction of the new Nyquist frequency
BAND_FRACTION_OF_NYQUIST = 0.5
#: the record is cut into at most this many blocks for the error bars (fewer when it is short): as many as
#: the error bars use (:data:`modal.operational.modes.MAX_ERROR_BLOCKS`); every block costs an inverse FFT
#: per pair of channels
MAX_BLOCKS = 50


@dataclass(frozen=True)
class Correlations:
    """Correlation functions of a record, for lags 0…``max_lag``.

    Attributes
    ----------
    blocks : ndarray, shape (n_blocks, max_lag + 1, n_outputs, n_references)
        Each block's unbiased correlation estimate (units² of the signals).
    weights : ndarray, shape (n_blocks,)
        Samples per block (the record's estimate is their weighted mean).
    sample_rate_hz : float
        Rate of the (decimated) signals.
    references : tuple of int
        Output channels used as references (projection channels).
    """

    blocks: np.ndarray
    weights: np.ndarray
    sample_rate_hz: float
    references: tuple[int, ...]

    @property
    def mean(self) -> np.ndarray:
        """The record's correlation, shape (max_lag + 1, n_outputs, n_references)."""
        return np.tensordot(self.weights / self.weights.sum(), self.blocks, axes=1)

    @property
    def max_lag(self) -> int:
        return self.blocks.shape[1] - 1

    def grouped(self, n_groups: int) -> tuple[np.ndarray, np.ndarray]:
        """The blocks merged into ``n_groups`` contiguous groups: (correlations, weights)."""
        n = self.blocks.shape[0]
        n_groups = int(min(max(n_groups, 1), n))
        if n_groups == n:  # (a 10⁶ × 64 record's 50 blocks are 9 MB)
            return self.blocks, self.weights
        edges = np.linspace(0, n, n_groups + 1).round().astype(int)
        weights = np.add.reduceat(self.weights, edges[:-1])
        # each group's weighted mean, a block alone its own (no temporary the size of all the blocks: 13 MB for 50
        # blocks of 64 outputs)
        groups = np.empty((n_groups,) + self.blocks.shape[1:])
        for g, (first, stop) in enumerate(zip(edges[:-1], edges[1:])):
            groups[g] = self.blocks[first] if stop - first == 1 else \
                np.tensordot(self.weights[first:stop] / weights[g], self.blocks[first:stop], axes=1)
        return groups, weights


def decimation_factor(sample_rate_hz: float, high_hz: float) -> int:
    """The largest integer factor that keeps ``high_hz`` below :data:`BAND_FRACTION_OF_NYQUIST` of the new
    Nyquist frequency (1: no decimation)."""
    return max(1, int(np.floor(sample_rate_hz * BAND_FRACTION_OF_NYQUIST / (2.0 * high_hz))))


#: the decimation filter: a Kaiser-windowed sinc cut off at the new Nyquist frequency, 2 · this · factor + 1 taps
DECIMATION_HALF_LENGTH = 5
#: its Kaiser window's β
DECIMATION_KAISER_BETA = 8.0


def decimation_filter(factor: int) -> np.ndarray:
    """The FIR taps :func:`decimate` filters with.

    The band lies at or below :data:`BAND_FRACTION_OF_NYQUIST` (half) of the new Nyquist frequency f_N, so
    what must not alias is what would fold into it, above 1.5 f_N; between 0.5 and 1.5 f_N the filter may
    roll off. These taps (5 · factor on each side, β = 8) keep the band within 0.002 dB and hold what
    would alias into it 73 dB down, with half the taps (and time) of scipy's ``resample_poly`` default
    (10 · factor, β = 5: 0.013 dB and 64 dB), whose narrower roll-off this band does not need.
    """
    from scipy.signal import firwin

    return firwin(2 * DECIMATION_HALF_LENGTH * factor + 1, 1.0 / factor, window=("kaiser", DECIMATION_KAISER_BETA))


#: outputs per row of the decimation's matrix products (:func:`decimate`): rows of 10-16 outputs were within
#: 15 % of each other in time, 12 the fastest for factors 2-30 (10⁶ samples, one thread)
DECIMATION_ROW_OUTPUTS = 12
#: samples of a channel :func:`decimate` centres and filters at a time (their products then read them from cache:
#: a quarter faster than over the whole channel, 2¹⁵-2¹⁶ the fastest)
DECIMATION_PIECE = 1 << 16


def decimate(signals: np.ndarray, factor: int, taps: np.ndarray | None = None, mean=None,
             out: np.ndarray | None = None) -> np.ndarray:
    """Low-pass filter each channel (``taps``, by default :func:`decimation_filter`) and keep every
    ``factor``-th sample: scipy's ``resample_poly(signals, 1, factor, axis=1, window=taps)`` to double-precision
    rounding (the same ``ceil(n_samples / factor)`` outputs, the record taken as zero beyond its ends).

    Output m is ``Σ_t g[t] x[m·factor + t − h]``, g the taps reversed and h half their number less one. With
    the (zero-padded) channel cut into rows of B·factor samples (B = :data:`DECIMATION_ROW_OUTPUTS`), a row of
    B outputs is a fixed (banded Toeplitz) linear map of that row and the next: two matrix products,
    (rows × B·factor)(B·factor × B), on the rows of the centred channel as they lie (no overlapping copy).
    They do 2·B·factor multiplications per output where the filter needs 10·factor + 1 (the banded maps' zeros
    are multiplied too), but at BLAS's rate: a third to a half of the time of scipy's polyphase loop (upfirdn;
    10⁶ samples, factors 2-30, one thread).

    Parameters
    ----------
    signals : ndarray, shape (n_channels, n_samples)
        Single or double precision.
    factor : int
        Keep every ``factor``-th sample; 1 or less returns ``signals`` as they are.
    taps : ndarray, optional
        The FIR filter's taps (odd in number: the linear-phase filter :func:`decimation_filter` gives).
    mean : ndarray, shape (n_channels,), optional
        Each channel's mean, taken off (in double precision) before the filter.
    out : ndarray, shape (n_channels, ceil(n_samples / factor)), optional
        Double-precision array to write into.

    Returns
    -------
    ndarray, shape (n_channels, ceil(n_samples / factor))
        Double precision, in the units of ``signals``.
    """
    if factor <= 1:
        return signals
    taps = decimation_filter(factor) if taps is None else np.asarray(taps, float)
    n_channels, n = signals.shape
    n_out = -(-n // factor)
    if out is None:
        out = np.empty((n_channels, n_out))
    lead = (taps.size - 1) // 2  # zeros before the first sample (the filter's delay)
    g = taps[::-1]
    width = max(DECIMATION_ROW_OUTPUTS, -(-(taps.size - factor) // factor))  # rows 2 products cover
    row = width * factor
    terms = -(-((width - 1) * factor + taps.size) // row)
    # term c maps row r + c to row r's outputs: T[c][v, i] = g[c·row + v − i·factor]
    v = np.arange(row)[:, None]
    i = np.arange(width)[None, :]
    maps = []
    for c in range(terms):
        t = c * row + v - i * factor
        maps.append(np.where((t >= 0) & (t < taps.size), g[np.clip(t, 0, taps.size - 1)], 0.0))
    n_rows = -(-n_out // width)
    # the channel is centred into a short buffer a piece at a time (the rows of about DECIMATION_PIECE samples
    # and the terms − 1 rows after them), which both products then read from cache
    piece_rows = max(1, DECIMATION_PIECE // row)
    buffer = np.empty((piece_rows + terms - 1) * row)
    outputs = np.empty((n_rows, width))
    more = np.empty((piece_rows, width))
    shift = np.zeros(n_channels) if mean is None else np.asarray(mean, float)
    for ch in range(n_channels):
        for r0 in range(0, n_rows, piece_rows):
            r1 = min(r0 + piece_rows, n_rows)
            first = r0 * row - lead  # the sample the buffer starts at (zeros before 0 and from n on)
            piece = buffer[:(r1 - r0 + terms - 1) * row]
            lo, hi = max(first, 0), min(first + piece.size, n)
            piece[:lo - first] = 0.0
            piece[max(hi, lo) - first:] = 0.0
            np.subtract(signals[ch, lo:hi], shift[ch], out=piece[lo - first:hi - first])
            rows = piece.reshape(-1, row)
            np.matmul(rows[:r1 - r0], maps[0], out=outputs[r0:r1])
            for c in range(1, terms):
                outputs[r0:r1] += np.matmul(rows[c:c + r1 - r0], maps[c], out=more[:r1 - r0])
        out[ch] = outputs.reshape(-1)[:n_out]
    return out


def _segment_length(max_lag: int, n_samples: int) -> int:
    """Samples per segment: a fast FFT length of at least 4 lags and 256 samples, less the longest lag, at
    most the record. The extension by the longest lag then costs the forward FFTs at most a third more,
    while the inverse FFTs, one per block and pair of channels, stay short."""
    from scipy.fft import next_fast_len

    n_seg = next_fast_len(max(4 * max_lag, 256), real=True) - max_lag
    return int(max(min(n_seg, n_samples - max_lag), max_lag + 1))


def correlations(signals: np.ndarray, sample_rate_hz: float, references, max_lag: int,
                 max_blocks: int = MAX_BLOCKS, mean=None, scale=None, workers=None) -> Correlations:
    """Correlations ``R_k``, k = 0…``max_lag``, of every output with the references, per block.

    Parameters
    ----------
    signals : ndarray, shape (n_outputs, n_samples)
        The signals (zero-mean unless ``mean`` is given), single or double precision.
    sample_rate_hz : float
    references : sequence of int
        Reference channels (indices into the outputs).
    max_lag : int
        Longest lag, samples.
    max_blocks : int
        At most this many blocks (each of whole segments).
    mean : ndarray, shape (n_outputs,), optional
        Each signal's mean: removed as the samples are read, one block at a time, in double precision before
        they are rounded to single (so that an offset large against the signal costs no precision).
    scale : ndarray, shape (n_outputs,), optional
        Each signal's RMS: the correlations are those of the signals divided by it (``R_k`` divided by
        ``scale[o] scale[r]``), the samples themselves left as they are.
    workers : int, optional
        Threads over which the blocks are shared (default: every usable core, :mod:`modal.parallel`); the
        result is the same, bit for bit, whatever their number.

    Returns
    -------
    Correlations
        In units² of the signals, or of the signals divided by ``scale``.
    """
    from scipy import fft as sfft

    refs = np.asarray(references, int)
    n_out, n = signals.shape
    n_seg = _segment_length(max_lag, n)
    n_fft = sfft.next_fast_len(n_seg + max_lag, real=True)
    n_segments = (n - max_lag) // n_seg
    if n_segments < 1:
        raise ParameterError(f"{n} samples hold no segment of {n_seg} samples plus the longest lag {max_lag}")
    n_blocks = int(min(max_blocks, n_segments))
    edges = np.linspace(0, n_segments, n_blocks + 1).round().astype(int)
    lagged = np.empty((n_blocks, max_lag + 1, n_out, refs.size))
    shift = None if mean is None else np.asarray(mean, float)[:, None]
    # float32 FFTs: their rounding (1e-7 relative) lies far below the estimates' scatter (1/√samples)
    record = np.ascontiguousarray(signals, dtype=np.float32) if mean is None else None

    def block_correlations(first_block: int, stop_block: int) -> None:
        """The correlation sums of blocks ``first_block``…``stop_block − 1``, into ``lagged``."""
        spectra = np.empty((n_fft // 2 + 1, n_out, refs.size), np.complex64)
        most = int(np.diff(edges[first_block:stop_block + 1]).max())  # segments in the share's longest block
        if mean is not None:  # each block's samples centred into one buffer, reused
            buffer = np.empty((n_out, most * n_seg + max_lag), np.float32)
        # the references' segments, each followed by the zeros that pad it to n_fft (written once): transformed as
        # they lie, with no gathering copy of the reference rows and no padded copy of it
        padded = np.zeros((refs.size, most, n_fft), np.float32)
        for b in range(first_block, stop_block):
            first, stop = edges[b] * n_seg, edges[b + 1] * n_seg + max_lag
            segments = edges[b + 1] - edges[b]
            if mean is None:
                data = record[:, first:stop]
            else:
                data = buffer[:, :stop - first]
                np.subtract(signals[:, first:stop], shift, out=data)
            # (samples, n_out, segs): transformed along the first axis, the spectra come out line by line, each
            # line's (outputs × segments) matrix contiguous for the product below
            windows = np.lib.stride_tricks.sliding_window_view(data, n_seg + max_lag, axis=1)
            ext = windows[:, ::n_seg].transpose(2, 0, 1)
            future = sfft.rfft(ext, n=n_fft, axis=0)  # every output, extended by the longest lag
            for row, r in zip(padded, refs):
                row[:segments, :n_seg] = data[r, :segments * n_seg].reshape(segments, n_seg)
            past = sfft.rfft(padded[:, :segments].transpose(2, 0, 1), axis=0)  # the references' segments, padded
            # Σ over the block's segments of Y_o(f) conj(X_r(f)): one (outputs × segments)(segments × refs)
            # product per line
            np.matmul(future, past.conj().transpose(0, 2, 1), out=spectra)
            lagged[b] = sfft.irfft(spectra, n=n_fft, axis=0)[:max_lag + 1]  # (lags, n_out, refs)

    split_over_threads(block_correlations, n_blocks, workers)
    weights = (np.diff(edges) * n_seg).astype(float)
    lagged /= weights[:, None, None, None]
    if scale is not None:
        scale = np.asarray(scale, float)
        lagged /= scale[:, None] * scale[refs][None, :]
    return Correlations(lagged, weights, float(sample_rate_hz), tuple(int(r) for r in refs))


def choose_references(signals: np.ndarray, n_references: int, probe_lags: int = 8,
                      probe_samples: int = 1 << 14, mean=None) -> tuple[int, ...]:
    """The channels that best span the outputs' correlations, for projection.

    Each channel (less its ``mean``, when given) is scaled to unit RMS; the correlations of every
    channel with every other over a few lags (from the first ``probe_samples`` samples, one matrix
    product in single precision) form the columns of one matrix, and a column-pivoted QR picks the
    ``n_references`` channels that are the most independent and carry the most correlated
    (not white) signal: white measurement noise only enters lag 0, which is left out. The
    choice needs only the rough correlations that 2¹⁴ samples give (each within a few percent);
    the identification then uses the whole record.
    """
    from scipy.linalg import qr

    n_out, n = signals.shape
    if n_references >= n_out:
        return tuple(range(n_out))
    piece = signals[:, : min(n, probe_samples + probe_lags)]
    piece = np.array(piece if mean is None else piece - np.asarray(mean, float)[:, None], dtype=np.float32)
    piece /= np.sqrt(np.mean(piece**2, axis=1, keepdims=True))
    m = piece.shape[1] - probe_lags
    # one column per candidate reference, the rows (channel, lag) for lags 1…probe_lags: one product per lag,
    # each from the piece itself (no lagged copy of it)
    columns = np.stack([piece[:, k:k + m] @ piece[:, :m].T for k in range(1, probe_lags + 1)], axis=1)
    columns = columns.reshape(n_out * probe_lags, n_out)
    _, _, pivots = qr(columns.astype(float), mode="economic", pivoting=True)
    return tuple(sorted(int(p) for p in pivots[:n_references]))
