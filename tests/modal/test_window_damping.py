"""The exponential window's damping taken out of an identified pole (modal.window_damping)."""
import numpy as np
import pytest

from modal.window_damping import remove_window_damping


def test_the_pole_moves_back_by_one_over_tau_exactly():
    # a window exp(-t/τ) moves every pole left by 1/τ and keeps ωd: the true pole is recovered to rounding
    wn, zeta, tau = 2 * np.pi * 80.0, 0.015, 0.3
    sigma, wd = zeta * wn + 1 / tau, wn * np.sqrt(1 - zeta**2)
    wn_m = np.hypot(wd, sigma)
    cov = np.diag([1e-2, 1e-8, 1e-6, 1e-6])[None]
    back, z_back, _, _, _, window, valid = remove_window_damping(wn_m, sigma / wn_m, cov, 0.1, 1e-4, tau)
    assert valid
    assert back == pytest.approx(wn, rel=1e-14) and z_back == pytest.approx(zeta, rel=1e-12)
    assert window == pytest.approx(sigma / wn_m - zeta, rel=1e-12)


def test_the_errors_go_through_the_jacobian_of_the_map():
    wn, zeta, tau = 2 * np.pi * 80.0, 0.03, 0.3
    rng = np.random.default_rng(1)
    root = rng.standard_normal((4, 4)) * np.array([1e-1, 1e-4, 1e-3, 1e-3])[:, None]
    cov = (root @ root.T)[None]

    def pole(t):
        out = remove_window_damping(t[0], t[1], cov, 0.0, 0.0, tau)
        return np.array([out[0], out[1]])

    # central differences, steps 1e-7 relative: truncation ~1e-14, far below the 1e-7 asked
    steps = 1e-7 * np.array([wn, zeta])
    jac = np.column_stack([(pole(np.array([wn, zeta]) + e) - pole(np.array([wn, zeta]) - e)) / (2 * h)
                           for e, h in zip(np.diag(steps), steps)])
    _, _, moved, s_wn, s_z, _, _ = remove_window_damping(wn, zeta, cov, 0.2, 2e-3, tau)
    np.testing.assert_allclose(moved[0][:2, :2], jac @ cov[0][:2, :2] @ jac.T, rtol=1e-7)
    np.testing.assert_allclose(moved[0][2:, 2:], cov[0][2:, 2:], rtol=0, atol=0)  # constants unchanged
    reported = jac @ np.diag([0.2**2, 2e-3**2]) @ jac.T
    assert s_wn == pytest.approx(np.sqrt(reported[0, 0]), rel=1e-7)
    assert s_z == pytest.approx(np.sqrt(reported[1, 1]), rel=1e-7)


def test_a_window_that_makes_all_the_damping_leaves_the_pole_as_measured():
    wn, zeta = 2 * np.pi * 80.0, 0.01
    cov = np.eye(4)[None]
    out = remove_window_damping(wn, zeta, cov, 0.1, 1e-4, 0.9 / (zeta * wn))  # 1/τ above ζωn
    assert out[:2] == (wn, zeta) and out[2] is cov and out[5:] == (0.0, False)
