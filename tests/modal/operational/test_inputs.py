"""Preparing an ambient record: samples read once, in their stored precision, and left as they are."""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from modal.errors import ParameterError
from modal.operational.inputs import CHUNK_SAMPLES, prepare


def _record(n_channels=8, n_samples=200_000, seed=0):
    rng = np.random.default_rng(seed)
    return (rng.standard_normal((n_channels, n_samples)) * np.arange(1, n_channels + 1)[:, None] + 3.0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("workers", [1, 2])
def test_record_is_neither_copied_nor_centred(dtype, workers):
    # the prepared record is the input itself; the check allocates one piece of a channel at a time (512 kB) per
    # thread and the per-channel statistics, far below a copy of the record (6.4 or 12.8 MB here)
    signals = _record().astype(dtype)
    tracemalloc.start()
    prepared = prepare(signals, 100.0, workers=workers)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert prepared.signals is signals
    piece = CHUNK_SAMPLES * 8
    assert peak < workers * piece + 0.05 * signals.nbytes, peak / piece


def test_single_and_double_precision_records_agree():
    # the same samples stored in single precision: each channel's mean and RMS are taken in double either way,
    # so they agree with those of the same samples stored in double to double-precision rounding, and with
    # those of the unrounded samples to the input's own rounding (6e-8 of each sample)
    double = _record()
    single = double.astype(np.float32)
    a, b, c = prepare(double, 100.0), prepare(single.astype(float), 100.0), prepare(single, 100.0)
    assert np.allclose(c.scale, b.scale, rtol=1e-12) and np.allclose(c.mean, b.mean, rtol=1e-12)
    assert np.allclose(c.scale, a.scale, rtol=1e-6) and np.allclose(c.mean, a.mean, rtol=1e-6)
    assert np.array_equal(c.channel(3), b.channel(3))


@pytest.mark.parametrize("offset, rtol", [(0.0, 1e-11), (1e6, 1e-9)])
def test_mean_and_rms_are_exact(offset, rtol):
    # read in pieces (200 000 samples: three whole pieces and a partial one) and pooled: the channels' mean and
    # RMS about it, as from each whole channel centred in double precision. With a mean of 3 and an RMS of 1-8,
    # a piece's sum of squares about its mean is the difference of sums of 65 536 squares: rounding of
    # about 256 (√65 536) × 1e-16 × 10 of it (2.6e-13; 1e-11 allowed). Samples at 10⁶ carry 1e-10 of absolute
    # rounding each, so their RMS holds to 1e-9: those pieces are centred first, since a sum of squares about
    # zero would have lost 10¹² × 2e-16 = 2e-4 of the variance to cancellation
    signals = _record() + offset
    assert signals.shape[1] % CHUNK_SAMPLES and signals.shape[1] > 3 * CHUNK_SAMPLES
    prepared = prepare(signals, 100.0)
    centred = signals - signals.mean(axis=1, keepdims=True)
    rms = np.sqrt(np.mean(centred**2, axis=1))
    assert np.allclose(prepared.mean, signals.mean(axis=1), rtol=1e-14)
    assert np.allclose(prepared.scale, rms, rtol=rtol)


def test_channel_is_the_centred_and_scaled_samples():
    # one channel centred and scaled in double precision, stored in single: rounding of samples within about
    # 5 RMS (2.4e-7 each)
    signals = _record()
    prepared = prepare(signals, 100.0)
    centred = signals - signals.mean(axis=1, keepdims=True)
    rms = np.sqrt(np.mean(centred**2, axis=1))
    for ch in (0, 7):
        unit = prepared.channel(ch)
        assert unit.dtype == np.float32
        assert np.max(np.abs(unit - centred[ch] / rms[ch])) < 1e-6


def test_decimated_record_is_the_centred_channels_filtered():
    # a record far above its band is centred and decimated channel by channel (no double copy of the whole
    # record): the same numbers as centring the whole record and filtering it at once
    from scipy.signal import resample_poly

    from modal.operational.correlations import decimation_filter

    signals = _record(n_channels=3, n_samples=40_000)
    prepared = prepare(signals, 1000.0, (1.0, 30.0))
    assert prepared.decimation == 8 and prepared.sample_rate_hz == 125.0
    reduced = resample_poly(signals - signals.mean(axis=1, keepdims=True), 1, 8, axis=1, window=decimation_filter(8))
    assert np.allclose(prepared.signals, reduced, rtol=0, atol=1e-12)
    centred = reduced - reduced.mean(axis=1, keepdims=True)
    assert np.allclose(prepared.mean, reduced.mean(axis=1), rtol=0, atol=1e-12)
    assert np.allclose(prepared.scale, np.sqrt(np.mean(centred**2, axis=1)), rtol=1e-12)


def test_bad_sample_of_a_record_to_be_decimated_is_named():
    signals = _record(n_channels=3, n_samples=40_000)
    signals[2, 1234] = np.nan
    with pytest.raises(ParameterError, match=r"channel 3, sample 1234: nan; expected finite samples \(1 are not\)"):
        prepare(signals, 1000.0, (1.0, 30.0))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_bad_sample_in_a_later_piece_is_named(dtype):
    # the check reads a channel piece by piece: a NaN in its third piece is found there and named by the first
    # non-finite sample of the whole record
    signals = _record(n_channels=3).astype(dtype)
    signals[1, 2 * CHUNK_SAMPLES + 17] = np.inf
    signals[2, 5] = np.nan
    with pytest.raises(ParameterError, match=rf"channel 2, sample {2 * CHUNK_SAMPLES + 17}: inf; expected finite "
                                             r"samples \(2 are not\)"):
        prepare(signals, 100.0)


def test_samples_whose_squares_overflow_are_refused():
    # finite samples with a finite mean whose squares overflow double precision: named, not called constant
    signals = _record(n_channels=3)
    signals[2] *= 1e160
    with pytest.raises(ParameterError, match="channel 3: samples up to .*e\\+16.; expected values whose squares fit"):
        prepare(signals, 100.0)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_transposed_record_gives_the_same_statistics(dtype):
    # an array of shape (n_samples, n_channels) transposed: its channels' samples lie apart in memory, and it is
    # read a stretch of samples of every channel at a time; the same means and RMS to double-precision rounding
    # of sums of 200 000 samples, the same first bad sample named
    signals = _record().astype(dtype)
    signals[5] += 1e6  # one channel's pieces centred before their squares are summed
    transposed = np.ascontiguousarray(signals.T).T
    assert transposed.strides[1] != transposed.itemsize
    a, b = prepare(signals, 100.0), prepare(transposed, 100.0)
    assert np.allclose(b.mean, a.mean, rtol=1e-13) and np.allclose(b.scale, a.scale, rtol=1e-9)
    transposed[3, 70_000] = np.nan
    transposed[6, 5] = np.inf
    with pytest.raises(ParameterError, match=r"channel 4, sample 70000: nan; expected finite samples \(2 are not\)"):
        prepare(transposed, 100.0)


def test_an_array_rate_in_khz_is_named():
    # 0.1 for 100 Hz: the modes come out at a thousandth of their frequencies, stable and within their errors
    # (3.1 Hz as 0.0031 Hz, no flag), so the rate itself is the only sign; as for a file's rate field
    from modal.errors import QualityWarning

    with pytest.warns(QualityWarning, match=r"<array>: 'sample_rate_hz' is 0\.1 Hz, below .* give 100 \(Hz\)"):
        prepared = prepare(_record(n_samples=20_000), 0.1)
    assert prepared.sample_rate_hz == 0.1  # named, not changed


@pytest.mark.parametrize("rate_hz", [100.0, 1000.0])  # (the second decimated by 8 first)
def test_statistics_do_not_depend_on_the_number_of_threads(rate_hz):
    # the channels are shared among threads, each channel read (and decimated) as one loop does it: bit for bit
    # the same
    signals = _record(n_channels=5)
    signals[3] += 1e6  # a channel whose pieces are centred first
    one = prepare(signals, rate_hz, (1.0, 30.0), workers=1)
    for workers in (2, 3, 8):
        other = prepare(signals, rate_hz, (1.0, 30.0), workers=workers)
        assert np.array_equal(other.signals, one.signals)
        assert np.array_equal(other.mean, one.mean) and np.array_equal(other.scale, one.scale)
