"""Correlations by FFT per block, the references chosen, the decimation to the band."""
from __future__ import annotations

import numpy as np
import pytest

from modal.operational.correlations import choose_references, correlations, decimation_factor
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
