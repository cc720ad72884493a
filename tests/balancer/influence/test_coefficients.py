"""Influence coefficients and corrections (balancer.influence.coefficients): least squares and min-max,
bounds per plane, warnings for dependent planes and weak trials."""
from __future__ import annotations

import math

import numpy as np
import pytest

from balancer.influence import correction, influence_matrix
from modal.errors import QualityWarning
from support.balancing import polar, HS_INITIAL, HS_RUNS, HS_TRIALS


def test_hsbalance_readme_two_plane_example():
    alpha = influence_matrix(HS_INITIAL, HS_RUNS, HS_TRIALS)
    result = correction(alpha, HS_INITIAL)
    # independent closed form: 2 x 2 system solved by Cramer's rule
    a, b = HS_INITIAL
    d11, d21 = (HS_RUNS[0] - HS_INITIAL) / HS_TRIALS[0]
    d12, d22 = (HS_RUNS[1] - HS_INITIAL) / HS_TRIALS[1]
    det = d11 * d22 - d12 * d21
    exact = np.array([(-a * d22 + b * d12) / det, (-b * d11 + a * d21) / det])
    np.testing.assert_allclose(result.unbalance_kg_m, exact, rtol=1e-6, atol=0)
    magnitude = np.abs(result.unbalance_kg_m)
    angle = np.mod(np.rad2deg(np.angle(result.unbalance_kg_m)), 360.0)
    # the published answer, at the precision it is printed with
    np.testing.assert_array_equal(np.round(magnitude, 3), [1.979, 1.071])
    np.testing.assert_array_equal(np.round(angle, 1), [236.2, 121.8])
    assert result.worst_residual <= 1e-12 * result.worst_initial  # square system: exact cancellation
    minmax = correction(alpha, HS_INITIAL, method="minmax")
    np.testing.assert_allclose(minmax.unbalance_kg_m, exact, rtol=1e-6)


# ---------------------------------------------------------------- a synthetic flexible rotor
def rotor_alpha(speeds_rad_s, sensors=(0, 1, 2, 3, 4), planes=(1, 2, 3)):
    """Five stations on a flexible shaft (bearings at 0 and 4, discs at 1-3), 1x response per unbalance.

    alpha[(speed, sensor), plane] = Omega^2 H(Omega)[sensor, plane] in the lag convention (conjugate
    of the rotation-convention receptance), stacked speed by speed.
    """
    mass = np.diag([5.0, 20.0, 30.0, 20.0, 5.0])
    k_shaft, k_bearing = 2e6, 5e6
    stiffness = np.zeros((5, 5))
    for i in range(4):
        stiffness[i:i + 2, i:i + 2] += k_shaft * np.array([[1.0, -1.0], [-1.0, 1.0]])
    stiffness[0, 0] += k_bearing
    stiffness[4, 4] += k_bearing
    damping = 1e-4 * stiffness + 2.0 * mass
    blocks = []
    for w in speeds_rad_s:
        h = np.linalg.inv(stiffness - w * w * mass + 1j * w * damping)
        blocks.append(np.conj(w * w * h[np.ix_(sensors, planes)]))
    return np.vstack(blocks)


def test_three_planes_five_sensors_two_speeds_recovered_exactly():
    alpha_true = rotor_alpha([150.0, 400.0])  # 10 readings x 3 planes
    rotor_unbalance = polar([2e-3, 1e-3, 3e-3], [30.0, 200.0, 110.0])  # kg m
    initial = alpha_true @ rotor_unbalance
    trials = polar([5e-3, 5e-3, 5e-3], [0.0, 90.0, 180.0])
    runs = initial[None, :] + (alpha_true * trials[None, :]).T
    alpha = influence_matrix(initial, runs, trials)
    # noise-free runs: alpha is exact up to the rounding of (run - initial) / trial
    np.testing.assert_allclose(alpha, alpha_true, rtol=1e-12, atol=1e-12 * np.abs(alpha_true).max())
    for method in ("least_squares", "minmax"):
        result = correction(alpha, initial, method=method)
        assert result.worst_residual <= 1e-9 * result.worst_initial, method
        np.testing.assert_allclose(result.unbalance_kg_m, -rotor_unbalance, rtol=1e-9)


def test_minmax_worst_residual_never_above_least_squares_with_5_percent_noise():
    rng = np.random.default_rng(17)
    alpha_true = rotor_alpha([150.0, 400.0])
    trials = polar([2e-2, 2e-2, 2e-2], [0.0, 90.0, 180.0])  # changes every run by well over 10 %
    improved = 0
    for _ in range(30):
        rotor_unbalance = (rng.normal(size=3) + 1j * rng.normal(size=3)) * 2e-3
        clean_initial = alpha_true @ rotor_unbalance
        clean_runs = clean_initial[None, :] + (alpha_true * trials[None, :]).T

        def noisy(z):  # 5 % reading noise: complex Gaussian, relative to each reading
            return z * (1 + 0.05 * (rng.normal(size=z.shape) + 1j * rng.normal(size=z.shape)) / math.sqrt(2))

        initial, runs = noisy(clean_initial), noisy(clean_runs)
        alpha = influence_matrix(initial, runs, trials)
        ls = correction(alpha, initial, method="least_squares")
        mm = correction(alpha, initial, method="minmax")
        assert mm.worst_residual <= ls.worst_residual
        assert mm.rms_residual >= ls.rms_residual * (1 - 1e-9)  # and least squares stays best in RMS
        improved += mm.worst_residual < ls.worst_residual * (1 - 1e-3)
        # min-max optimality certificate: random moves around the answer never lower the worst case
        moves = (rng.normal(size=(200, 3)) + 1j * rng.normal(size=(200, 3))) * 1e-3 * np.abs(mm.unbalance_kg_m).max()
        worst_moved = np.abs(initial[None, :] + (mm.unbalance_kg_m[None, :] + moves) @ alpha.T).max(axis=1)
        assert worst_moved.min() >= mm.worst_residual * (1 - 1e-6)  # the cutting-plane tolerance
    assert improved >= 20  # with 10 readings and 3 planes, min-max strictly beats least squares' worst case


def test_bound_per_plane_is_respected():
    alpha = rotor_alpha([150.0, 400.0])
    initial = alpha @ polar([2e-3, 1e-3, 3e-3], [30.0, 200.0, 110.0])
    for method in ("least_squares", "minmax"):
        result = correction(alpha, initial, method=method, max_unbalance_kg_m=1.5e-3)
        assert np.all(np.abs(result.unbalance_kg_m) <= 1.5e-3 * (1 + 1e-12))
        assert result.bound_active and "bound_active" in result.flags
        free = correction(alpha, initial, method=method)
        assert result.objective >= free.objective


def test_nearly_dependent_planes_warn():
    alpha = np.array([[1.0, 1.0 + 1e-3], [1.0, 1.0 - 1e-3], [1.0 + 1e-3j, 1.0]])
    with pytest.warns(QualityWarning, match="condition number"):
        result = correction(alpha, np.array([1.0, 1.0, 1.0]))
    assert "ill_conditioned" in result.flags and result.condition_number > 100


def test_weak_trial_warns():
    with pytest.warns(QualityWarning, match="trial_runs\\[0\\]"):
        influence_matrix(HS_INITIAL, np.array([HS_INITIAL * 1.01, HS_RUNS[1]]), HS_TRIALS)
