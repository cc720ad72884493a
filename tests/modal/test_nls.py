"""The complex nonlinear least squares of modes (modal.nls)."""
import numpy as np

from modal.nls import fit_modes
from modal.synthetic import add_noise, modal_frf


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
    from modal.whitening import LineWhitening

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


def _wide_band(n_out=10, seed=0):
    """10 response points x 2 references on 2000 lines over 0.5-2000 Hz, accelerance, 0.5 % noise: 13 modes in
    the band and two above it (2150 and 2500 Hz) whose dampings the lines hardly determine."""
    fn = np.array([47.3, 118., 205., 300., 302.5, 410., 540., 655., 790., 930., 1080., 1240., 1420., 2150., 2500.])
    zeta = np.array([0.0042, 0.012, 0.01, 0.008, 0.008, 0.008, 0.007, 0.007, 0.006, 0.006, 0.006, 0.005, 0.005,
                     0.005, 0.005])
    rng = np.random.default_rng(11)
    phi = rng.normal(size=(n_out, fn.size))
    phi[:2] = rng.choice([-1, 1], size=(2, fn.size)) * rng.uniform(0.6, 1.2, size=(2, fn.size))
    const = np.array([[phi[o, r] * phi[q, r] for r in range(fn.size)] for o in range(n_out) for q in (0, 1)])
    frf = add_noise(modal_frf(np.linspace(0.5, 2000, 2000), fn, zeta, const, kind="accelerance"), 0.005, seed=seed)
    return fn, zeta, frf


def test_a_damping_ratio_at_its_floor_does_not_keep_the_fit_going():
    # a pole above the lines whose damping collapsed onto the floor (ζ ~ 2.5e-10 here; the global method's
    # stages hand such a pole on): every Gauss–Newton step wanted it below zero, the bound took that part
    # of the step back, and the fit went on to max_iter, each step predicting a decrease it could not have
    # (the wide-band bench case: 200 iterations, every mode flagged did_not_converge). The bound is now
    # active in the step: the others converge within a few iterations and the pole stays on its floor
    fn, zeta, frf = _wide_band()
    w0 = 2 * np.pi * np.append(fn[:13], [2161.7, 2542.0])
    z0 = np.append(zeta[:13], [0.0073, 0.0])
    fit = fit_modes(frf.omega_rad_s, frf.channels, 2, w0, z0, residual_terms=True, step_tol=1e-9, max_damping=0.3,
                    max_iter=60)
    assert fit.converged and fit.n_iter <= 10, fit.n_iter
    assert fit.damping_ratio[-1] < 1e-9
    np.testing.assert_allclose(fit.omega_n[:13] / (2 * np.pi), fn[:13], rtol=3e-3)


def test_decrement_tolerance_stops_within_a_small_fraction_of_a_standard_error():
    # decrement_tol: converged where the Gauss–Newton step would lower the cost by less than that many times
    # the residual's mean square, i.e. a step under sqrt(2·1e-4) = 0.014 standard errors. The poles above the
    # lines converge linearly (each step a fixed fraction ρ of the last); what is left is then under
    # 0.014 ρ/(1 − ρ) standard errors, below 0.1 of one for ρ up to 0.87. Fewer iterations, and every pole
    # within a tenth of its standard error of the fit to a step of 1e-9 relative
    fn, zeta, frf = _wide_band()
    w0 = 2 * np.pi * np.append(fn[:13], [2100.0, 2300.0])
    z0 = np.append(zeta[:13], [0.004, 0.003])
    common = dict(residual_terms=True, step_tol=1e-9, max_damping=0.3)
    full = fit_modes(frf.omega_rad_s, frf.channels, 2, w0, z0, **common)
    early = fit_modes(frf.omega_rad_s, frf.channels, 2, w0, z0, decrement_tol=1e-4, **common)
    assert early.converged and early.n_iter < full.n_iter
    s_wn = np.sqrt(full.mode_cov[:, 0, 0, 0])
    s_zeta = np.sqrt(full.mode_cov[:, 0, 1, 1])
    pinned = full.damping_ratio < 1e-9  # a damping on its floor has no standard error; it stays there
    assert np.all(np.abs(early.omega_n - full.omega_n) < 0.1 * s_wn)
    assert np.all(np.abs(early.damping_ratio - full.damping_ratio)[~pinned] < 0.1 * s_zeta[~pinned])
    assert np.all(early.damping_ratio[pinned] == full.damping_ratio[pinned])


def test_projection_cost_by_difference_matches_the_residual_it_stands_for():
    # with ‖Y‖² given, the projection's cost is ‖Y‖² − ‖QᴴY‖² where that keeps 1e-4 of ‖Y‖² (nls.RSS_BY_DIFFERENCE):
    # the rounding of the two sums (~1e-16 of ‖Y‖² per term, 1e-12 over 4000 × 8 terms at most) is then below
    # 1e-8 of the cost; near-exact data (cost below that share) take the residual's own sum
    from modal.nls import _project

    rng = np.random.default_rng(2)
    x = np.linspace(0.5, 2.0, 4000)
    Phi = np.column_stack([1 / (w**2 - x**2 + 2j * 0.01 * w * x) for w in (0.8, 1.3, 1.7)] + [np.ones_like(x)])
    coef = rng.standard_normal((4, 8)) + 1j * rng.standard_normal((4, 8))
    exact = Phi @ coef
    for noise, direct in ((1.0, False), (1e-9, True)):
        Y = exact + noise * (rng.standard_normal(exact.shape) + 1j * rng.standard_normal(exact.shape))
        energy = float(np.vdot(Y, Y).real)
        *_, plain = _project(Phi, Y)
        *_, quick = _project(Phi, Y, energy)
        assert (plain < 1e-4 * energy) == direct
        if direct:
            assert quick == plain  # formed and summed as without the energy
        else:
            assert abs(quick - plain) < 1e-8 * plain


def test_a_budget_of_evaluations_stops_the_fit_where_it_stands():
    # two modes started 2 % and 30 % off: unbounded, the fit converges in a few evaluations; a budget below that
    # stops it not converged and marks it capped, after exactly the evaluations allowed; a budget above it
    # changes nothing (the same steps, bit for bit)
    f = np.linspace(20, 400, 761)
    frf = add_noise(modal_frf(f, [100.0, 250.0], [0.02, 0.02], [1.0, 0.5]), 0.01, seed=5)
    omega, region = frf.omega_rad_s, np.zeros(f.size, int)
    start = (2 * np.pi * np.array([102.0, 250.0 * 1.3]), [0.03, 0.01])
    free = fit_modes(omega, frf.channels, 0, *start, region=region)
    assert free.converged and not free.capped and free.n_evaluations > 3
    roomy = fit_modes(omega, frf.channels, 0, *start, region=region, max_evaluations=free.n_evaluations)
    assert roomy.converged and not roomy.capped
    assert np.array_equal(roomy.omega_n, free.omega_n) and np.array_equal(roomy.mode_cov, free.mode_cov, equal_nan=True)
    capped = fit_modes(omega, frf.channels, 0, *start, region=region, max_evaluations=2)
    assert capped.capped and not capped.converged and capped.n_evaluations == 2
    assert np.all(np.isfinite(capped.omega_n)) and not np.array_equal(capped.omega_n, free.omega_n)
    at_start = fit_modes(omega, frf.channels, 0, *start, region=region, max_evaluations=0)
    assert at_start.capped and at_start.n_evaluations == 0
    np.testing.assert_array_equal(at_start.omega_n, start[0])  # no step taken: the start, with its errors
    assert np.all(np.isfinite(at_start.mode_cov))


def test_pole_errors_of_channels_with_unequal_noise_match_their_scatter():
    # the fit scales each channel to a peak of 1 and weighs the scaled channels alike; when their noise is not
    # alike (a quiet channel beside two noisy ones, relative to their peaks), the poles' covariance is the
    # sandwich of that cost, not the Fisher information's inverse (the covariance of a fit weighing each
    # channel by its noise, which this one is not: 1.5–1.7 times too small a standard error on the multi-channel
    # hammer cells of benchmarks/bench_chain.py, 0.15 of the scatter here). Over 300 noise draws the scatter's
    # standard deviation is known to 1/√600 = 4 %: the reported standard error (the root-mean-square over the
    # draws) is held within 15 % of it (3.5 of those standard errors, and the covariance's own linearisation
    # error, below 1 % at this noise)
    f = np.linspace(30.0, 50.0, 201)
    w = 2 * np.pi * f
    wn, zeta = 2 * np.pi * 40.0, 0.02
    constants = np.array([1.0, 0.6, -0.8])
    clean = np.array([a / (wn**2 - w**2 + 2j * zeta * wn * w) for a in constants])
    relative_noise = np.array([0.002, 0.03, 0.03])  # of each channel's peak
    sigma = relative_noise * np.abs(clean).max(axis=1)
    rng = np.random.default_rng(7)
    estimates, reported = [], []
    for _ in range(300):
        noise = (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape)) * sigma[:, None] / np.sqrt(2)
        fit = fit_modes(w, clean + noise, 0, [wn], [zeta])
        estimates.append([fit.omega_n[0], fit.damping_ratio[0]])
        reported.append([fit.mode_cov[0, 0, 0, 0], fit.mode_cov[0, 0, 1, 1]])
    scatter = np.std(estimates, axis=0)
    reported_std = np.sqrt(np.mean(reported, axis=0))
    np.testing.assert_allclose(reported_std / scatter, 1.0, atol=0.15)



def test_pole_errors_of_channels_sharing_an_error_match_their_scatter():
    # an error every channel shares relative to its FRF (a hammer's force noise: H_c η, one η for every channel,
    # smooth across the lines) moves every channel's pole alike: a covariance taking the channels as independent
    # reports a quarter of the scatter here. Carried as a factor of η's covariance, it is in the sandwich's
    # middle. Over 300 draws the scatter's standard deviation is known to 1/√600 = 4 %: the reported standard
    # error (RMS over the draws) is held within 15 % of it, as in the test above
    f = np.linspace(30.0, 50.0, 201)
    w = 2 * np.pi * f
    wn, zeta = 2 * np.pi * 40.0, 0.02
    constants = np.array([1.0, 0.6, -0.8])
    clean = np.array([a / (wn**2 - w**2 + 2j * zeta * wn * w) for a in constants])
    t = np.linspace(-1.0, 1.0, f.size)
    factor = 0.004 * np.array([np.ones_like(t), t, t**2, np.sin(3 * t)]).astype(complex)  # η = factorᵀ ξ
    sigma = 0.002 * np.abs(clean).max(axis=1)  # each channel's own noise
    rng = np.random.default_rng(7)
    estimates, reported = [], []
    for draw in range(300):
        xi = (rng.standard_normal(factor.shape[0]) + 1j * rng.standard_normal(factor.shape[0])) / np.sqrt(2)
        noise = (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape)) * sigma[:, None] / np.sqrt(2)
        data = clean * (1 + factor.T @ xi) + noise
        fit = fit_modes(w, data, 0, [wn], [zeta], relative_error=factor)
        estimates.append([fit.omega_n[0], fit.damping_ratio[0]])
        reported.append([fit.mode_cov[0, 0, 0, 0], fit.mode_cov[0, 0, 1, 1]])
        if draw == 0:
            independent = fit_modes(w, data, 0, [wn], [zeta])
    scatter = np.std(estimates, axis=0)
    np.testing.assert_allclose(np.sqrt(np.mean(reported, axis=0)) / scatter, 1.0, atol=0.15)
    # the channels taken as independent: far too narrow (0.25-0.27 of the scatter over all draws)
    plain = np.sqrt([independent.mode_cov[0, 0, 0, 0], independent.mode_cov[0, 0, 1, 1]])
    assert np.all(plain / scatter < 0.5)
