"""The complex nonlinear least squares of modes (modal.nls)."""
import numpy as np

from modal.nls import fit_modes
from modal.synthetic import add_noise, modal_frf


def test_pole_covariance_leaves_undetermined_poles_undetermined():
    # a Fisher information with one direction the data do not determine (two parameters that enter only as
    # their sum): those two get NaN variances, the determined ones the inverse of their own block, as for a
    # regular matrix, where the result is its inverse (to the rounding of the diagonal scaling, a few ulp)
    from modal.nls import _pole_covariance

    regular = np.array([[4.0, 1.0], [1.0, 3.0]])
    np.testing.assert_allclose(_pole_covariance(regular), np.linalg.inv(regular), rtol=1e-14)
    u = np.array([1.0, 1.0])
    F = np.zeros((4, 4))
    F[:2, :2] = regular
    F[2:, 2:] = 5.0 * np.outer(u, u)  # rank one: only θ2 + θ3 is determined
    cov = _pole_covariance(F)
    assert np.all(np.isnan(cov[2:, :])) and np.all(np.isnan(cov[:, 2:]))
    np.testing.assert_allclose(cov[:2, :2], np.linalg.inv(regular), rtol=1e-12)


def test_residual_sum_of_squares_by_difference_matches_the_residual_it_stands_for():
    # many channels: each channel's residual sum of squares is ‖y‖² − ‖Qᴴy‖² (no product with every channel)
    # where that keeps 1e-4 of ‖y‖² (nls.RSS_BY_DIFFERENCE): the two sums' rounding, ~1e-15 of ‖y‖² (a few
    # hundred lines), is then below 1e-11 of the result. Exact data (residual at rounding) take the residual
    # itself: the difference would be rounding of either sign. The residual is formed for the rows asked
    f = np.linspace(20, 400, 761)
    rng = np.random.default_rng(4)
    const = rng.standard_normal((300, 2)) + 0.1j * rng.standard_normal((300, 2))
    exact = modal_frf(f, [100.0, 250.0], [0.02, 0.02], const)
    omega, region = exact.omega_rad_s, np.zeros(f.size, int)
    for frf, direct in ((add_noise(exact, 0.01, seed=5), False), (exact, True)):
        fit = fit_modes(omega, frf.channels, 0, 2 * np.pi * np.array([100.0, 250.0]), [0.02, 0.02], region=region)
        residual = fit.residual[:]
        rss = np.sum(np.abs(residual) ** 2, axis=1)
        dof = f.size - 3 - 4 / (2 * 300)
        energy = np.sum(np.abs(frf.channels) ** 2, axis=1)
        assert np.all(rss >= 1e-4 * energy) != direct
        if direct:  # rounding: the residual's own sum, to the last bits of the summation
            np.testing.assert_allclose(fit.noise_var, rss / dof, rtol=1e-12, atol=0)
        else:
            np.testing.assert_allclose(fit.noise_var, rss / dof, rtol=1e-10, atol=0)
        # the same rows formed alone: rounding of the fitted part, ~1e-16 of the data
        np.testing.assert_allclose(fit.residual[[3, 7]], residual[[3, 7]], rtol=0,
                                   atol=1e-13 * np.abs(frf.channels).max())


def test_orthonormal_factor_of_the_design_matches_householder():
    # the fit's projection: CholeskyQR2 of a well-conditioned design (mode columns with residual terms) gives
    # Q orthonormal and Q R = Φ to rounding (a few ulp times the column count), like Householder's; a design
    # with two equal columns (two poles at one frequency) is beyond it and takes Householder's QR, whose R
    # then has a zero on its diagonal
    from modal.nls import orthonormal_factor

    omega = np.linspace(20, 400, 2001) / 100
    basis = np.column_stack([1 / (w**2 - omega**2 + 2j * 0.01 * w * omega) for w in (0.5, 1.2, 2.5, 3.1)])
    design = np.hstack([basis, (-omega**2)[:, None], np.ones((omega.size, 1))])
    Q, R = orthonormal_factor(design)
    assert np.abs(Q.conj().T @ Q - np.eye(6)).max() < 1e-14
    assert np.abs(Q @ R - design).max() < 1e-14 * np.abs(design).max()
    np.testing.assert_allclose(np.abs(np.diag(R)), np.abs(np.diag(np.linalg.qr(design)[1])), rtol=1e-12)
    twice = np.hstack([basis, basis[:, :1]])
    Q, R = orthonormal_factor(twice)
    assert abs(R[-1, -1]) < 1e-12 * np.abs(R).max()
    assert np.abs(Q @ R - twice).max() < 1e-14 * np.abs(twice).max()


def test_whitened_fit_on_the_cholesky_qr_projection(monkeypatch):
    # generalised least squares (``whitening``) on a design large enough for CholeskyQR2 (4001 lines × 3
    # columns): errors correlated between neighbouring lines by a/(1 + a²) ≈ 0.49 (a moving average of white
    # noise), whitened by the banded Cholesky factor of that correlation
    import modal.nls as nls
    from modal.nls import LineWhitening

    f = np.linspace(20, 400, 4001)
    exact = modal_frf(f, [100.0, 250.0], [0.02, 0.02], np.array([1.0, 0.5 + 0.2j]))
    omega, region = exact.omega_rad_s, np.zeros(f.size, int)
    rng = np.random.default_rng(7)
    a = 0.8
    white = (rng.standard_normal(f.size + 1) + 1j * rng.standard_normal(f.size + 1)) / np.sqrt(2)
    sigma = 0.02 * np.abs(exact.response).max()
    data = exact.response + sigma * (white[1:] + a * white[:-1]) / np.sqrt(1 + a * a)
    band = np.zeros((2, f.size), complex)
    band[0], band[1, :-1] = 1.0, a / (1 + a * a)
    whitening = LineWhitening(band)
    start = (2 * np.pi * np.array([101.0, 249.0]), [0.025, 0.018])
    assert 3 * f.size >= nls.CHOLESKY_QR_MIN_SIZE  # the CholeskyQR2 projection is the one used
    gls = fit_modes(omega, data, 0, *start, region=region, whitening=whitening)
    ols = fit_modes(omega, data, 0, *start, region=region)
    assert gls.converged and gls.line_weighted and not ols.line_weighted
    # the whitened residual is white: its lag-1 correlation within 4 of its standard error 1/sqrt(2n) per part
    # (the unweighted fit's residual keeps the noise's 0.49)
    for fit, white_expected in ((gls, True), (ols, False)):
        r = fit.residual[:][0]
        rho = np.vdot(r[:-1], r[1:]) / np.vdot(r, r)
        assert (abs(rho) < 4 * np.sqrt(2 / f.size)) == white_expected
    # W R Wᴴ = I with R the correlation: the whitened noise keeps the lines' variance σ² (chi-square of
    # 2·dof ≈ 8000 degrees of freedom: relative spread 1/sqrt(dof) ≈ 0.016, five of it)
    assert abs(gls.noise_var[0] / sigma**2 - 1) < 5 / np.sqrt(f.size)
    # Householder's projection of the same whitened design finds the same optimum: both stop at relative
    # steps of 1e-13, far below 1e-6 of standard errors that are 1e-4 of the poles
    monkeypatch.setattr(nls, "CHOLESKY_QR_MIN_SIZE", 10**12)
    householder = fit_modes(omega, data, 0, *start, region=region, whitening=whitening)
    monkeypatch.undo()
    s_wn, s_zeta = np.sqrt(gls.mode_cov[:, 0, 0, 0]), np.sqrt(gls.mode_cov[:, 0, 1, 1])
    assert np.all(np.abs(householder.omega_n - gls.omega_n) < 1e-6 * s_wn)
    assert np.all(np.abs(householder.damping_ratio - gls.damping_ratio) < 1e-6 * s_zeta)
    # ignoring the correlation understates the poles' errors (positively correlated errors average less)
    assert np.all(np.sqrt(ols.mode_cov[:, 0, 0, 0]) < 0.8 * s_wn)
    # the unweighted fit's residual fails the Ljung–Box test: with ``correlated_lags`` its poles' covariance is
    # the Newey–West sandwich, larger than the Fisher information's by about sqrt(1 + 2·0.49·5/6) ≈ 1.35 (the
    # Bartlett weight of lag 1 of 5); over 40 noise seeds it was 1.04-1.65 of it, never below
    sandwich = fit_modes(omega, data, 0, *start, region=region, correlated_lags=5)
    np.testing.assert_array_equal(sandwich.omega_n, ols.omega_n)
    for k in (0, 1):
        assert np.all(sandwich.mode_cov[:, 0, k, k] > ols.mode_cov[:, 0, k, k])
    # the whitened residual passes the Ljung–Box test: the covariance stays the Fisher information's; without
    # errors the same poles, bit for bit, and no covariance
    lagged = fit_modes(omega, data, 0, *start, region=region, whitening=whitening, correlated_lags=5)
    np.testing.assert_array_equal(lagged.mode_cov, gls.mode_cov)
    bare = fit_modes(omega, data, 0, *start, region=region, whitening=whitening, correlated_lags=5, errors=False)
    np.testing.assert_array_equal(bare.omega_n, gls.omega_n)
    assert np.all(np.isnan(bare.mode_cov))


def test_whitening_keeps_a_long_correlation_as_it_is():
    # an exponential window (τ = 0.5 s on 2 s records at 1024 Hz) correlates the lines of a hit record by
    # ~1/(0.79 m) over tens of lines; on a band of 41 lines every lag is carried, the matrix is the errors'
    # own correlation and positive definite, and whitening by it must leave errors of unit variance, white.
    # Each check is over 41 × 2000 complex values: the mean variance has relative spread 1/sqrt(82000) =
    # 0.0035 and the lag-1 correlation (each part) 1/sqrt(2 · 80000) = 0.0025; five of those
    from modal.estimate.windows import exponential_window
    from modal.nls import LineWhitening
    from modal.noise_model import window_line_correlation

    c = window_line_correlation(exponential_window(2048, 1024.0, 0.5))
    n = 41
    band = np.zeros((n, n), complex)
    for d in range(n):
        band[d, :n - d] = np.conj(c[d])  # R[j + d, j] = E[e_{j+d} e*_j]
    dense = np.zeros((n, n), complex)
    for d in range(n):
        j = np.arange(n - d)
        dense[j + d, j] = band[d, :n - d]
        dense[j, j + d] = np.conj(band[d, :n - d])
    rng = np.random.default_rng(3)
    white = (rng.standard_normal((n, 2000)) + 1j * rng.standard_normal((n, 2000))) / np.sqrt(2)
    errors = np.linalg.cholesky(dense) @ white
    whitened = LineWhitening(band)(errors)
    assert abs(np.mean(np.abs(whitened) ** 2) - 1) < 5 * 0.0035
    lag1 = np.vdot(whitened[:-1], whitened[1:]) / np.vdot(whitened, whitened)
    assert abs(lag1) < 5 * 0.0025 * np.sqrt(2)
