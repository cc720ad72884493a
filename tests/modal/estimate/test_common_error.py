"""The error every output of a hammer estimate shares, the force channel's noise (modal.estimate.common_error),
carried by the estimate's noise model."""
from __future__ import annotations

import warnings

import numpy as np

import modal
from modal.synthetic_time import DigitalModes, hammer_force

FS = 1024.0
POINTS = np.array([0.2, 0.8])  # two accelerometers on a pinned-pinned beam, the driving point first
SHAPE = np.sin(np.pi * np.outer(POINTS, [1, 2]))
PLANT = DigitalModes(np.array([40.0, 95.0]), np.array([0.02, 0.012]), np.array([0.5, 0.8]) * SHAPE / SHAPE[0], FS)


def _estimate(force, response, window="force"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return modal.estimate_frf(force, response, FS, impact=True, window=window, kind="accelerance")


def _three_hits():
    """(force, the plant's accelerations) of three hits 4 s apart, exact."""
    force = hammer_force(int(16 * FS), FS, 0.5 + 4.0 * np.arange(3))
    return force, PLANT.respond(force, "acceleration")


def test_the_force_noise_error_is_common_to_the_outputs_and_as_large_as_carried():
    # three hits, the force channel noisy (0.5 % of its peak), the responses nearly exact: each output's error
    # relative to its FRF is η, one for both; its power is the factor's Σ_r |P_rk|². Over 12 draws of the noise
    # and the 460 lines of 20-250 Hz, whose errors correlate over ~50 lines (the force window's 42 samples of
    # 2048), ~110 independent values: the mean power's ratio to the model is known to ±10 %, held within 30 %
    force, response = _three_hits()
    rng = np.random.default_rng(11)
    relative, carried = [], []
    for _ in range(12):
        noisy = force + 0.005 * force.max() * rng.standard_normal(force.size)
        quiet = response + 1e-6 * np.abs(response).max() * rng.standard_normal(response.shape)
        frf = _estimate(noisy, quiet)
        band = (frf.frequency_hz > 20) & (frf.frequency_hz < 250)
        exact = PLANT.frf(frf.frequency_hz[band], "accelerance")
        relative.append((frf.response[:, band] - exact) / exact)
        carried.append(np.sum(np.abs(frf.noise_model.relative_error[:, band]) ** 2, axis=0))
    relative, carried = np.array(relative), np.array(carried)
    # one error for both outputs: correlated by 1 but for the response noise near the driving point's
    # antiresonances and the error's second order (η ~ 2 %)
    correlation = np.vdot(relative[:, 0], relative[:, 1]) / np.sqrt(np.vdot(relative[:, 0], relative[:, 0]).real
                                                                   * np.vdot(relative[:, 1], relative[:, 1]).real)
    assert abs(correlation) > 0.95
    np.testing.assert_allclose(np.mean(np.abs(relative[:, 0]) ** 2) / np.mean(carried), 1.0, atol=0.3)


def test_hits_carry_it_with_one_output_too_and_continuous_records_do_not():
    force, response = _three_hits()
    rng = np.random.default_rng(3)
    noisy = force + 0.005 * force.max() * rng.standard_normal(force.size)
    assert _estimate(noisy, response + 1e-4 * rng.standard_normal(response.shape)).noise_model.relative_error is not None
    one = _estimate(noisy, response[0] + 1e-4 * rng.standard_normal(response.shape[1])).noise_model.relative_error
    assert one is not None and one.ndim == 2  # a roving join (modal.roving) keeps it; one channel's constants take it
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        continuous = modal.estimate_frf(noisy, response, FS, kind="accelerance")
    assert continuous.noise_model.relative_error is None


def test_a_hammer_without_a_force_window_carries_none():
    # a rectangular window keeps the force channel's noise over the whole record: no short support to factor
    # (its 2048 samples would make a Gram matrix of 2048² per hit), the line correlation carries it instead
    force, response = _three_hits()
    rng = np.random.default_rng(5)
    noisy = force + 0.005 * force.max() * rng.standard_normal(force.size)
    assert _estimate(noisy, response + 1e-4 * rng.standard_normal(response.shape), "rect").noise_model.relative_error \
        is None


def _rank(n_rows: int, n_lines: int, rank: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    left = rng.standard_normal((n_rows, rank)) * np.geomspace(1.0, 1e-3, rank)
    return left @ (rng.standard_normal((rank, n_lines)) + 1j * rng.standard_normal((rank, n_lines)))


def test_the_compressed_factor_carries_the_rows_covariance():
    # the factor's covariance Pᴴ P is the rows' rowsᴴ rows, but for singular values below FACTOR_TOLERANCE of the
    # largest (the bound below: what they could carry at most, relative): whether the random sketch holds the
    # rows' range at once (rank 40), has to double (rank 150 > 64, 128 columns), or is as wide as the rows (the
    # Gram matrix's exact path)
    from modal.estimate.common_error import FACTOR_TOLERANCE, compressed_factor

    for n_rows, rank in ((504, 40), (504, 150), (60, 30)):
        rows = _rank(n_rows, 1025, rank, seed=rank)
        factor = compressed_factor(rows)
        exact = rows.conj().T @ rows
        assert factor.shape[0] == rank
        error = np.linalg.norm(factor.conj().T @ factor - exact) / np.linalg.norm(exact)
        assert error < FACTOR_TOLERANCE**2 * n_rows


def test_a_factor_whose_gram_matrix_would_cost_seconds_is_not_formed():
    # 3 records of 16384 samples whose excitation window keeps 316 samples each: 948 rows of 8193 lines, a Gram
    # matrix of 7e9 products (7 s a hammer file, where the estimate itself takes 0.1 s), rows of 124 MB: left to
    # the line correlation, as a window longer than MAX_SUPPORT_FRACTION of a record is
    from modal.estimate.common_error import MAX_FACTOR_WORK, MAX_UNCOMPRESSED_BYTES, common_error_factor

    length = 16384
    window = np.zeros(length)
    window[:316] = 1.0
    excitation = np.random.default_rng(2).standard_normal(3 * length)
    starts = np.arange(3) * length
    assert 948**2 * (length // 2 + 1) > MAX_FACTOR_WORK and 948 * (length // 2 + 1) * 16 > MAX_UNCOMPRESSED_BYTES
    assert common_error_factor(excitation, starts, length, window, 1.0) is None
    # records of 2048 samples (1025 lines) keeping 200 (600 rows: 4e8 products, within MAX_SUPPORT_FRACTION) are
    short = common_error_factor(excitation, np.arange(3) * 2048, 2048, np.r_[np.ones(200), np.zeros(1848)], 1.0)
    assert short is not None and short.shape[1] == 1025


def test_four_hits_of_eight_seconds_report_their_constants_errors():
    # 4 hits, 8 s records at 1024 Hz, force window (138 samples): 552 rows of 4097 lines, over MAX_FACTOR_WORK (a
    # Gram matrix of 0.7 s); without the factor the force noise's gain error near each mode, which the modal
    # constants (and k, c, m) absorb whole, was left out of their errors: |error| / reported error had a root mean
    # square of 11.6 over these 20 records and both modes. The rows themselves are the factor (36 MB, only the
    # fit bands' lines used). Calibrated, the mean square of |e|/s is 1 (40 values of unit mean and variance:
    # standard error of the root mean square 0.08); held within 0.75-1.3
    system = DigitalModes([12.0, 31.0], [0.02, 0.015], [[1.0, 0.6], [0.5, -0.8]], 1024.0)
    fs = 1024.0
    n = int(33.5 * fs)
    force = hammer_force(n, fs, [0.5, 8.5, 16.5, 24.5], amplitude_n=100.0)
    response = system.respond(force)
    ratios = []
    for seed in range(20):
        rng = np.random.default_rng(seed)
        measured = response + 1e-4 * np.abs(response).max() * rng.standard_normal(response.shape)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            estimate = modal.estimate_frf(force + 0.2 * rng.standard_normal(n), measured, fs, impact=True,
                                          window="force")
            result = modal.identify(estimate)
        assert estimate.noise_model.relative_error is not None
        for k, fn in enumerate((12.0, 31.0)):
            mode = min(result, key=lambda m: abs(m.natural_frequency_hz - fn))
            error = np.atleast_1d(mode.modal_constant)[0] - system.modal_constant[0, k]
            ratios.append(abs(error) / np.atleast_1d(mode.std.modal_constant)[0])
    assert 0.75 <= float(np.sqrt(np.mean(np.square(ratios)))) <= 1.3, np.sqrt(np.mean(np.square(ratios)))
