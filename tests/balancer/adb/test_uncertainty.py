"""The stability threshold's standard error from identified k, c, M: covariance, checked by Monte Carlo.

k, c and M identified from one mode share ωn, ζ and the modal constant: k = ωn²/|A|,
M = 1/|A|, c = 2ζωn/|A|. Their errors are strongly correlated (k and M nearly +1), and
the threshold depends mostly on √(k/M), in which the common 1/|A| cancels. Propagating
them as independent overstates the threshold's error several times; the covariance of
identify carried through :func:`balancer.adb.threshold_sensitivity` must match the
scatter of the threshold over noise seeds of identify → threshold.
"""
from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import modal
from balancer.adb import ADBParameters, ParameterStd, identified_std, stable_speed_intervals, threshold_sensitivity
from balancer.adb.stability import characteristic_polynomial
from modal.errors import ModalWarning
from modal.synthetic import add_noise, sdof_frf

#: the rotor of tests/balancer/adb/test_stability.py (S1): M = 1 kg, k = 1e4 N/m, c = 20 N s/m (ζ = 0.1)
ROTOR = dict(M=1.0, k=1e4, c=20.0)
BALLS = dict(m=0.02, n=2, R=0.05, e=0.5e-3, D=1e-3)
N_SEEDS = 200
NOISE = 0.01


def _frf():
    """Driving-point receptance of the rotor on its supports: 12 lines per half-power band, ±4 widths."""
    wn = np.sqrt(ROTOR["k"] / ROTOR["M"])
    zeta = ROTOR["c"] / (2 * np.sqrt(ROTOR["k"] * ROTOR["M"]))
    fn = wn / (2 * np.pi)
    df = 2 * zeta * fn / 12
    f = fn + (np.arange(-48, 49) + 0.37) * df
    return sdof_frf(f[f > 0], ROTOR["M"], ROTOR["k"], ROTOR["c"])


def _threshold(params: ADBParameters, guess: float) -> float:
    """Lowest stable speed near ``guess``: the zero of the largest real part of the roots of the
    two-ball characteristic polynomial (0.8 ms; the same boundary as stable_speed_intervals)."""
    def growth(speed):
        return float(np.max(np.roots(characteristic_polynomial(params, speed)).real))

    return brentq(growth, 0.8 * guess, 1.25 * guess, xtol=1e-10 * guess)


@functools.lru_cache(maxsize=None)
def _monte_carlo():
    truth = ADBParameters(**ROTOR, **BALLS)
    nominal = stable_speed_intervals(truth, 10 * truth.natural_frequency_rad_s, xtol_ratio=1e-12).lowest_stable_speed_rad_s
    # the derivatives once, at the truth (threshold_sensitivity's central differences)
    gradient = threshold_sensitivity(truth, ParameterStd(), 10 * truth.natural_frequency_rad_s)
    g = np.array([gradient.derivative_k, gradient.derivative_c, gradient.derivative_M])
    clean = _frf()
    thresholds, correlated, independent = [], [], []
    for seed in range(N_SEEDS):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModalWarning)  # a noisy draw may be flagged: the scatter is the subject
            mode = modal.identify(add_noise(clean, NOISE, seed=seed), "nls")[0]
        params = ADBParameters.from_identified(mode, **BALLS)
        thresholds.append(_threshold(params, nominal))
        std = identified_std(mode)
        correlated.append(np.sqrt(g @ std.covariance @ g))
        independent.append(np.sqrt(g @ ParameterStd(k=std.k, c=std.c, M=std.M).covariance @ g))
    return nominal, np.array(thresholds), np.array(correlated), np.array(independent), g


def test_fast_threshold_is_the_same_boundary():
    truth = ADBParameters(**ROTOR, **BALLS)
    ref = stable_speed_intervals(truth, 10 * truth.natural_frequency_rad_s, xtol_ratio=1e-12).lowest_stable_speed_rad_s
    # both refine the same sign change of the growth rate to ~1e-10 relative
    assert _threshold(truth, 1.01 * ref) == pytest.approx(ref, rel=1e-8)


def test_threshold_error_from_the_covariance_matches_monte_carlo():
    nominal, thresholds, correlated, independent, _ = _monte_carlo()
    z = (thresholds - nominal) / correlated
    # 200 seeds: the SD of 200 standard normals has standard error 1/sqrt(400) = 0.05; ±0.15 is 3 of
    # those (the calibration bound the standard errors are held to); the mean has standard error 0.071, |mean| <= 0.3 is 4.2
    assert abs(np.std(z) - 1) <= 0.15, (np.std(z), np.mean(z))
    assert abs(np.mean(z)) <= 0.3, np.mean(z)
    # the independent sum overstates the threshold's error (the common 1/|A| of k and M cancels in
    # sqrt(k/M)): its z would be far below 1 in spread, outside the same bound
    z_independent = (thresholds - nominal) / independent
    assert np.std(z_independent) < 0.85, np.std(z_independent)


def test_threshold_sensitivity_uses_the_correlation():
    truth = ADBParameters(**ROTOR, **BALLS)
    r = np.array([[1.0, 0.3, 0.9], [0.3, 1.0, 0.2], [0.9, 0.2, 1.0]])
    std = ParameterStd(k=50.0, c=0.2, M=0.004, correlation=r)
    sens = threshold_sensitivity(truth, std, 10 * truth.natural_frequency_rad_s)
    g = np.array([sens.derivative_k, sens.derivative_c, sens.derivative_M])
    sd = np.array([50.0, 0.2, 0.004])
    # gᵀ Σ g with Σ = D R D, written out term by term (not through ParameterStd.covariance)
    expected = np.sqrt(sum(g[i] * sd[i] * r[i, j] * sd[j] * g[j] for i in range(3) for j in range(3)))
    assert sens.std_rad_s == pytest.approx(expected, rel=1e-12)
    with pytest.raises(modal.errors.ParameterError, match="correlation"):
        ParameterStd(k=1.0, correlation=np.eye(2))


def test_monte_carlo_draws_carry_the_correlation():
    from balancer.adb.montecarlo import sample_parameters

    truth = ADBParameters(**ROTOR, **BALLS)
    r = np.array([[1.0, 0.3, 0.95], [0.3, 1.0, 0.2], [0.95, 0.2, 1.0]])
    std = ParameterStd(k=50.0, c=0.2, M=0.004, correlation=r)
    draws = sample_parameters(truth, std, 20000, seed=4)
    # 20000 draws: a sample correlation has standard error (1 - r²)/sqrt(N) <= 0.007 and a sample
    # SD relative error 1/sqrt(2N) = 0.005; 0.03 and 3 % are more than 4 of those
    np.testing.assert_allclose(np.corrcoef(draws.T), r, atol=0.03)
    np.testing.assert_allclose(draws.std(axis=0), [50.0, 0.2, 0.004], rtol=0.03)
