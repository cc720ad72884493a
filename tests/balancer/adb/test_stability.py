"""Stability of the balanced state over speed (balancer.adb.stability): the reference case and the
literature's findings, stability maps and intervals.

Reference numbers come from the reference case (M = 1 kg, two 20 g balls on a 50 mm race, k = 10 kN/m)
and the research note's independent script (``adb.md`` section 2 "Findings" and section 5); they are
reproduced, not tuned.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from balancer.adb import (
    ADBParameters,
    ParameterStd,
    balanced_ball_angles,
    balanced_stability,
    balanced_state,
    characteristic_polynomial,
    find_equilibria,
    routh_hurwitz,
    routh_hurwitz_n2,
    stability_map,
    stable_speed_intervals,
    threshold_sensitivity,
)

from balancer.adb.linear import MARGINAL, STABLE, UNSTABLE
from modal.errors import ParameterError


S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s


def quoted(text: str):
    """A reference number as printed: it stands for every value that rounds to it, so the
    tolerance is half a unit of its last digit (1.604 -> +-5e-4, 1.3956 -> +-5e-5), plus the
    boundary's own refinement (xtol_ratio 1e-10 of omega_n)."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return pytest.approx(float(text), abs=0.5 * 10.0**-decimals + 1e-10)


def test_reference_threshold_and_angles():
    result = stable_speed_intervals(S1, 60 * WN)
    assert WN == pytest.approx(98.058, abs=5e-4)
    assert len(result) == 1
    low, high = result[0]
    assert low / WN == quoted("1.3956")
    assert result.reaches_speed_max and high == pytest.approx(60 * WN)
    # closed form for two balls: cos(phi) = -a/2 with a = M e / (m R) = 0.5 (104.4775 deg; the
    # reference case quotes 104.5); the library's angles come from the same balance equations, so they
    # agree to rounding of an arccos (~1e-16 rad; 1e-10 leaves room for a numerical solve)
    a = S1.M * S1.e / (S1.m * S1.R)
    angles = np.sort(balanced_ball_angles(S1))
    assert np.allclose(angles, [-math.acos(-a / 2), math.acos(-a / 2)], rtol=0, atol=1e-10)
    assert np.degrees(angles[1]) == quoted("104.5")
    assert list(result) == [result[0]]


def test_stable_just_above_unstable_just_below_threshold():
    low = stable_speed_intervals(S1, 10 * WN, xtol_ratio=1e-12).lowest_stable_speed_rad_s
    # Brent's boundary to 1e-12 omega_n; step 1e-6 omega_n is far outside that and the
    # growth rate there (~1e-7 omega_n) is far above the rounding bound (~1e-12).
    check = balanced_stability(S1, [low - 1e-6 * WN, low + 1e-6 * WN])
    assert list(check.stability_class) == [UNSTABLE, STABLE]


def test_routh_hurwitz_agrees_with_eigenvalues_at_every_speed():
    ratios = np.concatenate([np.linspace(0.1, 3.0, 59), [0.95, 1.05, 1.3956488, 5.0, 20.0, 60.0]])
    eig = balanced_stability(S1, ratios * WN)
    for ratio, values, code in zip(ratios, eig.eigenvalues_per_s, eig.stability_class):
        if code == MARGINAL:
            continue
        rh = routh_hurwitz_n2(S1, ratio * WN)
        assert rh.regular
        assert rh.sign_changes == int(np.sum(values.real > 0)), ratio
        assert rh.stable == (code == STABLE)
        assert np.all(rh.hurwitz_minors > 0) == (code == STABLE)


def test_characteristic_polynomial_has_the_eigenvalues_as_roots():
    # Coefficients from an FFT of sampled determinants (no eigen-solver); compare the
    # polynomial's roots with the eigenvalues; roots of a degree-8 polynomial with O(1)
    # coefficients are accurate to ~1e-12 when simple.
    speed = 2.0 * WN
    coeffs = characteristic_polynomial(S1, speed)
    roots = np.sort_complex(np.roots(coeffs))
    eig = np.sort_complex(balanced_stability(S1, [speed]).eigenvalues_per_s[0] / WN)
    assert np.max(np.abs(roots - eig)) < 1e-9
    # every coefficient positive at Omega = 1.05, yet unstable (adb.md section 5)
    rh = routh_hurwitz_n2(S1, 1.05 * WN)
    assert np.all(rh.coefficients > 0) and not rh.stable and rh.sign_changes == 2


def test_routh_simple_polynomials():
    assert routh_hurwitz([1, 3, 3, 1]).stable  # (s+1)^3
    assert routh_hurwitz([1, -1, 2]).sign_changes == 2
    assert not routh_hurwitz([1, 0, 1]).regular  # roots on the imaginary axis
    with pytest.raises(ParameterError):
        routh_hurwitz([0.0, 1.0])


# research note table (section 5): lower bound of the stable interval, scanned to 60 omega_n
@pytest.mark.parametrize(
    "name, changes, threshold",
    [
        ("S2", dict(n=5), "1.604"),
        ("S3", dict(c=2.0), "1.711"),
        ("S4", dict(D=2e-2), "1.006"),
        ("S5", dict(D=1e-4), "1.754"),
        ("S6", dict(n=3), "1.461"),
    ],
)
def test_literature_sets_thresholds(name, changes, threshold):
    p = S1.replace(**changes)
    result = stable_speed_intervals(p, 60 * p.natural_frequency_rad_s)
    assert len(result) == 1 and result.reaches_speed_max
    assert result.intervals_ratio[0, 0] == quoted(threshold)


def test_no_balancing_below_the_natural_frequency():
    # no balancing below omega_n (Thearle; Lee & Van Moorhem; adb.md): every stable interval starts above it.
    rng = np.random.default_rng(4)
    for _ in range(24):
        n = int(rng.integers(2, 6))
        p = ADBParameters.from_nondimensional(
            n=n, mass_ratio=float(rng.uniform(0.005, 0.6 / (n + 1))),
            unbalance_ratio=float(rng.uniform(0.05, 0.95 * n)),
            damping_ratio=float(10 ** rng.uniform(-2.5, -0.5)), drag_ratio=float(10 ** rng.uniform(-2, 1)),
        )
        result = balanced_stability(p, np.linspace(0.01, 1.0, 300) * p.natural_frequency_rad_s)
        assert not np.any(result.stability_class == STABLE)


def test_drag_lowers_threshold_and_low_drag_never_balances():
    # raising beta lowers the threshold (S5 -> S1 -> S4; adb.md); the drag condition beta > kappa zeta:
    # S7 (beta/zeta = 0.010 below kappa = 0.016) is unstable at every speed up to 60 omega_n.
    thresholds = [stable_speed_intervals(S1.replace(D=d), 20 * WN).intervals_ratio[0, 0] for d in (1e-4, 1e-3, 2e-2)]
    assert thresholds[0] > thresholds[1] > thresholds[2] > 1.0
    s7 = stable_speed_intervals(S1.replace(D=5e-6), 60 * WN, speed_min_rad_s=0.02 * WN, grid_points=3000)
    assert len(s7) == 0 and s7.lowest_stable_speed_rad_s == math.inf


def test_split_stable_region_for_heavy_balls():
    # heavier balls can split the stable region (adb.md): n = 2, mu = 0.1, a = 0.3, zeta = beta = 0.01 -> [1.184, 1.468] U [2.737, >= 100]
    p = ADBParameters.from_nondimensional(n=2, mass_ratio=0.1, unbalance_ratio=0.3, damping_ratio=0.01, drag_ratio=0.01)
    result = stable_speed_intervals(p, 100 * p.natural_frequency_rad_s, grid_points=4000)
    assert len(result) == 2 and result.reaches_speed_max
    assert list(result.intervals_ratio[0]) == [quoted("1.184"), quoted("1.468")]
    assert result.intervals_ratio[1, 0] == quoted("2.737")


def test_stability_map_matches_pointwise_analysis():
    speeds = np.linspace(0.3, 4, 40) * WN
    drags = np.geomspace(1e-6, 0.1, 30)
    screened = stability_map(S1, speeds, "D", drags)
    full = stability_map(S1, speeds, "D", drags, condition_cap=None)
    assert screened.stability_class.shape == (30, 40)
    assert np.array_equal(screened.stability_class, full.stability_class)
    row = balanced_stability(S1.replace(D=drags[7]), speeds)
    assert np.array_equal(screened.stability_class[7], row.stability_class)
    # same matrices, same LAPACK routine family: growth rates agree to rounding
    assert np.allclose(screened.max_real_part_per_s[7], row.max_real_part_per_s, rtol=1e-9, atol=1e-9 * WN)
    counts = stability_map(S1, speeds, "n", [2, 3, 5]).class_counts
    assert counts["stable"] > 0 and counts["unstable"] > 0
    with pytest.raises(ParameterError, match="parameter"):
        stability_map(S1, speeds, "zeta", [0.1])


def test_threshold_sensitivity_to_identified_parameters():
    std = ParameterStd(k=200.0, c=1.0, M=0.01)
    sens = threshold_sensitivity(S1, std, 10 * WN)
    assert sens.threshold_rad_s / WN == quoted("1.3956")
    # A larger, one-sided step reproduces the central derivative to first order in the step
    # (relative step 1e-2 -> ~1e-2 relative error).
    step = 0.01 * S1.c
    moved = stable_speed_intervals(S1.replace(c=S1.c + step), 10 * WN, xtol_ratio=1e-12).lowest_stable_speed_rad_s
    assert (moved - sens.threshold_rad_s) / step == pytest.approx(sens.derivative_c, rel=0.05)
    expected = math.sqrt((sens.derivative_k * 200) ** 2 + sens.derivative_c**2 + (sens.derivative_M * 0.01) ** 2)
    assert sens.std_rad_s == pytest.approx(expected, rel=1e-12)


def test_balancing_required_for_stability_questions():
    heavy = S1.replace(e=0.05)
    with pytest.raises(ParameterError, match="n\\*m\\*R"):
        stable_speed_intervals(heavy, 10 * WN)
    with pytest.raises(ParameterError, match="speed_max_rad_s"):
        stable_speed_intervals(S1, math.nan)
    # equilibria still exist without balancing: only unbalanced ones
    assert all(eq.kind == "unbalanced" for eq in find_equilibria(heavy, 2 * WN))


def test_another_family_member_can_be_passed():
    # n = 3 (S6): the balanced states form a one-parameter family and stability depends on the
    # member; the symmetric one is the default, another member is accepted and analysed.
    p = S1.replace(n=3)
    default = stable_speed_intervals(p, 20 * p.natural_frequency_rad_s)
    assert default.intervals_ratio[0, 0] == quoted("1.461")
    member = balanced_ball_angles(p, free_angles_rad=[2.0])
    other = stable_speed_intervals(p, 20 * p.natural_frequency_rad_s, ball_angles_rad=member)
    assert np.allclose(other.ball_angles_rad, member)
    assert abs(other.lowest_stable_speed_rad_s - default.lowest_stable_speed_rad_s) > 1e-3 * p.natural_frequency_rad_s


def test_no_stable_speed_without_drag_or_without_support_damping():
    # the drag condition's limit cases: beta = 0 (no ball drag) fails beta > kappa zeta; zeta = 0 leaves
    # the rotor's whirl undamped.  With both zero the balanced state is at best marginal, and the
    # interval search must not mistake marginal points for stable ones.
    for changes in ({"D": 0.0}, {"c": 0.0}, {"c": 0.0, "D": 0.0}):
        p = S1.replace(**changes)
        assert len(stable_speed_intervals(p, 10 * WN)) == 0
    classes = balanced_stability(S1.replace(c=0.0, D=0.0), np.linspace(0.1, 10, 200) * WN).stability_class
    assert set(np.unique(classes)) == {UNSTABLE, MARGINAL}


def test_a_huge_condition_number_at_one_grid_speed_does_not_split_a_stable_interval():
    # a case the stress runs found (tests/stress/test_adb.py with tests/stress/test_identify.py): five
    # balls, stable from 1.373 wn on with a growth rate of -0.029/s throughout, but at 4.3 wn
    # the critical condition number was 4e16 and the first-order rounding bound 2.9e4/s, so
    # that one grid speed came out marginal and the interval was cut there (4.2875–4.3125 wn
    # missing). Perturbing the Jacobian at the rounding level moves the growth rate by 1e-12
    params = ADBParameters(M=1.0, m=0.001, n=5, R=0.23713737056616552, e=0.0006153698904364681,
                           k=100.0, c=0.059167988436520935, D=0.0005609407219565116)
    wn = params.natural_frequency_rad_s
    intervals = stable_speed_intervals(params, 5.0 * wn, grid_points=400)
    assert len(intervals) == 1 and intervals.intervals_ratio[0, 1] == 5.0
    at = balanced_stability(params, [4.3 * wn])
    assert at.stability_class[0] == STABLE
    assert at.rounding_bound_per_s[0] < 1e-6 * abs(at.max_real_part_per_s[0])


@pytest.mark.parametrize("seed", range(6))
def test_interval_scan_verdicts_are_the_eigenvalue_verdicts(seed):
    # stable_speed_intervals scans with Routh verdicts (stability_map margin=False); away from the
    # eigenvalue path's rounding band they must be its verdicts, point for point
    from balancer.adb.stability import _analyse_balanced, _stable_on_grid, balanced_state

    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 5))
    M, m, R = rng.uniform(0.5, 5.0), rng.uniform(0.005, 0.05), rng.uniform(0.02, 0.1)
    p = ADBParameters(M=M, m=m, n=n, R=R, e=rng.uniform(0.0, 0.9) * n * m * R / M, k=rng.uniform(1e3, 1e5),
                      c=rng.uniform(0.1, 50.0), D=10 ** rng.uniform(-5.0, -1.0))
    speeds = np.linspace(0.002, 8.0, 2000) * p.natural_frequency_rad_s
    angles = balanced_state(p)[2:2 + n]
    eig = _analyse_balanced([p], speeds, [angles])
    clear = np.abs(eig.max_real_part_per_s) > 1e3 * eig.rounding_bound_per_s
    routh = _stable_on_grid(p, speeds, angles)
    assert np.array_equal(routh[clear], (eig.stability_class == STABLE)[clear])
    assert np.count_nonzero(clear) > 1990  # the band is a few points at most
