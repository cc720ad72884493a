"""Preparing an ambient record: samples read in their stored precision."""
from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from modal.errors import ParameterError
from modal.operational.inputs import prepare


def _record(n_channels=8, n_samples=200_000, seed=0):
    rng = np.random.default_rng(seed)
    return (rng.standard_normal((n_channels, n_samples)) * np.arange(1, n_channels + 1)[:, None] + 3.0)


def test_single_precision_record_is_not_copied_to_double():
    # the prepared record (single precision) is as large as a single-precision input; a double copy of the
    # input would add twice that to the peak, per-channel temporaries (one channel in double) 1/4 of it here
    signals = _record().astype(np.float32)
    tracemalloc.start()
    prepared = prepare(signals, 100.0)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert prepared.signals.dtype == np.float32
    assert peak < 1.6 * signals.nbytes, peak / signals.nbytes


def test_single_and_double_precision_records_agree():
    # the same samples stored in single precision: each channel's mean and RMS are taken in double either way,
    # so the prepared signals differ by the input's own rounding (6e-8 of each sample, ~2e-7 of the unit RMS
    # here, where the mean is 3 and the RMS 1-8) and the scales by far less than 1e-6
    double = _record()
    single = double.astype(np.float32)
    a, b, c = prepare(double, 100.0), prepare(single.astype(float), 100.0), prepare(single, 100.0)
    assert np.allclose(c.scale, b.scale, rtol=1e-12)  # the same samples, the same double arithmetic
    assert np.array_equal(c.signals, b.signals)
    assert np.allclose(c.scale, a.scale, rtol=1e-6)
    assert np.max(np.abs(c.signals - a.signals)) < 1e-6


def test_prepared_channels_are_the_explicitly_centred_and_scaled_samples():
    # centred piece by piece (200 000 samples: three whole pieces and a partial one) and scaled in place: the
    # same as centring and scaling each whole channel in double precision, to single-precision rounding of
    # samples within about 5 RMS (2.4e-7 each, a second rounding by the division)
    from modal.operational.inputs import CHUNK_SAMPLES

    signals = _record()
    assert signals.shape[1] % CHUNK_SAMPLES and signals.shape[1] > 3 * CHUNK_SAMPLES
    prepared = prepare(signals, 100.0)
    centred = signals - signals.mean(axis=1, keepdims=True)
    rms = np.sqrt(np.mean(centred**2, axis=1))
    assert np.allclose(prepared.scale, rms, rtol=1e-12)
    assert np.max(np.abs(prepared.signals - centred / rms[:, None])) < 1e-6
    assert np.allclose(np.mean(prepared.signals, axis=1, dtype=float), 0.0, atol=1e-7)
    assert np.allclose(np.mean(prepared.signals.astype(float) ** 2, axis=1), 1.0, rtol=1e-6)


def test_decimated_record_is_the_centred_channels_filtered():
    # a record far above its band is centred and decimated channel by channel (no double copy of the whole
    # record): the same numbers as centring the whole record and filtering it at once
    from scipy.signal import resample_poly

    signals = _record(n_channels=3, n_samples=40_000)
    prepared = prepare(signals, 1000.0, (1.0, 30.0))
    assert prepared.decimation == 8 and prepared.sample_rate_hz == 125.0
    reduced = resample_poly(signals - signals.mean(axis=1, keepdims=True), 1, 8, axis=1)
    centred = reduced - reduced.mean(axis=1, keepdims=True)
    rms = np.sqrt(np.mean(centred**2, axis=1))
    assert np.allclose(prepared.scale, rms, rtol=1e-12)
    # single-precision storage of samples within about 5 RMS, then the division by the RMS
    assert np.max(np.abs(prepared.signals - centred / rms[:, None])) < 1e-6


def test_bad_sample_of_a_record_to_be_decimated_is_named():
    signals = _record(n_channels=3, n_samples=40_000)
    signals[2, 1234] = np.nan
    with pytest.raises(ParameterError, match=r"channel 3, sample 1234: nan; expected finite samples \(1 are not\)"):
        prepare(signals, 1000.0, (1.0, 30.0))
