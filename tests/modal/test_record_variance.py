"""The parameters' covariance measured over the records (modal.record_variance), against the Monte-Carlo
covariance of the same estimates."""
from __future__ import annotations

import numpy as np
import pytest

from modal.nls import fit_modes
from modal.record_variance import MIN_EFFECTIVE_RECORDS, misfit_ratio, projected_scores, record_covariance
from modal.whitening import LineWhitening

#: Monte-Carlo trials: a variance from T trials has relative standard error √(2/T) (3.2 % at 2000)
TRIALS = 2000


def _smoothed(rng, n_records, n_lines, smooth_lines, complex_=False):
    """White terms (n_records, n_lines) averaged over ``smooth_lines`` neighbouring lines, unit variance: every
    line correlates with its neighbours far beyond one lag."""
    shape = (n_records, n_lines + smooth_lines - 1)
    white = rng.standard_normal(shape) + (1j * rng.standard_normal(shape) if complex_ else 0)
    return sum(white[:, k:k + n_lines] for k in range(smooth_lines)) / np.sqrt(smooth_lines)


def _records(rng, n_records, n_lines, smooth_lines, shared=0.0, complex_=False):
    """Each record's error (n_records, n_lines), line-correlated; neighbouring records correlate by ``shared``
    (u_i = (b_i + c b_{i+1}) / √(1 + c²), c/(1 + c²) = ``shared``), as overlapping records share samples."""
    if not shared:
        return _smoothed(rng, n_records, n_lines, smooth_lines, complex_)
    c = (1 - np.sqrt(1 - 4 * shared**2)) / (2 * shared)
    terms = _smoothed(rng, n_records + 1, n_lines, smooth_lines, complex_)
    return (terms[:-1] + c * terms[1:]) / np.sqrt(1 + c**2)


def _linear_trials(rng, n_records, n_lines, shared, trials):
    """A linear fit y = A θ + Σ_i u_i over ``trials`` draws: the observed variance of θ̂ and each draw's
    scores Aᵀψ_i, the records' terms estimated as u_i − ū (they sum to zero, as an H1 estimate's residuals do)."""
    lines = np.linspace(-1, 1, n_lines)
    design = np.column_stack([np.ones(n_lines), lines, lines**2])
    information = design.T @ design
    terms = np.array([_records(rng, n_records, n_lines, 9, shared) for _ in range(trials)])
    observed = np.var(np.linalg.solve(information, design.T @ terms.sum(axis=1).T), axis=1)
    scores = np.einsum("lp,tnl->tpn", design, terms - terms.mean(axis=1, keepdims=True))
    return information, observed, scores


def test_measured_covariance_of_a_linear_fit_matches_monte_carlo():
    # independent records whose errors correlate over 9 lines: the sum over the records is exact
    information, observed, scores = _linear_trials(np.random.default_rng(1), 29, 60, 0.0, TRIALS)
    reported = np.mean([np.diag(record_covariance(information, score, 0)) for score in scores], axis=0)
    # the observed variance errs by √(2/T) = 3.2 %, the mean reported one by less (each from 29 records,
    # ~25 % each, averaged over T): 4 standard errors of the observed
    np.testing.assert_allclose(reported, observed, rtol=4 * np.sqrt(2 / TRIALS))


@pytest.mark.parametrize("shared", [0.3, -0.3])
def test_overlapping_records_enter_with_bartletts_weight(shared):
    # neighbours correlated by ρ: the sum's variance is (1 + 2ρ) times the records' (to 1/n); Bartlett's
    # weight 1/2 on the cross terms reports (1 + ρ) of it, the records alone 1
    information, observed, scores = _linear_trials(np.random.default_rng(2), 29, 40, shared, TRIALS)
    with_cross = np.mean([np.diag(record_covariance(information, score, 1)) for score in scores], axis=0)
    without = np.mean([np.diag(record_covariance(information, score, 0)) for score in scores], axis=0)
    n = 29
    truth = 1 + 2 * shared * (n - 1) / n
    tolerance = 4 * np.sqrt(2 / TRIALS)
    np.testing.assert_allclose(with_cross / observed, (1 + shared * (n - 1) / n) / truth, rtol=tolerance)
    # the records alone (the overlap ignored) report 1/(1 + 2ρ) of it: the cross terms halve that error
    np.testing.assert_allclose(without / observed, 1 / truth, rtol=tolerance)
    assert np.all(np.abs(with_cross / observed - 1) < np.abs(without / observed - 1))


def test_nls_covariance_from_records_matches_monte_carlo_of_the_fit():
    # one mode fitted by fit_modes with a line weight and a whitening that is not the errors' own: the
    # records' influences go through the same transformations as the data, so the reported covariance is
    # the fit's actual one; the Fisher information (lines taken as independent) is not
    rng = np.random.default_rng(3)
    omega = np.linspace(2 * np.pi * 90, 2 * np.pi * 110, 81)
    wn, zeta, constant = 2 * np.pi * 100, 0.02, 1.0 + 0.3j
    exact = constant / (wn**2 - omega**2 + 2j * zeta * wn * omega)
    level = 0.03 * np.abs(exact).max()
    weight = 1.0 + 0.5 * np.cos(np.linspace(0, 3, omega.size))
    band = np.zeros((3, omega.size), complex)
    band[0], band[1, :-1], band[2, :-2] = 1.0, 0.3, 0.05
    whitening = LineWhitening(band)
    n_records = 30
    fitted, reported, fisher = [], [], []
    for _ in range(400):
        terms = level * _records(rng, n_records, omega.size, 7, complex_=True) / np.sqrt(n_records)
        data = exact + terms.sum(axis=0)
        influence = terms - terms.mean(axis=0)
        fit = fit_modes(omega, data[None], 0, [wn], [zeta], region=np.zeros(omega.size, int), line_weight=weight,
                        whitening=whitening, record_influence=influence)
        assert fit.record_errors
        fitted.append([fit.omega_n[0], fit.damping_ratio[0]])
        reported.append([fit.mode_cov[0, 0, 0, 0], fit.mode_cov[0, 0, 1, 1]])
        if len(fisher) < 20:  # the same fit's Fisher covariance (it scatters little from fit to fit)
            plain = fit_modes(omega, data[None], 0, [wn], [zeta], region=np.zeros(omega.size, int),
                              line_weight=weight, whitening=whitening)
            assert not plain.record_errors
            fisher.append([plain.mode_cov[0, 0, 0, 0], plain.mode_cov[0, 0, 1, 1]])
    observed = np.var(np.array(fitted), axis=0)
    # 400 fits: the observed variance within ±7 % (1 SE, √(2/400)); 3.5 SE (over seeds 3, 10, 11, 12 the ratio
    # was 0.85–1.17)
    np.testing.assert_allclose(np.mean(reported, axis=0), observed, rtol=0.25)
    # the errors correlate over 7 lines: the Fisher covariance, blind to it, is off by far more (0.15–0.2)
    assert np.all(np.abs(np.mean(fisher, axis=0) / observed - 1) > 0.4)


def test_projected_scores_are_the_real_stacked_jacobian_products():
    rng = np.random.default_rng(4)
    derivatives = rng.standard_normal((12, 2)) + 1j * rng.standard_normal((12, 2))
    coefficients = np.array([0.5 - 1j, 2 + 0.1j])
    influence = rng.standard_normal((12, 3)) + 1j * rng.standard_normal((12, 3))
    # the residual's Jacobian column j is −E_j c_j; real-stacked, Jᵀδ = −(Re J·Re δ + Im J·Im δ)
    jacobian = -derivatives * coefficients
    stacked = np.vstack([jacobian.real, jacobian.imag])
    expected = -stacked.T @ np.vstack([influence.real, influence.imag])
    np.testing.assert_allclose(projected_scores(derivatives, coefficients, influence), expected, atol=1e-12)


def test_too_few_records_or_a_singular_sum_give_none():
    rng = np.random.default_rng(5)
    information = np.eye(2)
    assert record_covariance(information, rng.standard_normal((2, MIN_EFFECTIVE_RECORDS)), 0) is None
    assert record_covariance(information, rng.standard_normal((2, 30)), 0) is not None
    # every record's score along one direction: the sum of products is singular
    scores = np.outer([1.0, 2.0], rng.standard_normal(30))
    assert record_covariance(information, scores, 0) is None
    assert record_covariance(information, np.full((2, 30), np.nan), 0) is None


def test_misfit_ratio_is_one_without_misfit_and_grows_with_one():
    # the residual of a linear fit against the records' errors projected off the design: their ratio is 1
    # on average where the model holds (over 500 draws its mean is within ±2 %), and grows by the misfit's
    # share where the data hold a term the model leaves out (a ripple as large as the errors: about twice)
    rng = np.random.default_rng(6)
    n_records, n_lines = 29, 60
    lines = np.linspace(-1, 1, n_lines)
    design = np.column_stack([np.ones(n_lines), lines])
    basis, _ = np.linalg.qr(design)
    ripple = np.cos(4 * np.pi * lines)
    ripple -= basis @ (basis.T @ ripple)  # the part of it no fit of the design takes out
    misfit = np.sqrt(n_records) * ripple / np.sqrt(np.mean(ripple**2))  # as large as the errors (29 unit terms)
    ratios, with_misfit, error_power = [], [], []
    for _ in range(500):
        terms = _records(rng, n_records, n_lines, 5)
        off = (terms - terms.mean(axis=0)).T
        off = off - basis @ (basis.T @ off)
        residual = terms.sum(axis=0) - basis @ (basis.T @ terms.sum(axis=0))
        error_power.append(float(residual @ residual))
        ratios.append(misfit_ratio(error_power[-1], off, 0))
        residual = residual + misfit
        with_misfit.append(misfit_ratio(float(residual @ residual), off, 0))
    assert abs(np.mean(ratios) - 1) < 0.05
    # the misfit's power over the errors' (the ratio's own scatter, ~1/√29 each, adds a few per cent: 10 %)
    expected = 1 + float(misfit @ misfit) / np.mean(error_power)
    assert abs(np.mean(with_misfit) / expected - 1) < 0.1


def test_nls_covariance_of_several_channels_from_records_matches_monte_carlo():
    # three channels of one mode whose errors are mostly one error in the mode's shape (a lightly damped mode's
    # leakage is: two shakers' errors near 95 Hz correlated by 0.97 between outputs), correlated over 7 lines,
    # plus a little of each channel's own: each channel's records' influences, projected through the fit and
    # summed over the channels record by record, give the fit's actual covariance; the channel sandwich, which
    # takes the channels' errors as independent (and the lines'), is off by far more
    rng = np.random.default_rng(6)
    omega = np.linspace(2 * np.pi * 90, 2 * np.pi * 110, 81)
    wn, zeta = 2 * np.pi * 100, 0.02
    constants = np.array([1.0, 0.6, -0.4]) * (1.0 + 0.3j)
    exact = constants[:, None] / (wn**2 - omega**2 + 2j * zeta * wn * omega)  # (3, n_freq)
    level = 0.03 * np.abs(exact[0]).max()
    n_records = 30
    fitted, reported, sandwich = [], [], []
    for _ in range(400):
        shared = _records(rng, n_records, omega.size, 7, complex_=True)  # (records, lines)
        own = _records(rng, 3 * n_records, omega.size, 1, complex_=True).reshape(3, n_records, omega.size)
        terms = level * (constants.real[:, None, None] * shared[None] + 0.3 * own) / np.sqrt(n_records)
        data = exact + terms.sum(axis=1)
        influence = terms - terms.mean(axis=1, keepdims=True)  # (channels, records, lines)
        fit = fit_modes(omega, data, 0, [wn], [zeta], region=np.zeros(omega.size, int), record_influence=influence)
        assert fit.record_errors
        fitted.append([fit.omega_n[0], fit.damping_ratio[0]])
        reported.append([fit.mode_cov[0, 0, 0, 0], fit.mode_cov[0, 0, 1, 1]])
        if len(sandwich) < 20:
            plain = fit_modes(omega, data, 0, [wn], [zeta], region=np.zeros(omega.size, int))
            sandwich.append([plain.mode_cov[0, 0, 0, 0], plain.mode_cov[0, 0, 1, 1]])
    observed = np.var(np.array(fitted), axis=0)
    # 400 fits: the observed variance within ±7 % (1 SE, √(2/400)), the reported one's mean from 30 records each
    # (~25 % a fit, averaged over 400) closer: 3.5 SE
    np.testing.assert_allclose(np.mean(reported, axis=0), observed, rtol=0.25)
    assert np.all(np.abs(np.mean(sandwich, axis=0) / observed - 1) > 0.4)
