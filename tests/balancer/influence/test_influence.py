"""Field balancing with influence coefficients (balancer.influence), issue 17."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from balancer.influence import (
    allocate_to_planes,
    correction,
    equally_spaced_deg,
    influence_matrix,
    iso_check,
    jeffcott_influence,
    permissible_unbalance_kg_m,
    split_correction,
    trial_mass_kg,
    unbalance_kg_m,
    vibration,
)
from modal.errors import ParameterError, QualityWarning


def polar(amplitude, phase_deg):
    return np.asarray(amplitude) * np.exp(1j * np.deg2rad(phase_deg))


# ---------------------------------------------------------------- hsbalance's README example
# hsbalance (github.com/MagedMohamedTurk/Turbomachinery-Rotors-Balancing), README "Quick Example",
# taken there from B&K application note 17-227, table 2, example 6: two sensors, two planes,
# 1.15 g trial masses at 0 deg; readings "amplitude @ phase".  Its least-squares answer:
# 1.979 @ 236.2 and 1.071 @ 121.8 (printed to 3 and 1 decimals).
HS_INITIAL = polar([170.0, 53.0], [112.0, 78.0])
HS_RUNS = np.array([polar([235.0, 58.0], [94.0, 68.0]), polar([185.0, 77.0], [115.0, 104.0])])
HS_TRIALS = polar([1.15, 1.15], [0.0, 0.0])


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


# ---------------------------------------------------------------- ISO 21940-11
def test_iso_21940_11_worked_example_symmetric_rotor():
    # G 2.5, 100 kg, 3000 rpm: Omega = 314.159 rad/s, e_per = G / Omega = 7.958 um,
    # U_per = e_per m = 795.8 g mm; mass centre midway: 397.9 g mm per bearing plane.
    u_per = permissible_unbalance_kg_m(2.5, 100.0, 3000.0)
    assert u_per * 1e6 == pytest.approx(795.7747, rel=1e-6)
    check = iso_check(polar([390e-6, 400e-6], [0.0, 45.0]), 2.5, 100.0, 3000.0)
    np.testing.assert_allclose(check.permissible_per_plane_kg_m * 1e6, [397.887, 397.887], rtol=1e-5)
    assert check.passes.tolist() == [True, False] and check.verdict == "fail"


def test_iso_21940_11_worked_example_mass_centre_near_one_bearing():
    # G 6.3, 500 kg, 1500 rpm: U_per = 6.3e-3 * 500 / 157.080 = 20 053.5 g mm.  Mass centre 0.1 m
    # from A and 0.3 m from B: the lever rule gives A 75 %, B 25 %; the 30-70 % limit makes it
    # A 70 % = 14 037.5 g mm, B 30 % = 6 016.0 g mm.
    u_per = permissible_unbalance_kg_m(6.3, 500.0, 1500.0)
    assert u_per * 1e6 == pytest.approx(20053.523, rel=1e-6)
    a, b = allocate_to_planes(u_per, 0.1, 0.3)
    assert (a * 1e6, b * 1e6) == pytest.approx((14037.466, 6016.057), rel=1e-6)
    # without the limit at play (mass centre 0.2 / 0.3 m): A 60 %, B 40 %
    assert allocate_to_planes(u_per, 0.2, 0.3) == pytest.approx((0.6 * u_per, 0.4 * u_per), rel=1e-12)
    check = iso_check([14e-3, 6.1e-3], 6.3, 500.0, 1500.0, distances_m=(0.1, 0.3))
    assert check.passes.tolist() == [True, False]


# ---------------------------------------------------------------- splitting onto holes
def test_split_is_exact_on_random_vectors():
    rng = np.random.default_rng(3)
    for n_holes in (3, 5, 8, 12):
        positions = np.sort(rng.uniform(0, 360, n_holes)) if n_holes == 12 else equally_spaced_deg(n_holes, 10.0)
        gaps = np.diff(np.concatenate([np.sort(positions), [np.sort(positions)[0] + 360]]))
        if gaps.max() >= 180:
            continue
        u = (rng.normal(size=500) + 1j * rng.normal(size=500)) * 10 ** rng.uniform(-4, 0, 500)
        amounts = split_correction(u, positions)
        rebuilt = amounts @ np.exp(1j * np.deg2rad(positions))
        np.testing.assert_allclose(rebuilt, u, rtol=0, atol=1e-12 * np.abs(u).max())
        assert np.all(amounts >= 0)
        assert np.all((amounts > 0).sum(axis=1) <= 2)
        order = np.argsort(np.mod(positions, 360))
        for row in amounts[:, order]:  # non-zero amounts on adjacent holes (cyclically)
            nz = np.flatnonzero(row)
            if nz.size == 2:
                assert nz[1] - nz[0] in (1, n_holes - 1)
    np.testing.assert_allclose(split_correction(2.0 * np.exp(1j * np.deg2rad(90)), [0, 90, 180, 270]), [0, 2, 0, 0], atol=1e-15)


def test_split_refuses_a_gap_wider_than_half_a_turn():
    with pytest.raises(ParameterError, match="positions_deg"):
        split_correction(np.exp(1j * np.deg2rad(200)), [0.0, 90.0])


# ---------------------------------------------------------------- Jeffcott model against the adb equations
@pytest.mark.parametrize("speed_ratio", [0.6, 1.0, 1.7])
def test_jeffcott_influence_matches_direct_simulation(speed_ratio):
    """Steady 1x orbit of the adb rotor without balls, integrated from rest, against the model alpha.

    Transients decay as exp(-zeta omega_n t) = exp(-0.1 * 100 * 2.5) ~ 1e-11; DOP853 at rtol 1e-11:
    the fitted amplitude agrees to 1e-6.
    """
    from balancer.adb.equations import scalar_rhs

    M, k, e = 2.0, 2e4, 1e-4  # omega_n = 100 rad/s
    c = 2 * 0.1 * math.sqrt(k * M)  # zeta = 0.1
    omega = speed_ratio * math.sqrt(k / M)
    rhs = scalar_rhs(M, 0.0, 0, 0.05, e, k, c, 0.0, frame="fixed")
    t_end = 2.5
    period = 2 * math.pi / omega
    t_fit = np.linspace(t_end - 2 * period, t_end, 200)
    sol = solve_ivp(lambda t, y: rhs(y, omega, 0.0), (0.0, t_end), np.zeros(5), method="DOP853",
                    rtol=1e-11, atol=1e-16, t_eval=t_fit)
    x, y, theta = sol.y[0], sol.y[1], sol.y[4]
    # fit x + i y = X exp(i theta) + X' exp(-i theta) (forward and backward whirl; the latter ~ 0)
    basis = np.column_stack([np.exp(1j * theta), np.exp(-1j * theta)])
    forward, backward = np.linalg.lstsq(basis, x + 1j * y, rcond=None)[0]
    assert abs(backward) <= 1e-6 * abs(forward)
    # lag convention: reading = conj(rotation-convention amplitude), unbalance M e at angle 0
    predicted = jeffcott_influence(k, c, M, omega) * (M * e)
    assert np.conj(forward) == pytest.approx(predicted, rel=1e-6)
    lag = math.degrees(np.angle(predicted))
    assert lag == pytest.approx(math.degrees(math.atan2(c * omega, k - M * omega**2)), abs=1e-9)


def test_jeffcott_velocity_and_trial_mass():
    k, c, M, w = 1e5, 50.0, 10.0, 150.0
    d = jeffcott_influence(k, c, M, w)
    assert jeffcott_influence(k, c, M, w, "velocity") == pytest.approx(-1j * w * d)
    assert jeffcott_influence(k, c, M, w, "acceleration") == pytest.approx(-w * w * d)
    # 100 kg rotor, 3000 rpm, trial at 0.2 m on one of two planes: 10 % of 490 N -> 49.03 N = m r Omega^2
    m_t = trial_mass_kg(100.0, 3000.0, 0.2, n_planes=2)
    assert m_t * 0.2 * (math.pi * 100) ** 2 == pytest.approx(0.1 * 100 * 9.80665 / 2, rel=1e-12)


def test_readings_in_users_units():
    z = vibration([100.0, 2.0], [30.0, 390.0], "µm")
    np.testing.assert_allclose(z, polar([100e-6, 2e-6], [30.0, 30.0]), rtol=1e-14)
    np.testing.assert_allclose(vibration(1.0, 0.0, "g"), 9.80665)
    np.testing.assert_allclose(vibration(1.0, 0.0, "mil"), 25.4e-6)
    np.testing.assert_allclose(unbalance_kg_m(10.0, 0.1, 90.0, "g"), 1e-3j, atol=1e-18)


# ---------------------------------------------------------------- bad readings
def assert_one_line_error(call, field):
    """Assert that ``call`` raises a ParameterError whose message is one line naming ``field``."""
    with pytest.raises(ParameterError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message and field in message, message
    return message


def test_bad_readings_give_one_line_errors_naming_the_field():
    alpha = influence_matrix(HS_INITIAL, HS_RUNS, HS_TRIALS)
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, HS_RUNS[:1], HS_TRIALS), "trial_runs")  # fewer runs than planes
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, np.array([HS_RUNS[0], HS_INITIAL]), HS_TRIALS), "trial_runs[1]")
    nan_initial = HS_INITIAL.copy()
    nan_initial[1] = np.nan
    assert_one_line_error(lambda: influence_matrix(nan_initial, HS_RUNS, HS_TRIALS), "initial[1]")
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, HS_RUNS[:, :1], HS_TRIALS), "trial_runs")  # mismatched shapes
    assert_one_line_error(lambda: correction(alpha, HS_INITIAL[:1]), "alpha")
    assert_one_line_error(lambda: influence_matrix(HS_INITIAL, HS_RUNS, [1.15, 0.0]), "trial_unbalances[1]")
    singular = np.column_stack([alpha[:, 0], 2 * alpha[:, 0]])
    assert_one_line_error(lambda: correction(singular, HS_INITIAL), "alpha")
    assert_one_line_error(lambda: correction(alpha, HS_INITIAL, method="l1"), "method")
    assert_one_line_error(lambda: vibration([1.0], [1.0], "furlongs"), "units")


def test_nearly_dependent_planes_warn():
    alpha = np.array([[1.0, 1.0 + 1e-3], [1.0, 1.0 - 1e-3], [1.0 + 1e-3j, 1.0]])
    with pytest.warns(QualityWarning, match="condition number"):
        result = correction(alpha, np.array([1.0, 1.0, 1.0]))
    assert "ill_conditioned" in result.flags and result.condition_number > 100


def test_weak_trial_warns():
    with pytest.warns(QualityWarning, match="trial_runs\\[0\\]"):
        influence_matrix(HS_INITIAL, np.array([HS_INITIAL * 1.01, HS_RUNS[1]]), HS_TRIALS)
