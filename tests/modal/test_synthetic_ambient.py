"""The ambient-record generator: exact sampled dynamics, noise, tones and the truth it reports."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from modal.errors import ParameterError
from modal.synthetic import (ambient_modal_response, ambient_response, chain_matrices,
                             modal_parameters_of_matrices)

FS = 100.0


def test_sampled_record_is_the_exact_zero_order_hold_discretisation():
    # One mode, accelerations, unit white forces held over each sample: the sampled system is
    # H(z) = N(z)/D(z) from the matrix exponential (scipy's ss2tf, independent of the generator), so
    # filtering the record by D(z) leaves exactly the moving average N(z) of white noise: its correlations
    # are Σ c_j c_{j+k} up to lag 2 and zero beyond. A pole off by a part in 10⁴ leaves a resonant
    # remainder, a wrong hold gain other moving-average weights: both far beyond the tolerance.
    from scipy.signal import lfilter, ss2tf

    wn, zeta, n = 2 * np.pi * 6.0, 0.02, 200_000
    rec = ambient_modal_response([6.0], [zeta], [[1.0]], FS, n, noise=0.0, seed=5)
    A = np.array([[0.0, 1.0], [-wn**2, -2 * zeta * wn]])
    aug = expm(np.block([[A, np.array([[0.0], [1.0]])], [np.zeros((1, 3))]]) / FS)
    num, den = ss2tf(aug[:2, :2], aug[:2, 2:], np.array([[-wn**2, -2 * zeta * wn]]), np.array([[1.0]]))
    e = lfilter(den, [1.0], rec.signals[0])[10:]
    c = num[0]
    expected = np.array([c[: c.size - k] @ c[k:] for k in range(c.size)] + [0.0] * 3)
    sample = np.array([e[k:] @ e[: e.size - k] / (e.size - k) for k in range(expected.size)])
    # Bartlett: a sample correlation of a moving average scatters by √(Σ_m ρ_m² + ρ_{m+k} ρ_{m−k})/√N,
    # at most √(2 Σ ρ²)/√N; 5 of those
    sigma = np.sqrt(2 * np.sum(expected**2) / e.size)
    assert sigma < 0.01 * expected[0]
    assert np.all(np.abs(sample - expected) < 5 * sigma), (sample - expected) / sigma


def test_truth_is_the_matrices_poles_and_shapes():
    M, C, K = chain_matrices([1.0, 1.0, 1.0], [1e4, 1e4, 1e4], 0.02)
    rec = ambient_response(M, C, K, FS, 2000, noise=0.0, seed=0)
    wn, zeta = modal_parameters_of_matrices(M, C, K)
    assert np.allclose(rec.natural_frequency_hz, wn / (2 * np.pi), rtol=1e-12)
    assert np.allclose(rec.damping_ratio, 0.02, rtol=1e-9)
    w2, phi = np.linalg.eigh(K)  # M = I here: the undamped shapes
    for r in range(3):
        unit = phi[:, r] / phi[np.argmax(np.abs(phi[:, r])), r]
        assert np.allclose(rec.mode_shape[:, r], unit, atol=1e-10)


def test_noise_is_the_stated_fraction_of_each_channels_rms():
    shapes = np.array([[1.0, 0.5], [0.4, -1.0], [0.8, 0.9]])
    clean = ambient_modal_response([5.0, 12.0], [0.01, 0.02], shapes, FS, 50_000, noise=0.0, seed=4)
    noisy = ambient_modal_response([5.0, 12.0], [0.01, 0.02], shapes, FS, 50_000, noise=0.2, seed=4)
    ratio = np.std(noisy.signals - clean.signals, axis=1) / np.sqrt(np.mean(clean.signals**2, axis=1))
    # 50 000 Gaussian samples: the sample std scatters by 1/√(2·50 000) = 0.3 %
    assert np.allclose(ratio, 0.2, rtol=0.015)


def test_tones_are_sinusoids_of_the_stated_rms():
    shapes = np.array([[1.0], [0.5]])
    clean = ambient_modal_response([5.0], [0.02], shapes, FS, 20_000, noise=0.0, seed=2)
    toned = ambient_modal_response([5.0], [0.02], shapes, FS, 20_000, noise=0.0, tones_hz=[7.0], tone_rms=0.5,
                                   seed=2)
    tone = toned.signals - clean.signals
    t = np.arange(20_000) / FS
    basis = np.column_stack([np.sin(2 * np.pi * 7.0 * t), np.cos(2 * np.pi * 7.0 * t)])
    coef, *_ = np.linalg.lstsq(basis, tone.T, rcond=None)
    assert np.allclose(basis @ coef, tone.T, atol=1e-9)  # nothing but the 7 Hz sinusoid
    rms = np.sqrt(np.mean(clean.signals**2, axis=1))
    amplitude = np.hypot(*coef)
    assert np.all((amplitude / np.sqrt(2) >= 0.5 * 0.5 * rms - 1e-12) & (amplitude / np.sqrt(2) <= 0.5 * rms + 1e-12))
    assert toned.tone_frequency_hz.tolist() == [7.0]


def test_bad_parameters_are_refused():
    M, C, K = chain_matrices([1.0, 1.0], [1e4, 1e4], 0.02)
    with pytest.raises(ParameterError, match="tones_hz"):
        ambient_response(M, C, K, FS, 1000, tones_hz=[60.0])
    with pytest.raises(ParameterError, match="noise"):
        ambient_response(M, C, K, FS, 1000, noise=-0.1)
    with pytest.raises(ParameterError, match="quantity"):
        ambient_response(M, C, K, FS, 1000, quantity="strain")
    with pytest.raises(ParameterError, match="force_dofs"):
        ambient_response(M, C, K, FS, 1000, force_dofs=[5])
    with pytest.raises(ParameterError, match="damping_ratio"):
        ambient_modal_response([5.0], [0.0], [[1.0]], FS, 1000)
    with pytest.raises(ParameterError, match="one spring per mass"):
        chain_matrices([1.0, 1.0], [1e4])
