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


@pytest.mark.parametrize("kind, power", [("receptance", 0), ("mobility", 1), ("accelerance", 2)])
@pytest.mark.parametrize("method", ["nls", "global"])
def test_constants_of_an_accelerometer_record_windowed_come_back_real(kind, power, method):
    # a record of the quantity the kind says, windowed by exp(-t/τ): its FRF is (s + 1/τ)^p H_r(s + 1/τ), which
    # near the moved pole p' reads as s^p R (p/p')^p / (s - p'). The constants came back turned by about
    # -p/(ωτ) (-4.6° at 40 Hz for an accelerance, τ = 0.1 s; -23° with τ = 0.02 s, flagged complex_mode) and their
    # magnitude off by (1/(ωτ))². (What the model leaves out, a term of the windowed FRF linear in s, is
    # 2ζ'/(ωτ) of the peak: 0.4 % here, below the noise's effect on the constants)
    import modal
    from modal.window_damping import window_constant_factor

    tau = 0.1
    fn, zeta, residue = np.array([40.0, 95.0]), np.array([0.01, 0.02]), np.array([1.0, 0.5])  # 1/kg, real
    f = np.linspace(1.0, 200.0, 1600)
    s = 2j * np.pi * f + 1 / tau  # the windowed FRF is the structure's at s + 1/τ
    wn = 2 * np.pi * fn
    receptance = sum(r / (s**2 + 2 * z * w * s + w**2) for r, z, w in zip(residue, zeta, wn))
    windowed = s**power * receptance
    rng = np.random.default_rng(4)
    noise = 1e-5 * np.abs(windowed).max()
    measured = windowed + noise * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2)
    frf = modal.FRF(f, measured, kind=kind, response_points=["1+Z"], reference_points=["1+Z"],
                    exponential_decay_s=tau, noise_std=np.full(f.size, noise))
    result = modal.identify(frf, method, modes_hz=list(fn)) if method == "global" else modal.identify(frf, method)
    for mode, r, z, w in zip(sorted(result.modes, key=lambda m: m.natural_frequency_hz), residue, zeta, wn):
        assert "complex_mode" not in mode.flags and "complex_shape" not in mode.flags
        # nls: the constant within 4 of its standard errors of the structure's (noise 1e-5 of the peak), and within
        # what the model leaves out, 2ζ'/(ωτ) of it (ζ' the windowed pole's damping; 0 for a receptance)
        const = complex(mode.modal_constant)
        # the window turned it by about -p/(ωτ): back within a fifth of that (the global fit's poles themselves
        # are biased by the term its model leaves out, 6 of their errors at 95 Hz here)
        assert abs(np.angle(const)) < 0.2 * power / (w * tau) + 1e-3
        if method == "nls":
            left_out = 2 * (z + 1 / (w * tau)) / (w * tau) * r if power else 0.0
            assert abs(const - r) <= 4 * float(mode.std.modal_constant) + left_out
    assert window_constant_factor(2 * np.pi * 40.0, 0.1, 2 * np.pi * 40.0, 0.01, 0) == 1.0
