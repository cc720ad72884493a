"""The noise model an estimate from time records carries: line correlation, lag window, averages."""
from __future__ import annotations

import numpy as np
import pytest

import modal
from modal.errors import FRFValidationError
from modal.estimate.error_correlation import LEAKAGE_LAGS
from modal.estimate.windows import segment_window
from modal.noise_model import NoiseModel, lag_window, window_line_correlation
from modal.synthetic_time import DigitalModes, impact_record, random_record

FS = 1024.0


@pytest.fixture(scope="module")
def plant():
    return DigitalModes(np.array([40.0, 95.0]), np.array([0.02, 0.012]), np.array([0.5, 0.8]), FS)


def _errors(make, seeds, plant):
    """Errors Ĥ − E[Ĥ] over seeds (the mean over the seeds stands for E[Ĥ]) normalised per line, and the model."""
    estimates = [make(seed) for seed in range(seeds)]
    response = np.array([e.response for e in estimates])
    errors = response - response.mean(axis=0)
    return errors / np.sqrt(np.mean(np.abs(errors) ** 2, axis=0)), estimates[0]


def test_hann_window_correlates_neighbouring_lines_by_four_ninths(plant):
    """H1 from white excitation through a periodic Hann window: each record's noise and excitation lines
    correlate by c(1) = −2/3 and c(2) = 1/6, so the estimate's errors by c(m)², 4/9 and 1/36."""
    def make(seed):
        rec = random_record(plant, 32.0, response_noise=0.3, seed=seed).record
        return modal.estimate_frf(rec.signals[0], rec.signals[1], FS, window="hann", segment_length=1024)

    errors, first = _errors(make, 16, plant)
    model = first.noise_model
    f = first.frequency_hz
    away = (f > 150) & (f < 450)  # far from the modes: the measurement noise alone
    # 63 records: the correlation is measured over them (modal.estimate.error_correlation), over Hann's two
    # lags and the leakage's four; away from the modes it is the window's (within 0.02 over 300 lines)
    assert model.n_lags == LEAKAGE_LAGS and model.averages == first.averages
    np.testing.assert_allclose(model.line_correlation[:, away].mean(axis=1), [4 / 9, 1 / 36, 0, 0], atol=0.02)
    # what the seeds show (E[e_k e*_{k+1}]; 16 seeds × 300 lines, correlated: standard error ≈ 0.017, 3 of them)
    measured = np.mean(errors[:, :-1][:, away[:-1]] * np.conj(errors[:, 1:][:, away[:-1]]))
    assert abs(measured - 4 / 9) < 0.05


def test_exponential_window_correlation_matches_the_hits(plant):
    """An exponential window (τ = 0.5 s on 2 s records) correlates lines over many lags, with a phase: the
    model from the windows and the recorded hits matches what repeated tests show, lag by lag."""
    def make(seed):
        hits = 0.5 + 4.0 * np.arange(4)
        rec = impact_record(plant, hits, 16.5, amplitude_variation=0.2, response_noise=0.002, force_noise=0.002,
                            seed=seed).record
        return modal.estimate_frf(rec.signals[0], rec.signals[1], FS, impact=True, window="exponential",
                                  exponential_decay_s=0.5)

    errors, first = _errors(make, 16, plant)
    model = first.noise_model
    f = first.frequency_hz
    away = (f > 150) & (f < 300)
    assert model.n_lags > 10  # the window's correlation reaches far
    for m in (1, 2, 4):
        predicted = model.line_correlation[m - 1, away].mean()
        measured = np.mean(errors[:, :-m][:, away[:-m]] * np.conj(errors[:, m:][:, away[:-m]]))
        # 16 seeds × 150 correlated lines: standard error below 0.04; 0.1 is 2.5 of them at most
        assert abs(measured - predicted) < 0.1, (m, predicted, measured)


def test_lag_window_of_a_rectangular_window_on_stationary_excitation():
    """ρ(τ) = 1 − τ/N exactly for a rectangular window and an excitation of constant mean square."""
    n = 256
    rho = lag_window(np.ones(n), np.ones(n), np.full(n, 2.0))
    np.testing.assert_allclose(rho, 1 - np.arange(n) / n, atol=1e-12)
    hann = segment_window("hann", n)
    c = window_line_correlation(hann)
    np.testing.assert_allclose(c[:3].real, [1, -2 / 3, 1 / 6], atol=1e-12)


def test_estimates_carry_their_model_through_cropping(plant):
    rec = random_record(plant, 32.0, response_noise=0.05, seed=1).record
    frf = modal.estimate_frf(rec.signals[0], rec.signals[1], FS, window="hann", segment_length=1024)
    cropped = frf.cropped(30.0, 60.0)
    keep = (frf.frequency_hz >= 30) & (frf.frequency_hz <= 60)
    lags = frf.noise_model.n_lags
    np.testing.assert_array_equal(cropped.noise_model.line_correlation[:, :-lags],
                                  frf.noise_model.line_correlation[:, keep][:, :-lags])
    assert np.all(cropped.noise_model.line_correlation[0, -1:] == 0)  # no neighbour past the last line
    assert np.all(cropped.noise_model.line_correlation[1, -2:] == 0)
    plain = modal.FRF(frf.frequency_hz, frf.response)
    assert plain.noise_model is None


def test_correlation_band_matches_the_dense_matrix():
    corr = np.zeros((3, 30), complex)
    corr[0, :-1], corr[1, :-2], corr[2, :-3] = 0.4 + 0.1j, 0.1, -0.05j
    model = NoiseModel(3, 2.0, corr, None, 1e-3)
    lines = np.array([0, 1, 2, 3, 5, 6, 10, 11, 12, 20, 21])
    band = model.correlation_band(lines)
    dense = np.eye(lines.size, dtype=complex)
    for i, a in enumerate(lines):
        for j, b in enumerate(lines):
            if 1 <= b - a <= 3:
                dense[i, j] = corr[b - a - 1, a]
                dense[j, i] = np.conj(dense[i, j])
    for d in range(band.shape[0]):
        np.testing.assert_array_equal(band[d, :lines.size - d], np.diagonal(dense, -d))


def test_bad_noise_models_are_refused():
    with pytest.raises(FRFValidationError, match="line_correlation"):
        NoiseModel(3, 2.0, np.full((1, 4), 2.0), None, 1e-3)
    with pytest.raises(FRFValidationError, match="noise_model"):
        modal.FRF(np.arange(1.0, 6.0), np.ones(5), noise_model=NoiseModel(3, 2.0, np.zeros((1, 4)), None, 1e-3))
    with pytest.raises(FRFValidationError, match="variance_model"):
        NoiseModel(3, 2.0, None, None, 1e-3, np.array([1.0, -1.0]))
    with pytest.raises(FRFValidationError, match="variance model over 4 lines"):
        modal.FRF(np.arange(1.0, 6.0), np.ones(5), noise_model=NoiseModel(3, 2.0, None, None, 1e-3, np.ones(4)))
    # the model of the lines kept, per line; lines reordered take their variances with them
    with pytest.warns(modal.ModalWarning, match="sorted"):
        frf = modal.FRF(np.array([3.0, 1.0, 2.0]), np.ones(3),
                        noise_model=NoiseModel(3, 2.0, None, None, 1e-3, np.array([30.0, 10.0, np.nan])))
    np.testing.assert_array_equal(frf.noise_model.variance_model, [10.0, np.nan, 30.0])


def test_force_noise_correlates_the_peak_lines_through_the_force_window(plant):
    """A hammer test's force noise enters H1 as −H N_x X*/S_xx: at the peak it is most of the error, and it
    correlates through the short force window (nearly the same on neighbouring lines) with H's phase. The model
    splits each line's error power into a + b|H|² and mixes the two correlations; at lag 1 the response noise's
    alone says 0.66 + 0.42i, the seeds show 0.88 + 0.27i."""
    def make(seed):
        hits = 0.5 + 4.0 * np.arange(6)
        rec = impact_record(plant, hits, 24.5, response_noise=0.002, force_noise=0.002, seed=seed).record
        return modal.estimate_frf(rec.signals[0], rec.signals[1], FS, impact=True, window="exponential",
                                  exponential_decay_s=0.5, kind="accelerance")

    errors, first = _errors(make, 24, plant)
    model = first.noise_model
    f = first.frequency_hz
    peak = np.abs(f - 40.0) <= 2.0  # within the half-power band of the 40 Hz mode (ζ 2 % + the window's)
    assert model.variance_model is not None
    for m in (1, 3, 6):
        lines = np.flatnonzero(peak)
        predicted = model.line_correlation[m - 1, lines].mean()
        measured = np.mean(errors[:, lines] * np.conj(errors[:, lines + m]))
        # 24 seeds (less their mean) × 9 correlated lines: standard error about 0.05; 0.12 is 2.4 of them
        assert abs(measured - predicted) < 0.12, (m, predicted, measured)


def test_input_noise_split_recovers_both_noise_powers():
    """Residual powers a + b|H|² scattered as a chi-square of 10 degrees of freedom (6 hits) over 2000 lines:
    a and b come back within 5 % (their standard errors are about 1 %: a rests on the ~1000 lines where
    |H|² is small, b on the ~1000 where it is large, each line 1/sqrt(5) = 45 % scatter)."""
    from modal.noise_model import input_noise_split

    rng = np.random.default_rng(5)
    h = 10.0 ** rng.uniform(-3, 3, 2000)  # |H|² over six decades, as across peaks and anti-resonances
    a, b = 2.0, 0.5
    residual = (a + b * h) * rng.chisquare(10, h.size) / 10
    fitted = input_noise_split(residual, h)
    np.testing.assert_allclose(fitted, (a, b), rtol=0.05)
    # without excitation noise: b comes out near zero (one in a thousand of the response noise at |H|² = 1)
    fitted = input_noise_split(a * rng.chisquare(10, h.size) / 10, h)
    assert abs(fitted[0] - a) < 0.05 * a and fitted[1] < 1e-3 * a
    # fitted on the lines it is told to: the others, whatever they hold, do not count
    spoiled = residual.copy()
    spoiled[:100] *= 50
    lines = np.ones(h.size, bool)
    lines[:100] = False
    np.testing.assert_allclose(input_noise_split(spoiled, h, lines), (a, b), rtol=0.05)


def test_a_change_of_kind_scales_the_variance_model_as_the_data(plant):
    """The variance model is in the FRF's unit squared: accelerance converted to receptance divides it by ω⁴,
    as the estimator does when it gives receptance from the same accelerations. It was left in (m/s²/N)²:
    the converted FRF's noise shape was then off by ω⁴ (10⁸ at 100 Hz) against its own noise_std."""
    hits = 0.5 + 4.0 * np.arange(6)
    rec = impact_record(plant, hits, 24.5, response_noise=0.002, force_noise=0.002, seed=3).record

    def estimate(kind):
        return modal.estimate_frf(rec.signals[0], rec.signals[1], FS, impact=True, window="exponential",
                                  exponential_decay_s=0.5, response_quantity="acceleration", kind=kind)

    accelerance = estimate("accelerance")
    assert accelerance.noise_model.variance_model is not None
    converted = accelerance.cropped(0.5, FS / 2).as_kind("receptance")
    direct = estimate("receptance")  # the model of the converted data, from the estimator itself
    np.testing.assert_array_equal(converted.frequency_hz, direct.frequency_hz)
    # the same numbers up to rounding (both are the accelerance model times |2πf|⁻⁴)
    np.testing.assert_allclose(converted.noise_model.variance_model, direct.noise_model.variance_model,
                               rtol=1e-10, equal_nan=True)
    # and the model keeps its ratio to the converted lines' own noise (both are variances of one unit)
    held = np.isfinite(converted.noise_model.variance_model)
    np.testing.assert_allclose((converted.noise_model.variance_model / converted.noise_std ** 2)[held],
                               (accelerance.noise_model.variance_model[1:] / accelerance.noise_std[1:] ** 2)[held],
                               rtol=1e-10)


def test_several_outputs_carry_the_noise_shape_they_share():
    """One force, three accelerometers: each channel's error variance is (a_o + b|H_o|²)/S_xx, the response
    noise's part in one shape for all and the force noise's in each channel's own. The variance model is the
    shared part, a/S_xx with a the channels' mean: without force noise it is the channels' mean noise variance
    (each line's from 6 hits, 5 degrees of freedom, 3 channels, over ~400 lines: the mean ratio is known to ~3 %;
    held within 10 %); with it, at the 40 Hz peak, where the force noise is most of the error, it is far below
    that (it was None: the line weights then took the peaks' force noise)."""
    shape = np.sin(np.pi * np.outer([0.2, 0.35, 0.8], [1, 2]))
    structure = DigitalModes(np.array([40.0, 95.0]), np.array([0.02, 0.012]), 0.5 * shape / shape[0], FS)
    hits = 0.5 + 4.0 * np.arange(6)

    def estimate(force_noise):
        rec = impact_record(structure, hits, 24.5, response_noise=0.002, force_noise=force_noise, seed=4).record
        return modal.estimate_frf(rec.signals[0], rec.signals[1:], FS, impact=True, window="exponential",
                                  exponential_decay_s=0.5, kind="accelerance")

    quiet_force = estimate(0.0)
    shared = quiet_force.noise_model.variance_model
    assert shared is not None and shared.shape == quiet_force.frequency_hz.shape
    f = quiet_force.frequency_hz
    lines = (f > 5) & (f < 400)
    assert abs(np.mean(np.mean(quiet_force.noise_std**2, axis=0)[lines] / shared[lines]) - 1) < 0.1
    noisy_force = estimate(0.002)
    peak = np.abs(f - 40.0) <= 0.5
    assert np.all(np.mean(noisy_force.noise_std**2, axis=0)[peak] > 3 * noisy_force.noise_model.variance_model[peak])


def test_the_two_coefficient_nonnegative_fit_is_scipys_nnls():
    # input_noise_split's fit does without scipy.optimize (its import cost a time-record fit 0.4 CPU-s): the
    # same minimum as nnls, with either, both or neither coefficient held at 0 (the problem is strictly
    # convex with two independent columns, so its minimiser is unique: equal to the solvers' rounding)
    from scipy.optimize import nnls

    from modal.noise_model import _nonnegative_fit, _nonnegative_fit_of_sums

    rng = np.random.default_rng(7)
    held = set()
    for _ in range(300):
        # the |H|² column is 1e-10 to 1e-16 of the constant one in a receptance hammer test (in m/N): far apart
        scale = 10.0 ** rng.uniform(-20, 2)
        design = np.column_stack([np.ones(40), scale * rng.exponential(1.0, 40) ** 3]) * rng.exponential(1.0, (40, 1))
        target = design @ (rng.normal(0.0, 1.0, 2) / [1.0, scale]) + rng.normal(0.0, 0.3, 40)
        expected, _ = nnls(design, target)
        fitted = np.array(_nonnegative_fit(design, target))
        assert np.all(fitted >= 0)
        np.testing.assert_allclose(fitted, expected, rtol=1e-9, atol=1e-12 * np.abs(target).max())
        # input_noise_split's rounds solve it from the sums alone (normal equations of the unit-scaled columns,
        # rounding ~1e-16 / (1 - rho^2) relative, used while 1 - rho^2 >= 1e-6)
        sums = np.array([design[:, 0] @ design[:, 0], design[:, 0] @ design[:, 1], design[:, 1] @ design[:, 1],
                         design[:, 0] @ target, design[:, 1] @ target, target @ target])
        from_sums = _nonnegative_fit_of_sums(sums)
        if from_sums is not None:
            np.testing.assert_allclose(from_sums, expected, rtol=1e-9, atol=1e-12 * np.abs(target).max())
        held.add(tuple(expected == 0))
    assert held == {(False, False), (True, False), (False, True), (True, True)}  # every active set was met


def test_input_noise_split_is_the_same_in_any_unit():
    # a receptance in m/N makes |H|² ~1e-12 and residual powers ~1e-20 or less: the fit (squared weights, sums
    # of their products) must neither overflow nor lose the small column, so scaling the residual by s and |H|²
    # by u scales a by s and b by s/u, to rounding; the response-noise-only case (b = 0) included
    from modal.noise_model import input_noise_split

    rng = np.random.default_rng(11)
    h = rng.exponential(1.0, 4000) ** 4
    for a, b in ((1.0, 0.3), (0.0, 2.0), (1.0, 0.0)):
        residual = (a + b * h) * rng.chisquare(8, h.size) / 8
        reference = np.array(input_noise_split(residual, h))
        assert reference[0] >= 0 and reference[1] >= 0 and (b == 0) == (reference[1] < 0.05 * max(b, 1.0))
        for s, u in ((1e-30, 1e-24), (1e20, 1e-24), (1e-30, 1e10), (1e60, 1e-60)):
            scaled = np.array(input_noise_split(residual * s, h * u))
            np.testing.assert_allclose(scaled, reference * [s, s / u], rtol=1e-9, atol=1e-12 * s * reference.max())


def test_large_arrays_are_copied_once_then_shared_by_derived_models():
    from dataclasses import replace

    influence = np.ones((552, 4097), complex)  # records' influences of 36 MB
    model = NoiseModel(4, 3.0, None, None, 1e-3, record_influence=influence)
    assert model.record_influence is not influence and influence.flags.writeable  # the caller's array is left alone
    assert not model.record_influence.flags.writeable
    derived = replace(model, averages=5)  # every crop or scaling of an FRF makes one: no 36 MB copy each time
    assert derived.record_influence is model.record_influence
    with pytest.raises(FRFValidationError, match="field 'record_influence' must be a finite array of records"):
        NoiseModel(4, 3.0, None, None, 1e-3, record_influence=np.full((2, 5), np.nan))
    # the excitation's shared error is what generates its covariance (modal.shared_error), not a factor
    with pytest.raises(FRFValidationError, match="field 'relative_error' is a ndarray; expected a CommonError"):
        NoiseModel(4, 3.0, None, None, 1e-3, relative_error=np.ones((2, 5), complex))
