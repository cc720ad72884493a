"""The errors' line correlation measured over the records of a continuous estimate
(modal.estimate.error_correlation), against the errors' own over many records."""
from __future__ import annotations

import numpy as np
import pytest

import modal
from modal.estimate.error_correlation import measured_line_correlation
from modal.synthetic import DigitalModes, random_record
from modal.whitening import LineWhitening

FS = 1024.0
#: the structure of benchmarks/bench_chain.py: decay times 0.2 s and 0.14 s against 8 s Hann segments
PLANT = DigitalModes([40.0, 95.0], [0.02, 0.012], [0.5, 0.8], FS)
RECORDS = 60


@pytest.fixture(scope="module")
def estimates():
    out = []
    for seed in range(RECORDS):
        rec = random_record(PLANT, 120.0, response_noise=0.05, seed=seed)
        out.append(modal.estimate_frf(rec.record.signals[0], rec.record.signals[1], FS, window="hann",
                                      kind="accelerance"))
    return out


def test_whitened_errors_at_the_peaks_are_white(estimates):
    # the error of each line against the records' mean (the window's bias is the same in every record),
    # whitened with each record's own correlation: near the peaks most of the error is leakage, which the
    # window's model (+0.44 between neighbouring lines) does not describe: whitened with it the errors kept
    # a lag-one correlation of −0.3 to −0.4 and 1.26–1.34 times their variance
    f = estimates[0].frequency_hz
    response = np.array([e.response for e in estimates])
    sigma = np.sqrt(np.mean([e.noise_std**2 for e in estimates], axis=0))
    errors = (response - response.mean(axis=0)) / sigma
    for low, high in ((35.0, 45.0), (88.0, 102.0)):
        lines = np.flatnonzero((f >= low) & (f <= high))
        white = np.array([LineWhitening(e.noise_model.correlation_band(lines))(err[lines][:, None])[:, 0]
                          for e, err in zip(estimates, errors)])
        variance = np.mean(np.abs(white) ** 2)
        lag_one = np.mean(white[:, :-1].conj() * white[:, 1:]).real / variance
        # 60 records × 80–112 lines: the lag-one correlation of white errors is within ±0.015 (one standard
        # error, 1/√(2 · 4800)); the variance within ±2 % (1/√4800), besides the records' mean taken out
        # (1/60 of it); ±0.1 and 0.85–1.15 leave the measured correlation's own scatter (±0.07 per line) room
        assert abs(lag_one) < 0.1, (low, lag_one)
        assert 0.85 < variance < 1.15, (low, variance)


def test_few_records_keep_the_windows_model():
    rec = random_record(PLANT, 16.0, response_noise=0.05, seed=0)
    est = modal.estimate_frf(rec.record.signals[0], rec.record.signals[1], FS, window="hann", segment_length=4096,
                             kind="accelerance")
    assert est.averages < 16
    assert est.noise_model.n_lags == 2  # Hann's two lags, from the window: 6 records do not measure them


def test_measured_correlation_of_white_records_is_the_windows():
    # white excitation and white response noise only (no structure): the errors' correlation is the
    # window's, 4/9 between neighbouring Hann lines (the excitation's own correlation, 2/3 squared)
    rng = np.random.default_rng(3)
    x = rng.standard_normal(64 * 1024)
    y = 0.5 * x + rng.standard_normal(x.size)
    est = modal.estimate_frf(x, y, FS, window="hann", segment_length=1024)
    lag_one = est.noise_model.line_correlation[0, 10:-10]
    # 127 records, 5 lines averaged: ±0.04 per line; the mean over 490 lines within ±0.02 of 4/9
    assert abs(np.mean(lag_one.real) - 4 / 9) < 0.02, np.mean(lag_one.real)
    assert measured_line_correlation(np.zeros((4, 3, 5), complex), np.ones(5), 8) is None  # too few records
