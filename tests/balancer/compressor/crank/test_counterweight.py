"""The exact counterweight optimum (balancer.compressor.crank.counterweight): seed 000 and seed 004,
the curve of equal optima, other objectives, the grid search, results and bad arguments.

Paper numbers come from seed 000 (hermetic compressor, Table 1 and the results table) and seed 004
(slider-crank, R = 35 mm, L = 140 mm), as decoded in ``../shared/reference/crank_drive.md``.
Tolerances are half a unit in the last printed digit unless a comment says otherwise.
"""
from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pytest
from hypothesis import given, seed, settings
from hypothesis import strategies as st

from support.crank import mass_written_out, R_000_M, SPEED_000_RPM

from balancer.compressor import crank
from balancer.compressor.crank import (
    counterweight_mass,
    PAPER_RULES,
    SliderCrank,
    counterweight_on_curve,
    evaluate_balance_fraction,
    evaluate_counterweight,
    grid_search_counterweight,
    max_shaking_force,
    optimal_counterweight,
    shaking_force,
    shaking_harmonics,
    shaking_objective,
    two_mass_split,
)
from modal.errors import ParameterError


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
    paper_point = max_shaking_force(exact, SPEED_000_RPM, mass_written_out(exact, 0.6218), 0.011583)
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
@pytest.mark.stress_quick
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
