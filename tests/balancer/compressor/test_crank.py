"""Slider-crank shaking forces and the exact counterweight optimum (issue 5).

Paper numbers come from seed 000 (hermetic compressor, Table 1 and the results
table) and seed 004 (slider-crank, R = 35 mm, L = 140 mm), as decoded in
``../shared/reference/crank_drive.md``.  Tolerances are half a unit in the last
printed digit unless a comment says otherwise.
"""
from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pytest
from hypothesis import given, seed, settings
from hypothesis import strategies as st

from balancer.compressor import crank
from balancer.compressor.crank import (
    PAPER_RULES,
    SliderCrank,
    balance_fraction,
    counterweight_mass,
    counterweight_on_curve,
    evaluate_balance_fraction,
    evaluate_counterweight,
    grid_search_counterweight,
    max_shaking_force,
    optimal_counterweight,
    shaking_force,
    shaking_harmonics,
    shaking_objective,
    slider_crank_from_components,
    two_mass_split,
)
from modal.errors import ParameterError

SPEED_000_RPM = 2950.0
R_000_M = 0.0119
DEG_GRID = np.deg2rad(np.arange(360.0))  # the paper's 1 deg angle grid


@pytest.fixture
def seed000() -> SliderCrank:
    # Table 1: m_A = 0.067, m_G = 0.044, m_B = 0.134 kg, a = 16.3 mm, l = 50 mm.
    return slider_crank_from_components(
        crank_radius_m=R_000_M, rod_length_m=0.050, rod_mass_kg=0.044,
        rod_cg_to_crank_pin_m=0.0163, crank_pin_mass_kg=0.067, piston_mass_kg=0.134)


@pytest.fixture
def seed004() -> SliderCrank:
    return SliderCrank(0.035, 0.140, 0.55, 1.13)


def _mass(mech: SliderCrank, k: float) -> float:
    # written out here rather than calling counterweight_mass, so the table
    # test does not depend on the function it could be checking
    return mech.rotating_mass_kg + k * mech.reciprocating_mass_kg


def _second_derivative(fun, x, h=1e-3):
    """Five-point central second difference (error O(h^4))."""
    return (-fun(x + 2 * h) + 16 * fun(x + h) - 30 * fun(x) + 16 * fun(x - h)
            - fun(x - 2 * h)) / (12 * h ** 2)


# ----------------------------------------------------------------------------- model
def test_two_mass_split_gives_the_exact_lumped_masses(seed000):
    # m_rot = m_A + m_G b/l, m_rec = m_B + m_G a/l: exact arithmetic, so only
    # rounding error (1e-15) separates them from 0.096656 and 0.148344 kg.
    assert seed000.rotating_mass_kg == pytest.approx(0.096656, abs=1e-12)
    assert seed000.reciprocating_mass_kg == pytest.approx(0.148344, abs=1e-12)
    split = two_mass_split(0.140, 0.3, 0.140 / 3, crank_pin_mass_kg=0.35, piston_mass_kg=1.03,
                           rod_inertia_about_cg_kg_m2=1e-3)
    # seed 004 eqs. 6-7: m_tq = m2 + 2/3 m3 = 0.55, m_ct = m4 + 1/3 m3 = 1.13 kg.
    assert split.rotating_mass_kg == pytest.approx(0.55, abs=1e-12)
    assert split.reciprocating_mass_kg == pytest.approx(1.13, abs=1e-12)
    assert split.rod_inertia_correction_kg_m2 == pytest.approx(
        1e-3 - 0.3 * (0.14 / 3) * (0.28 / 3), rel=1e-12)


def test_exact_piston_acceleration_matches_finite_differences():
    # Independent check of the closed form: differentiate the piston position
    # y = r cos(t) + sqrt(l^2 - r^2 sin^2 t) twice numerically with the 5-point
    # stencil, h = 1e-3: truncation ~h^4 y^(6)/90 ~ 1e-15 m, rounding
    # ~16 eps y / (12 h^2) ~ 3e-11 m; times omega^2 ~ 1.1e4 gives < 1e-6 N.
    mech = SliderCrank(0.035, 0.080, 0.0, 1.0, harmonics="exact")
    theta = np.linspace(0.1, 6.2, 50)

    def y(t):
        return 0.035 * np.cos(t) + np.sqrt(0.080 ** 2 - (0.035 * np.sin(t)) ** 2)

    y_dd = _second_derivative(y, theta)
    omega = 2 * math.pi * 1000 / 60
    force = shaking_force(mech, 1000.0, theta)
    # the shaking force of the piston is -m_rec * acceleration = -m_rec * omega^2 * y''
    np.testing.assert_allclose(force.force_y_n, -omega ** 2 * y_dd, rtol=0, atol=1e-5)
    np.testing.assert_array_equal(force.force_x_n, 0.0)


def test_exact_rod_couple_matches_finite_differences():
    # M_z = J_AB * rod angular acceleration, phi = asin(lam sin t): same check.
    j_ab = -2.0487e-5
    mech = SliderCrank(0.0119, 0.050, 0.1, 0.15, harmonics="exact",
                       rod_inertia_correction_kg_m2=j_ab)
    theta = np.linspace(0.05, 6.2, 40)

    def phi(t):
        return np.arcsin(0.238 * np.sin(t))

    phi_dd = _second_derivative(phi, theta)
    omega = 2 * math.pi * 2950 / 60
    couple = shaking_force(mech, 2950.0, theta).couple_z_n_m
    # rounding of the stencil: ~7e-11 rad/rad^2 times |J_AB| omega^2 ~ 2 -> 1e-9 N m
    np.testing.assert_allclose(couple, j_ab * omega ** 2 * phi_dd, rtol=1e-8, atol=1e-9)


def test_fourier_series_converges_to_the_exact_force():
    # With the exact Fourier coefficients the only error is the dropped orders,
    # which decay like lam^h: lam = 0.238, orders up to 14 leave < 0.238^16 ~ 1e-10.
    exact = SliderCrank(0.0119, 0.050, 0.096656, 0.148344, harmonics="exact")
    series = SliderCrank(0.0119, 0.050, 0.096656, 0.148344, harmonics=tuple(range(1, 15)),
                         series="fourier")
    theta = np.linspace(0, 2 * np.pi, 97)
    a = shaking_force(exact, 2950.0, theta, 0.15, 0.011)
    b = shaking_force(series, 2950.0, theta, 0.15, 0.011)
    scale = 0.148344 * 0.0119 * (2 * math.pi * 2950 / 60) ** 2
    np.testing.assert_allclose(b.force_y_n, a.force_y_n, atol=1e-9 * scale)
    np.testing.assert_allclose(b.force_x_n, a.force_x_n, atol=1e-9 * scale)


def test_leading_series_coefficients_are_the_leading_terms_of_the_fourier_ones():
    # 2x coefficient: lam + lam^3/4 + 15 lam^5/128 + O(lam^7) (standard series);
    # the papers' "leading" series keeps only lam.  lam = 0.1: O(lam^7) = 1e-7.
    mech = SliderCrank(0.01, 0.1, 0.0, 1.0, harmonics=(2, 4, 6), series="fourier")
    h = shaking_harmonics(mech, 60.0 / (2 * math.pi))  # omega = 1 rad/s
    a2, a4, a6 = h.force_n[:, 1].real / 0.01
    lam = 0.1
    assert a2 == pytest.approx(lam + lam ** 3 / 4 + 15 * lam ** 5 / 128, abs=1e-7 * 5)
    assert a4 == pytest.approx(-(lam ** 3 / 4 + 3 * lam ** 5 / 16), abs=1e-7 * 5)
    assert a6 == pytest.approx(9 * lam ** 5 / 128, abs=1e-7)


def test_harmonic_amplitudes_rebuild_the_time_signal(seed000):
    # f(t) = Re(sum X_h exp(i h t)) must equal the direct evaluation (1x+2x is a
    # trig polynomial, so the FFT is exact to rounding).
    mc, rc = _mass(seed000, 0.6218), 0.011583
    harm = shaking_harmonics(seed000, SPEED_000_RPM, mc, rc)
    theta = np.linspace(0, 2 * np.pi, 73)
    direct = shaking_force(seed000, SPEED_000_RPM, theta, mc, rc)
    rebuilt = np.real(np.exp(1j * np.outer(theta, harm.orders)) @ harm.force_n)
    np.testing.assert_allclose(rebuilt[:, 0], direct.force_x_n, atol=1e-9)
    np.testing.assert_allclose(rebuilt[:, 1], direct.force_y_n, atol=1e-9)
    # reference note section 2: 1x amplitudes 99.0 / 69.4 N, 2x F_y 40.1 N at the optimum
    assert abs(harm.force_n[0, 0]) == pytest.approx(99.0, abs=0.05)
    assert abs(harm.force_n[0, 1]) == pytest.approx(69.4, abs=0.05)
    assert abs(harm.force_n[1, 1]) == pytest.approx(40.1, abs=0.05)


# ----------------------------------------------------------------------------- seed 000
def test_seed000_table_on_the_papers_one_degree_grid(seed000):
    # The printed table has 4 decimals: agreement to 5e-5 N.
    assert max_shaking_force(seed000, SPEED_000_RPM, crank_angles_rad=DEG_GRID) == pytest.approx(
        318.3321, abs=5e-5)
    assert max_shaking_force(seed000, SPEED_000_RPM, _mass(seed000, 1.0), R_000_M,
                             crank_angles_rad=DEG_GRID) == pytest.approx(173.1739, abs=5e-5)
    printed = {11.563: 109.8853, 11.573: 109.7050, 11.583: 109.5247, 11.593: 109.6591,
               11.603: 109.8005}
    for radius_mm, force_n in printed.items():
        got = max_shaking_force(seed000, SPEED_000_RPM, _mass(seed000, 0.6218), radius_mm * 1e-3,
                                crank_angles_rad=DEG_GRID)
        assert got == pytest.approx(force_n, abs=5e-5), radius_mm


def test_seed000_abstract_ratio_is_a_typo(seed000):
    # The abstract's r_c/r = 0.9473 with k = 0.6218 gives 115.1 N (reference
    # note, 1 decimal), 5.6 N above the table's own optimum 109.5247 N at
    # r_c/r = 11.583/11.9 = 0.97336, so the abstract cannot be the table's point.
    m_c = counterweight_mass(seed000, 0.6218)
    abstract = max_shaking_force(seed000, SPEED_000_RPM, m_c, 0.9473 * R_000_M,
                                 crank_angles_rad=DEG_GRID)
    assert abstract == pytest.approx(115.1, abs=0.05)
    assert abstract > 109.5247 + 5.0


def test_exact_maximum_is_never_below_a_grid_maximum(seed000):
    # The exact max over the revolution bounds every sampled max from above;
    # the unbalanced and k = 1 peaks sit on grid angles (0 and 90 deg), so they agree.
    for k, rc in ((0.6218, 0.011593), (0.6218, 0.011583), (0.3, 0.006)):
        exact = max_shaking_force(seed000, SPEED_000_RPM, _mass(seed000, k), rc)
        grid = max_shaking_force(seed000, SPEED_000_RPM, _mass(seed000, k), rc,
                                 crank_angles_rad=DEG_GRID)
        assert exact >= grid - 1e-9
    assert max_shaking_force(seed000, SPEED_000_RPM) == pytest.approx(318.3321, abs=5e-5)
    assert max_shaking_force(seed000, SPEED_000_RPM, _mass(seed000, 1.0),
                             R_000_M) == pytest.approx(173.1739, abs=5e-5)


def test_seed000_exact_optimum(seed000):
    opt = optimal_counterweight(seed000, SPEED_000_RPM)
    # reference values alpha* = 0.5878955, F* = 109.522005 N: required to 1e-6 relative
    assert opt.balance_fraction == pytest.approx(0.5878955, rel=1e-6)
    assert opt.max_force_n == pytest.approx(109.522005, rel=1e-6)
    # two equal peaks, at 0 deg and 101.305 deg (printed to 3 decimals)
    assert opt.method == "equal-peak root"
    assert opt.peak_angles_rad.size == 2
    assert np.rad2deg(opt.peak_angles_rad[0]) == pytest.approx(0.0, abs=5e-4)
    assert np.rad2deg(opt.peak_angles_rad[1]) == pytest.approx(101.305, abs=5e-4)
    assert opt.peak_forces_n[0] == pytest.approx(opt.peak_forces_n[1], rel=1e-10)
    # below the paper's grid optimum 109.5247 N, and the reduction is 65.595 %
    assert opt.max_force_n < 109.5247
    assert opt.reduction == pytest.approx(0.65595, abs=5e-6)
    assert opt.unbalanced_max_force_n == pytest.approx(318.3321, abs=5e-5)


def test_optimum_is_a_minimum_of_the_convex_objective(seed000):
    # Optimality: no alpha on a grid does better; the objective rises on both sides.
    opt = optimal_counterweight(seed000, SPEED_000_RPM)
    alphas = np.linspace(-0.6, 1.0, 41)
    values = shaking_objective(seed000, SPEED_000_RPM, alphas)
    assert np.all(values >= opt.max_force_n * (1 - 1e-12))
    near = shaking_objective(seed000, SPEED_000_RPM,
                             opt.balance_fraction + np.array([-1e-5, 1e-5]))
    assert np.all(near > opt.max_force_n)
    # convexity on the sampled grid: second differences are non-negative
    assert np.all(np.diff(values, 2) >= -1e-9)


def test_optimum_alpha_is_speed_independent_and_force_scales_with_speed_squared(seed000):
    base = optimal_counterweight(seed000, 1500.0)
    # reference note: 28.3 / 50.3 / 78.7 / 113.3 N at 1500 / 2000 / 2500 / 3000 rpm
    for speed, printed in ((1500.0, 28.3), (2000.0, 50.3), (2500.0, 78.7), (3000.0, 113.3)):
        opt = optimal_counterweight(seed000, speed)
        assert opt.balance_fraction == pytest.approx(base.balance_fraction, abs=1e-10)
        assert opt.max_force_n == pytest.approx(base.max_force_n * (speed / 1500.0) ** 2,
                                                rel=1e-10)
        assert opt.max_force_n == pytest.approx(printed, abs=0.05)


def test_optimal_curve_is_a_family_of_equal_optima(seed000):
    opt = optimal_counterweight(seed000, SPEED_000_RPM, n_curve_points=11)
    curve = opt.curve
    assert curve.k[0] == pytest.approx(opt.balance_fraction, rel=1e-12)
    assert curve.k[-1] == 1.0
    assert np.all(curve.counterweight_radius_m <= R_000_M * (1 + 1e-12))
    # every (k, r_c) on the curve has the same m_c r_c, hence the same peak force
    np.testing.assert_allclose(curve.counterweight_mass_kg * curve.counterweight_radius_m,
                               opt.counterweight_moment_kg_m, rtol=1e-12)
    for m_c, r_c in zip(curve.counterweight_mass_kg[::5], curve.counterweight_radius_m[::5]):
        assert max_shaking_force(seed000, SPEED_000_RPM, m_c, r_c) == pytest.approx(
            opt.max_force_n, rel=1e-9)
    # reference table of the curve: r_c/r = 0.973374 at k = 0.6218 (the paper's
    # point), 0.7505 at k = 1; the lightest is 183.9 g at r_c = r.
    paper = counterweight_on_curve(seed000, opt, k=0.6218)
    assert paper.radius_ratio == pytest.approx(0.973374, abs=5e-7)
    assert paper.radius_m * 1e3 == pytest.approx(11.583, abs=5e-4)
    heavy = counterweight_on_curve(seed000, opt, k=1.0)
    assert heavy.radius_ratio == pytest.approx(0.7505, abs=5e-5)
    assert heavy.mass_kg == pytest.approx(0.245, abs=5e-7)
    light = counterweight_on_curve(seed000, opt)
    assert light.radius_ratio == pytest.approx(1.0, abs=1e-12)
    assert light.mass_kg * 1e3 == pytest.approx(183.9, abs=0.05)
    assert light.mass_kg < paper.mass_kg < heavy.mass_kg
    given_r = counterweight_on_curve(seed000, opt, radius_m=paper.radius_m)
    assert given_r.k == pytest.approx(0.6218, abs=1e-12)


def test_naive_equal_at_0_and_90_deg_rule_is_worse(seed000):
    # alpha = (1 + 2 lam) / (2 (1 + lam)) = 0.596 gives 110.61 N (reference note):
    # the side peak sits near 101 deg, not at 90 deg.
    lam = seed000.crank_rod_ratio
    naive = evaluate_balance_fraction(seed000, SPEED_000_RPM, (1 + 2 * lam) / (2 * (1 + lam)))
    assert naive.max_force_n == pytest.approx(110.61, abs=5e-3)
    assert naive.max_force_n > optimal_counterweight(seed000, SPEED_000_RPM).max_force_n


def test_exact_kinematics_move_the_answer_more_than_the_grid(seed000):
    exact = dataclasses.replace(seed000, harmonics="exact")
    paper_point = max_shaking_force(exact, SPEED_000_RPM, _mass(exact, 0.6218), 0.011583)
    assert paper_point == pytest.approx(109.97, abs=5e-3)  # reference note, 2 decimals
    opt = optimal_counterweight(exact, SPEED_000_RPM)
    assert opt.balance_fraction == pytest.approx(0.5864, abs=5e-5)
    assert opt.max_force_n == pytest.approx(109.77, abs=5e-3)
    truncated = optimal_counterweight(seed000, SPEED_000_RPM)
    # model error (about 0.25 N) exceeds the paper's grid gap (0.0027 N) by ~100x
    assert opt.max_force_n - truncated.max_force_n > 50 * (109.5247 - truncated.max_force_n)


def test_other_objectives(seed000):
    # RMS^2 = (m_rec r w^2)^2 / 2 * (alpha^2 + (1 - alpha)^2 + lam^2) for 1x+2x,
    # minimal at alpha = 1/2 exactly.
    rms = optimal_counterweight(seed000, SPEED_000_RPM, objective="rms")
    assert rms.balance_fraction == pytest.approx(0.5, abs=1e-7)
    scale = 0.148344 * R_000_M * (2 * math.pi * SPEED_000_RPM / 60) ** 2
    lam = seed000.crank_rod_ratio
    assert rms.objective_value_n == pytest.approx(scale * math.sqrt((0.5 + lam ** 2) / 2),
                                                  rel=1e-12)
    # max |F_x| = |alpha| m_rec r w^2: minimal (zero) at alpha = 0
    max_x = optimal_counterweight(seed000, SPEED_000_RPM, objective="max_x")
    assert max_x.balance_fraction == pytest.approx(0.0, abs=1e-8)
    assert max_x.objective_value_n == pytest.approx(0.0, abs=1e-6 * scale)
    # max |F_y| is smallest with full balance of 1x along the stroke (alpha = 1)
    max_y = optimal_counterweight(seed000, SPEED_000_RPM, objective="max_y")
    assert max_y.balance_fraction == pytest.approx(1.0, abs=1e-8)
    assert max_y.objective_value_n == pytest.approx(lam * scale, rel=1e-9)


# ----------------------------------------------------------------------------- seed 004
def test_seed004_rules_and_optimum(seed004):
    # printed / reference values to 1 decimal: 753.2 (none), 542.1 (rule 1),
    # 325.3 (rule 2), 285.5 N (optimum, alpha* = 0.5917) at 1000 rpm
    none = evaluate_counterweight(seed004, 1000.0)
    rule1 = evaluate_balance_fraction(seed004, 1000.0, "rotating")
    rule2 = evaluate_balance_fraction(seed004, 1000.0, "rotating_plus_half_reciprocating")
    opt = optimal_counterweight(seed004, 1000.0)
    assert none.max_force_n == pytest.approx(753.2, abs=0.05)
    assert rule1.max_force_n == pytest.approx(542.1, abs=0.05)
    assert rule2.max_force_n == pytest.approx(325.3, abs=0.05)
    assert opt.max_force_n == pytest.approx(285.5, abs=0.05)
    assert opt.balance_fraction == pytest.approx(0.5917, abs=5e-5)
    # rule 1 cancels the force across the stroke
    assert rule1.force_x_span_n == pytest.approx(0.0, abs=1e-9)
    # the paper's "about 900 N" and "about 460 N" are peak-to-peak spans (crank_drive.md: 867 N
    # along the stroke for rule 1; 488 N along and 434 N across for rule 2), derived here in
    # closed form with F0 = m_rec R w^2 and lambda = R/L = 1/4. Along the stroke the force is
    # -F0 (c cos t + lambda cos 2t), c = 1 (rule 1) or 1/2 (rule 2): rule 1 ranges over
    # [-(1 + lambda), 1 - lambda] F0, span 2 F0; rule 2 from 3/4 F0 (t = 0) to -3/8 F0
    # (cos t = -1/2), span 9/8 F0; across it is F0/2 sin t, span F0. Rounding only.
    f0 = 1.13 * 0.035 * (2 * math.pi * 1000.0 / 60.0) ** 2
    assert round(2 * f0) == 867 and round(9 / 8 * f0) == 488 and round(f0) == 434  # the reference's digits
    assert rule1.force_y_span_n == pytest.approx(2 * f0, rel=1e-12)
    assert rule2.force_y_span_n == pytest.approx(9 / 8 * f0, rel=1e-12)
    assert rule2.force_x_span_n == pytest.approx(f0, rel=1e-12)
    # "nearly 4x" at 2000 rpm is exactly 4x (omega^2)
    for evaluation, value in ((none, "none"), (rule1, "rotating"),
                              (rule2, "rotating_plus_half_reciprocating")):
        fast = (evaluate_counterweight(seed004, 2000.0) if value == "none"
                else evaluate_balance_fraction(seed004, 2000.0, value))
        assert fast.max_force_n == pytest.approx(4 * evaluation.max_force_n, rel=1e-12)
    assert optimal_counterweight(seed004, 2000.0).max_force_n == pytest.approx(
        4 * opt.max_force_n, rel=1e-10)
    assert PAPER_RULES == {"rotating": 0.0, "rotating_plus_half_reciprocating": 0.5}


def test_balance_fraction_round_trip(seed004):
    alpha = balance_fraction(seed004, 1.0, 0.035 * 0.9)
    assert alpha == pytest.approx((0.9 - 0.55) / 1.13, rel=1e-12)
    evaluation = evaluate_counterweight(seed004, 1000.0, 1.0, 0.035 * 0.9)
    assert evaluation.balance_fraction == pytest.approx(alpha, rel=1e-12)


# ----------------------------------------------------------------------------- grid search
def test_grid_search_never_beats_the_exact_optimum(seed000):
    opt = optimal_counterweight(seed000, SPEED_000_RPM)
    grid = grid_search_counterweight(seed000, SPEED_000_RPM, np.linspace(0, 1, 41),
                                     np.linspace(0, R_000_M, 41), np.deg2rad(np.arange(0, 360, 2)))
    # a grid maximum over angles can only under-read a peak, but the angle grid
    # contains 0 deg, the location of one of the two equal peaks, so the grid
    # optimum is bounded below by F* up to the under-read side peak.
    assert grid.max_force_n >= opt.max_force_n - 1e-9
    assert grid.max_force_n < opt.max_force_n * 1.05
    assert grid.n_evaluations == 41 * 41 * 180


def check_optimum_beats(lam, m_rot, m_rec, alpha):
    mech = SliderCrank(0.02, 0.02 / lam, m_rot, m_rec)
    opt = optimal_counterweight(mech, 1000.0, n_curve_points=3)
    alpha = max(alpha, -m_rot / m_rec)
    assert shaking_objective(mech, 1000.0, alpha) >= opt.max_force_n * (1 - 1e-10)


OPTIMUM_ARGS = dict(lam=st.floats(0.05, 0.45), m_rot=st.floats(0.0, 2.0), m_rec=st.floats(0.05, 2.0),
                    alpha=st.floats(-1.0, 1.0))


# the default run draws the same 15 cases every time (derandomised, no example database);
# the stress run explores (its own seed, STRESS_SEED, and many more cases)
@settings(max_examples=15, deadline=None, derandomize=True, database=None)
@given(**OPTIMUM_ARGS)
def test_exact_optimum_beats_any_balance_fraction(lam, m_rot, m_rec, alpha):
    check_optimum_beats(lam, m_rot, m_rec, alpha)


@pytest.mark.stress
@seed(int(os.environ.get("STRESS_SEED", "8")))
@settings(max_examples=int(os.environ.get("STRESS_EXAMPLES", "500")), deadline=None, database=None)
@given(**OPTIMUM_ARGS)
def test_stress_exact_optimum_beats_any_balance_fraction(lam, m_rot, m_rec, alpha):
    check_optimum_beats(lam, m_rot, m_rec, alpha)


# ----------------------------------------------------------------------------- results
def _plain(value) -> bool:
    if dataclasses.is_dataclass(value):
        return all(_plain(getattr(value, f.name)) for f in dataclasses.fields(value))
    if isinstance(value, tuple):
        return all(_plain(v) for v in value)
    return isinstance(value, (int, float, str, bool, np.ndarray, np.integer, np.floating))


def test_results_are_frozen_and_archivable(seed000):
    results = [optimal_counterweight(seed000, SPEED_000_RPM, n_curve_points=3),
               evaluate_counterweight(seed000, SPEED_000_RPM),
               shaking_force(seed000, SPEED_000_RPM), shaking_harmonics(seed000, SPEED_000_RPM),
               seed000]
    for result in results:
        assert _plain(result), type(result)
        with pytest.raises(dataclasses.FrozenInstanceError):
            result.speed_rpm = 1.0  # type: ignore[misc]


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, match", [
    (dict(rotating_mass_kg=-0.1), "rotating_mass_kg = -0.1"),
    (dict(reciprocating_mass_kg=-1), "reciprocating_mass_kg = -1"),
    (dict(rod_length_m=0.01), "rod must be longer than the crank"),
    (dict(crank_radius_m=0.0), "crank_radius_m = 0.0"),
    (dict(crank_radius_m=float("nan")), "crank_radius_m = nan"),
    (dict(harmonics=(1, 8)), "harmonics"),
    (dict(harmonics="exactly"), "harmonics = 'exactly'"),
    (dict(harmonics=(1.5,)), "harmonics"),
    (dict(series="taylor"), "series = 'taylor'"),
])
def test_bad_mechanism_raises(kwargs, match):
    args = dict(crank_radius_m=0.0119, rod_length_m=0.05, rotating_mass_kg=0.1,
                reciprocating_mass_kg=0.15)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=match):
        SliderCrank(**args)


def test_bad_call_arguments_raise(seed000):
    with pytest.raises(ParameterError, match=r"counterweight_radius_m = 0\.02.*r_c <= crank_radius_m"):
        max_shaking_force(seed000, 2950.0, 0.2, 0.02)
    with pytest.raises(ParameterError, match="counterweight_mass_kg = -0.2"):
        max_shaking_force(seed000, 2950.0, -0.2, 0.01)
    with pytest.raises(ParameterError, match=r"speed_rpm = 0\.0: expected a value > 0"):
        max_shaking_force(seed000, 0.0)
    with pytest.raises(ParameterError, match=r"speed_rpm = -5\.0"):
        optimal_counterweight(seed000, -5.0)
    with pytest.raises(ParameterError, match="crank_angles_rad contains NaN"):
        max_shaking_force(seed000, 2950.0, crank_angles_rad=[0.0, float("nan")])
    with pytest.raises(ParameterError, match="crank_angles_rad has shape"):
        max_shaking_force(seed000, 2950.0, crank_angles_rad=[])
    with pytest.raises(ParameterError, match="objective = 'mean'"):
        optimal_counterweight(seed000, 2950.0, objective="mean")
    with pytest.raises(ParameterError, match="reciprocating_mass_kg = 0.0: expected > 0"):
        optimal_counterweight(SliderCrank(0.01, 0.05, 0.1, 0.0), 2950.0)
    with pytest.raises(ParameterError, match="balance_fraction_value = 'half'"):
        evaluate_balance_fraction(seed000, 2950.0, "half")
    opt = optimal_counterweight(seed000, 2950.0, n_curve_points=3)
    with pytest.raises(ParameterError, match=r"k = 0\.2: expected a value >= "):
        counterweight_on_curve(seed000, opt, k=0.2)
    with pytest.raises(ParameterError, match="radius_m = 0.001: needs k"):
        counterweight_on_curve(seed000, opt, radius_m=0.001)
    with pytest.raises(ParameterError, match="k_values contains NaN"):
        grid_search_counterweight(seed000, 2950.0, [0.5, float("nan")], [0.01], [0.0])
    with pytest.raises(ParameterError, match="radius_values_m spans"):
        grid_search_counterweight(seed000, 2950.0, [0.5], [0.02], [0.0])
    with pytest.raises(ParameterError, match="reciprocating_mass_kg = 0.0"):
        evaluate_counterweight(SliderCrank(0.01, 0.05, 0.1, 0.0), 2950.0)
    with pytest.raises(ParameterError, match="give k or radius_m"):
        counterweight_on_curve(seed000, opt, k=0.7, radius_m=0.01)
    with pytest.raises(ParameterError, match=r"k = 1\.2: expected a value <= 1\.0"):
        counterweight_mass(seed000, 1.2)
    with pytest.raises(ParameterError, match="rod_cg_to_crank_pin_m = 0.06"):
        two_mass_split(0.05, 0.044, 0.06)
    assert crank.OBJECTIVES == ("max", "rms", "max_x", "max_y")


# ----------------------------------------------------------------------------- plots
def test_plots_draw_the_computed_data_without_pyplot(seed000):
    import inspect

    from matplotlib.figure import Figure

    from balancer.compressor import crank_plots

    opt = optimal_counterweight(seed000, SPEED_000_RPM, n_curve_points=5)
    light = counterweight_on_curve(seed000, opt)
    fig = crank_plots.plot_force_vs_angle(seed000, SPEED_000_RPM, light.mass_kg, light.radius_m)
    assert isinstance(fig, Figure)
    resultant = fig.axes[0].lines[2].get_ydata()
    # the drawn |F| never exceeds the exact peak, and reaches it at 0 deg
    assert resultant.max() <= opt.max_force_n * (1 + 1e-12)
    assert resultant[0] == pytest.approx(opt.max_force_n, rel=1e-9)

    fig = crank_plots.plot_force_locus(seed000, SPEED_000_RPM, light.mass_kg, light.radius_m)
    before, after = fig.axes[0].lines[:2]
    assert np.hypot(before.get_xdata(), before.get_ydata()).max() == pytest.approx(
        318.3321, abs=5e-5)
    assert np.hypot(after.get_xdata(), after.get_ydata()).max() <= opt.max_force_n * (1 + 1e-12)

    fig = crank_plots.plot_objective(seed000, SPEED_000_RPM, opt)
    marker = fig.axes[0].lines[1]
    assert marker.get_xdata()[0] == opt.balance_fraction
    assert fig.axes[0].lines[0].get_ydata().min() >= opt.max_force_n

    fig = crank_plots.plot_optimal_curve(opt)
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(),
                               opt.curve.counterweight_radius_m * 1e3)
    # drawing on a caller's axes returns that axes' figure
    own = Figure()
    axes = own.add_subplot()
    assert crank_plots.plot_optimal_curve(opt, ax=axes) is own
    # the module never touches pyplot state
    source = inspect.getsource(crank_plots)
    assert "import matplotlib.pyplot" not in source and "plt." not in source


def test_every_public_parameter_is_documented():
    # numpydoc discipline (style guide 1.7 item 8), without a numpydoc dependency
    import inspect
    import re

    from balancer.compressor import crank_plots, mounts

    missing = []
    for module in (crank, mounts, crank_plots):
        for name in module.__all__:
            obj = getattr(module, name)
            if not callable(obj):
                continue
            doc = inspect.getdoc(obj) or ""
            missing += [f"{module.__name__}.{name}({p})" for p in inspect.signature(obj).parameters
                        if not re.search(rf"\b{p}\b", doc)]
    assert missing == []


@pytest.mark.parametrize("series", [None, "leading"])
def test_objective_of_many_fractions_is_each_fractions_own(seed000, series):
    # shaking_objective searches every fraction's peaks at once (one numpy call per zoom pass); the same
    # grid and passes as one fraction at a time (the scalar path), so the same numbers to the last bit
    mech = seed000 if series is None else dataclasses.replace(seed000, series=series)
    alphas = np.linspace(-0.5, 1.0, 31)
    together = shaking_objective(mech, SPEED_000_RPM, alphas)
    alone = [shaking_objective(mech, SPEED_000_RPM, [a])[0] for a in alphas]
    np.testing.assert_array_equal(together, alone)
