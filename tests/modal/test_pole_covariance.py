"""The poles' covariance of a fit (modal.pole_covariance)."""
import numpy as np
import pytest

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


def test_a_gain_error_shared_by_the_lines_moves_the_constant_by_its_own_size():
    from modal.channel_covariance import relative_error_terms
    from modal.pole_covariance import constants_noise

    rng = np.random.default_rng(0)
    design = rng.standard_normal((200, 2)) + 1j * rng.standard_normal((200, 2))
    Q, R = np.linalg.qr(design)
    gain = 0.01 + 0.005j  # every line's response off by the same relative error, as an excitation's gain
    # a shared error inside the design's span (the first column times the gain) moves the first coefficient by the
    # gain and leaves no residual: white noise of the residual's power (which it adds none to) says nothing of it
    common = (design[:, :1] * gain)[None]  # (1 channel, 200 lines, 1 factor)
    white, shared = constants_noise(Q, np.linalg.inv(R), np.array([1e-6]), common,
                                    relative_error_terms(Q, Q, np.ones((2, 1)), common, 198)[1])
    assert white == pytest.approx([1e-6])
    assert shared[:, 0] == pytest.approx([abs(gain) ** 2, 0.0], abs=1e-18)
    # off the design's span entirely: all of it in the residual, taken out of the white part, nothing in the
    # coefficients
    off = design[:, :1] - Q @ (Q.conj().T @ design[:, :1])
    white, shared = constants_noise(Q, np.linalg.inv(R), np.array([1.0]), off[None],
                                    relative_error_terms(Q, Q, np.ones((2, 1)), off[None], 198)[1])
    assert shared[:, 0] == pytest.approx([0.0, 0.0], abs=1e-20)
    assert white[0] == pytest.approx(1.0 - np.sum(np.abs(off) ** 2) / 198)
