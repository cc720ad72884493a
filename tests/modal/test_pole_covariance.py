"""The poles' covariance of a fit (modal.pole_covariance)."""
import numpy as np

from modal.pole_covariance import pole_covariance


def test_pole_covariance_leaves_undetermined_poles_undetermined():
    # a Fisher information with one direction the data do not determine (two parameters that enter only as
    # their sum): those two get NaN variances, the determined ones the inverse of their own block, as for a
    # regular matrix, where the result is its inverse (to the rounding of the diagonal scaling, a few ulp)
    regular = np.array([[4.0, 1.0], [1.0, 3.0]])
    np.testing.assert_allclose(pole_covariance(regular), np.linalg.inv(regular), rtol=1e-14)
    u = np.array([1.0, 1.0])
    F = np.zeros((4, 4))
    F[:2, :2] = regular
    F[2:, 2:] = 5.0 * np.outer(u, u)  # rank one: only θ2 + θ3 is determined
    cov = pole_covariance(F)
    assert np.all(np.isnan(cov[2:, :])) and np.all(np.isnan(cov[:, 2:]))
    np.testing.assert_allclose(cov[:2, :2], np.linalg.inv(regular), rtol=1e-12)
