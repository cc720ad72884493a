"""Correlations by FFT per block, the references chosen, the decimation to the band."""
from __future__ import annotations

import numpy as np
import pytest

from modal.operational.correlations import (Correlations, choose_references, correlations, decimate,
                                            decimation_factor, decimation_filter)
from modal.errors import ParameterError


def test_correlations_equal_the_direct_sums_per_block():
    rng = np.random.default_rng(1)
    y = rng.standard_normal((3, 30_000))
    y[1] += 0.5 * np.roll(y[0], 3)
    c = correlations(y, 50.0, [0, 2], 12, max_blocks=5)
    edges = np.concatenate([[0], np.cumsum(c.weights)]).astype(int)
    for b in range(5):
        lo, hi = edges[b], edges[b + 1]
        for k in range(13):
            direct = y[:, lo + k:hi + k] @ y[[0, 2], lo:hi].T / (hi - lo)
            # float32 FFTs: rounding of 1e-7 of the signals' power
            assert np.allclose(c.blocks[b, k], direct, atol=2e-6)
    assert np.allclose(c.mean, np.average(c.blocks, axis=0, weights=c.weights))
    merged, w = c.grouped(2)
    assert w.sum() == c.weights.sum() and np.allclose(np.average(merged, axis=0, weights=w), c.mean)



def test_references_out_of_order_and_blocks_of_unequal_length_in_one_share():
    # the references' segments are padded in a buffer per share, sized for its longest block: a shorter block after
    # a longer one, and references given out of order, must still give each block's direct sums (22 segments of
    # 244 samples in 3 blocks of 7, 8 and 7 segments, all on one thread); tolerance as in the test above
    rng = np.random.default_rng(7)
    y = rng.standard_normal((4, 22 * 244 + 12))
    y[2] += 0.7 * np.roll(y[3], 2)
    refs = [3, 0, 2]
    c = correlations(y, 50.0, refs, 12, max_blocks=3, workers=1)
    edges = np.concatenate([[0], np.cumsum(c.weights)]).astype(int)
    assert np.diff(edges).tolist() == [7 * 244, 8 * 244, 7 * 244]
    for b in range(3):
        for k in range(13):
            assert np.allclose(c.blocks[b, k], _direct(y, refs, edges[b], edges[b + 1], k), atol=2e-6)


def test_a_block_alone_in_its_group_is_kept_as_it_is():
    # 6 blocks in 5 groups: [0], [1], [2, 3], [4], [5]; a block alone is its group's mean exactly (not rounded
    # through its weight), two blocks of one weight their plain mean
    c = Correlations(np.random.default_rng(0).standard_normal((6, 5, 3, 2)), np.array([700.0] * 5 + [701.0]), 50.0,
                     (0, 1))
    merged, w = c.grouped(5)
    assert w.tolist() == [700, 700, 1400, 700, 701]
    for group, block in ((0, 0), (1, 1), (3, 4), (4, 5)):
        assert np.array_equal(merged[group], c.blocks[block])
    assert np.allclose(merged[2], (c.blocks[2] + c.blocks[3]) / 2, rtol=1e-15, atol=1e-15)

def _direct(y, refs, lo, hi, k):
    return y[:, lo + k:hi + k] @ y[refs, lo:hi].T / (hi - lo)


@pytest.mark.parametrize("offset, dtype", [(1e4, np.float64), (3.0, np.float32)])
def test_correlations_of_the_raw_record_are_those_of_the_centred_scaled_one(offset, dtype):
    # the record as recorded (an offset, channels of different RMS), its mean removed as each block is read (in
    # double precision, before the samples are rounded to single) and its scale taken out of the correlation
    # matrices: the correlations of the explicitly centred, unit-RMS record. The FFTs and the sums over a
    # block's segments run in single precision: each block's correlation of unit-RMS signals then holds to
    # about (segments per block + log2 FFT length) single-precision epsilons (4e-6; 1e-7 is seen). Rounding the
    # raw record to single precision first, as removing the mean after the FFT would, costs about
    # eps × offset / RMS instead (4e-5 with the first offset here)
    rng = np.random.default_rng(4)
    unit = rng.standard_normal((3, 30_000))
    unit[1] += 0.5 * np.roll(unit[0], 3)
    unit /= np.sqrt(np.mean(unit**2, axis=1, keepdims=True))
    rms = np.array([0.5, 2.0, 30.0])
    raw = (unit * rms[:, None] + offset).astype(dtype)
    mean = raw.mean(axis=1, dtype=float)
    scale = np.sqrt(np.mean((raw - mean[:, None]) ** 2, axis=1))
    exact = (raw - mean[:, None]) / scale[:, None]
    refs = [0, 2]
    c = correlations(raw, 50.0, refs, 12, max_blocks=5, mean=mean, scale=scale)
    edges = np.concatenate([[0], np.cumsum(c.weights)]).astype(int)
    n_fft = 256  # the segments' FFT length for the longest lag 12
    tolerance = (c.weights.max() / (n_fft - 12) + np.log2(n_fft)) * np.finfo(np.float32).eps
    for b in range(5):
        for k in range(13):
            assert np.allclose(c.blocks[b, k], _direct(exact, refs, edges[b], edges[b + 1], k), rtol=0,
                               atol=tolerance)
    explicit = correlations(exact, 50.0, refs, 12, max_blocks=5)
    assert np.allclose(c.blocks, explicit.blocks, rtol=0, atol=tolerance)


def test_too_short_a_record_is_refused():
    with pytest.raises(ParameterError, match="no segment"):
        correlations(np.ones((2, 30)), 1.0, [0], 40)


def test_references_are_the_independent_channels():
    # channels 0 and 1 carry independent resonant responses, 2 and 3 copies of them (with noise), 4 is noise
    rng = np.random.default_rng(2)
    from scipy.signal import lfilter

    a = lfilter([1.0], [1.0, -1.8, 0.95], rng.standard_normal(40_000))
    b = lfilter([1.0], [1.0, -1.2, 0.9], rng.standard_normal(40_000))
    noise = rng.standard_normal((5, 40_000)) * 0.1 * np.std(a)
    y = np.vstack([a, b, 0.9 * a, 1.1 * b, np.zeros(40_000)]) + noise
    refs = choose_references(y, 2)
    assert {refs[0] % 2, refs[1] % 2} == {0, 1} and 4 not in refs


def test_decimation_keeps_the_band_below_half_the_new_nyquist():
    assert decimation_factor(3200.0, 200.0) == 4  # 400 Hz Nyquist: 200 Hz at half of it
    assert decimation_factor(100.0, 30.0) == 1


def test_correlations_do_not_depend_on_the_number_of_threads():
    # each thread takes a contiguous share of the blocks and computes them as one loop would: bit for bit the same
    rng = np.random.default_rng(2)
    y = rng.standard_normal((4, 40_000)) + 3.0
    mean, scale = y.mean(axis=1), y.std(axis=1)
    one = correlations(y, 50.0, [0, 3], 12, max_blocks=7, mean=mean, scale=scale, workers=1)
    for workers in (2, 3, 16):
        other = correlations(y, 50.0, [0, 3], 12, max_blocks=7, mean=mean, scale=scale, workers=workers)
        assert np.array_equal(other.blocks, one.blocks) and np.array_equal(other.weights, one.weights)


@pytest.mark.parametrize("factor", [2, 3, 5, 8, 30])
def test_decimation_filter_keeps_the_band_and_what_would_alias_into_it_out(factor):
    # the band lies at or below half the new Nyquist frequency f_N (in these units 1): there the filter is flat
    # within 0.002 dB; what folds into the band after decimation lies above 1.5 f_N, held 70 dB down or more
    # (a Kaiser window of β = 8: its side lobes near -74 dB); unit gain at 0 Hz
    from scipy.signal import freqz

    taps = decimation_filter(factor)
    assert taps.size == 10 * factor + 1 and np.isclose(taps.sum(), 1.0, rtol=0, atol=1e-12)
    f, response = freqz(taps, worN=1 << 15, fs=2.0 * factor)
    gain_db = 20 * np.log10(np.abs(response))
    assert np.abs(gain_db[f <= 0.5]).max() < 0.002
    assert gain_db[f >= 1.5].max() < -70.0


@pytest.mark.parametrize("factor", [2, 3, 5, 8, 12, 30])
@pytest.mark.parametrize("n_samples", [7, 260, 1_001, 40_003])
def test_decimation_equals_scipys_polyphase_filter(factor, n_samples):
    # the matrix products give resample_poly's outputs (every length and phase of the last output, records shorter
    # than the filter) to double-precision rounding: each output sums at most 2 · 12 · factor products of taps below
    # 1/factor with samples of O(1) (after the mean is taken off), rounding ~ 1e-13 at factor 30; an output off by one
    # sample or tap is off by O(1e-1)
    from scipy.signal import resample_poly

    rng = np.random.default_rng(factor * n_samples)
    signals = rng.standard_normal((3, n_samples)) + np.array([[0.0], [1e4], [-3.0]])
    mean = signals.mean(axis=1)
    taps = decimation_filter(factor)
    expected = resample_poly(signals - mean[:, None], 1, factor, axis=1, window=taps)
    got = decimate(signals, factor, taps, mean=mean)
    assert got.shape == expected.shape and got.dtype == np.float64
    assert np.abs(got - expected).max() < 1e-12
    single = signals[::2].astype(np.float32)  # single-precision records filtered in double, as stored
    assert np.abs(decimate(single, factor, taps) - resample_poly(single.astype(float), 1, factor, axis=1,
                                                                  window=taps)).max() < 1e-12 * 1e4


@pytest.mark.parametrize("factor", [2, 5, 30])
def test_decimated_tones_keep_the_band_and_stop_what_would_alias(factor):
    # the filter as applied: a tone in the band (at or below half the new Nyquist frequency f_N) keeps its amplitude
    # within 0.002 dB; one above 1.5 f_N, which folds into the band, comes out 70 dB down or more (the taps'
    # own response, test above; the estimate's error from 2000 output cycles' fit is below 1e-6 of the tone)
    n_out = 4000
    t = np.arange(n_out * factor)
    inner = slice(100, n_out - 100)  # away from the record's ends, where the filter meets the zeros beyond
    for f_rel, expect_db, bound_db in ((0.05, 0.0, 0.002), (0.25, 0.0, 0.002), (0.5, 0.0, 0.002),
                                       (1.5, None, -70.0), (1.9, None, -70.0)):
        cycles = f_rel / (2 * factor)  # cycles per input sample: f_N is half the output rate
        y = decimate(np.cos(2 * np.pi * cycles * t + 0.3)[None, :], factor)[0][inner]
        m = np.arange(n_out)[inner]
        basis = np.column_stack([np.cos(2 * np.pi * cycles * factor * m), np.sin(2 * np.pi * cycles * factor * m)])
        coef = np.linalg.lstsq(basis, y, rcond=None)[0]
        gain_db = 20 * np.log10(np.hypot(*coef))
        if expect_db is None:
            assert gain_db < bound_db
        else:
            assert abs(gain_db - expect_db) < bound_db
