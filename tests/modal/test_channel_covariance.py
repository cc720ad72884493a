"""The poles' covariance of a fit weighing several channels alike (modal.channel_covariance)."""
import numpy as np

from modal.channel_covariance import channel_sandwich, sandwich_product, widened
from modal.pole_covariance import pole_covariance


def test_pole_errors_of_channels_with_equal_noise_are_the_fisher_information_inverse():
    # channels whose scaled noise is alike: the sandwich is the Fisher information's inverse (to rounding), the
    # covariance of the efficient fit this one then is
    rng = np.random.default_rng(3)
    E = rng.standard_normal((50, 4)) + 1j * rng.standard_normal((50, 4))
    C = rng.standard_normal((4, 3)) + 1j * rng.standard_normal((4, 3))
    gram = E.conj().T @ E
    noise_var = np.full(3, 0.37)
    bread = pole_covariance(2 * np.real(gram * (C.conj() @ C.T)))
    fisher = 2 * np.real(gram * ((C.conj() / noise_var) @ C.T))
    np.testing.assert_allclose(channel_sandwich(bread, gram, C, noise_var), np.linalg.inv(fisher), rtol=1e-10)


def test_the_lag_covariance_only_widens_and_keeps_the_correlations():
    # each variance is the larger of the two; the correlation coefficients are the model's
    model = np.array([[4.0, 1.2], [1.2, 1.0]])
    measured = np.array([[9.0, 0.0], [0.0, 0.25]])
    out = widened(model, measured)
    np.testing.assert_allclose(np.diag(out), [9.0, 1.0])
    np.testing.assert_allclose(out[0, 1] / np.sqrt(out[0, 0] * out[1, 1]), 1.2 / 2.0)


def test_undetermined_parameters_stay_undetermined_in_the_sandwich():
    # a NaN row and column of the bread (a pole the data do not determine) stay NaN; the others carry none of it
    bread = np.array([[2.0, 0.5, np.nan], [0.5, 1.0, np.nan], [np.nan, np.nan, np.nan]])
    middle = np.eye(3)
    out = sandwich_product(bread, middle)
    assert np.all(np.isnan(out[2])) and np.all(np.isnan(out[:, 2]))
    np.testing.assert_allclose(out[:2, :2], bread[:2, :2] @ bread[:2, :2])
