"""Whitening of errors correlated between lines (modal.whitening)."""
import numpy as np

from modal.whitening import LineWhitening


def test_whitening_keeps_a_long_correlation_as_it_is():
    # an exponential window (τ = 0.5 s on 2 s records at 1024 Hz) correlates the lines of a hit record by
    # ~1/(0.79 m) over tens of lines; on a band of 41 lines every lag is carried, the matrix is the errors'
    # own correlation and positive definite, and whitening by it must leave errors of unit variance, white.
    # Each check is over 41 × 2000 complex values: the mean variance has relative spread 1/sqrt(82000) =
    # 0.0035 and the lag-1 correlation (each part) 1/sqrt(2 · 80000) = 0.0025; five of those
    from modal.estimate.windows import exponential_window
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


def test_whitening_solves_as_solve_banded_on_every_call():
    # the band LU of the factor is formed once and reused (gbsv is gbtrf then gbtrs): every call, a matrix or
    # a vector, real or complex, must give solve_banded's numbers bit for bit
    from scipy.linalg import solve_banded

    n, rng = 60, np.random.default_rng(4)
    band = np.zeros((4, n), complex)
    band[0] = 1.0
    band[1, :-1], band[2, :-2], band[3, :-3] = 0.4 + 0.1j, 0.15 - 0.05j, 0.05
    whitening = LineWhitening(band)
    assert whitening.bandwidth == 3
    for values in (rng.standard_normal((n, 5)) + 1j * rng.standard_normal((n, 5)), rng.standard_normal(n),
                   rng.standard_normal((n, 2)), rng.standard_normal(n) + 1j * rng.standard_normal(n)):
        expected = solve_banded((3, 0), whitening._factor, values)
        got = whitening(values)
        assert got.shape == values.shape and np.array_equal(got, expected)
