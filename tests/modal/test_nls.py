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
