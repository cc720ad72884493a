"""Stability verdicts from the closed-form characteristic polynomial and a vectorised Routh
test (balancer.adb.verdict) against the eigenvalue path."""
from __future__ import annotations

import numpy as np
import pytest

from balancer.adb import ADBParameters, balanced_state, characteristic_polynomial, stability_map
from balancer.adb.linear import MARGINAL, STABLE, UNSTABLE
from balancer.adb.stability import _balanced_companion
from balancer.adb.verdict import UNRESOLVED, balanced_polynomial, routh_verdicts

S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s
EPS = np.finfo(float).eps
CAP = 1e8  # stability_map's default screening cap


def _polynomial(p: ADBParameters, ratios: np.ndarray) -> np.ndarray:
    angles = balanced_state(p)[2:2 + p.n]
    rho2 = abs(np.sum(np.exp(2j * angles))) ** 2
    return balanced_polynomial(p.mass_ratio, p.damping_ratio, p.drag_ratio, ratios, rho2, p.n)


def test_closed_form_polynomial_is_the_determinant_for_two_balls():
    # n = 2: P8 is det(s^2 M0 + s C0 + K0) itself; the FFT of sampled determinants
    # (characteristic_polynomial) carries ~1e-13 relative error on coefficients of size
    # up to Omega^8, so 1e-10 relative to the largest coefficient is far above both.
    for ratio in (0.3, 1.05, 2.0, 6.0):
        ours = _polynomial(S1, np.array(ratio))[::-1]
        reference = characteristic_polynomial(S1, ratio * WN)
        assert np.max(np.abs(ours - reference)) < 1e-10 * np.max(np.abs(reference)), ratio


@pytest.mark.parametrize("n", [3, 5])
def test_closed_form_polynomial_times_family_factor_has_the_eigenvalues_as_roots(n):
    # det = (s (s + beta))^(n - 2) P8: compare with the monic polynomial of the companion
    # matrix's eigenvalues (backward stable: coefficients to ~1e-13 relative to their size)
    p = S1.replace(n=n)
    ratios = np.array([0.5, 1.2, 2.0, 3.5])
    speeds = ratios * p.natural_frequency_rad_s
    companion = _balanced_companion([p], speeds, [balanced_state(p)[2:2 + n]])
    ours = _polynomial(p, ratios)
    for index in range(ratios.size):
        full = np.poly(np.linalg.eigvals(companion[index])).real
        mine = ours[::-1, index]
        for _ in range(n - 2):
            mine = np.polymul(mine, [1.0, p.drag_ratio, 0.0])
        mine = mine / mine[0]
        assert np.max(np.abs(mine - full) / np.maximum(1.0, np.abs(full))) < 1e-11


def test_routh_verdicts_on_simple_polynomials():
    def run(high):
        low = [np.array([x], dtype=float) for x in high[::-1]]
        errors = [np.array([4 * EPS * abs(x)]) for x in high[::-1]]
        hurwitz, not_hurwitz = routh_verdicts(low, errors)
        return bool(hurwitz[0]), bool(not_hurwitz[0])

    assert run([1, 3, 3, 1]) == (True, False)  # (s + 1)^3
    assert run([1, -1, 2]) == (False, True)  # roots 0.5 +- 1.32i
    assert run([1, 1, 4, 6]) == (False, True)  # Routh column 1, 1, -2, 6
    assert run([1, 0, 1]) == (False, False)  # roots on the imaginary axis: left open
    assert run([1, 2, 2, 1]) == (True, False)  # (s + 1)(s^2 + s + 1)


def _clear_margin(p: ADBParameters, ratios: np.ndarray, values, parameter) -> np.ndarray:
    """Rounding-derived threshold 2 x 10 cap eps ||J||_F of the screened eigenvalue path (1/s)."""
    out = []
    for v in values:
        member = p.replace(**{parameter: int(v) if parameter == "n" else float(v)})
        companion = _balanced_companion([member], ratios * member.natural_frequency_rad_s,
                                        [balanced_state(member)[2:2 + member.n]])
        out.append(2 * 10 * CAP * EPS * np.linalg.norm(companion, axis=(-2, -1)) * member.natural_frequency_rad_s)
    return np.array(out)


@pytest.mark.parametrize("parameter, values", [
    ("D", np.geomspace(1e-6, 0.1, 23)),
    ("c", np.concatenate([[0.0], np.geomspace(0.05, 200.0, 14)])),
    ("m", np.linspace(0.005, 0.2, 12)),
    ("n", [2, 3, 4, 5]),
    ("e", np.linspace(0.0, 1e-3, 6)),
    ("k", np.geomspace(1e3, 1e6, 5)),
])
def test_routh_verdicts_agree_with_eigenvalues_where_the_margin_is_clear(parameter, values):
    # same grid, both paths; wherever the eigenvalue growth rate is clear of twice the
    # screened rounding bound, the Routh verdict must be the eigenvalue path's verdict,
    # and the points it leaves to the eigenvalue path carry that path's numbers.
    ratios = np.concatenate([np.linspace(0.05, 6.0, 97), [0.999, 1.0, 1.001, 1.3956488]])
    speeds = ratios * WN
    eig = stability_map(S1, speeds, parameter, values)
    fast = stability_map(S1, speeds, parameter, values, margin=False)
    # speeds are shared, so for parameters that change omega_n compare on the common speeds
    threshold = np.array([_clear_margin(S1, speeds / (S1.replace(**{parameter: int(v) if parameter == "n" else float(v)})
                                                      .natural_frequency_rad_s), [v], parameter)[0] for v in values])
    clear = np.abs(eig.max_real_part_per_s) > threshold
    assert np.array_equal(fast.stability_class[clear], eig.stability_class[clear])
    assert np.any(eig.stability_class == STABLE) or parameter == "c"
    # where the Routh test decided, no growth rate is reported; elsewhere the eigenvalue path's
    resolved = np.isnan(fast.max_real_part_per_s)
    assert not np.any(fast.stability_class[resolved] == MARGINAL)
    same = ~resolved
    assert np.array_equal(fast.stability_class[same], eig.stability_class[same])
    assert np.allclose(fast.max_real_part_per_s[same], eig.max_real_part_per_s[same], rtol=1e-9, atol=0)
    # the point of the fast path: no eigenvalue wherever the growth rate is clear of the band
    # (points first caught by the band from the norm's upper bound are tried again with the
    # exact norm, whose band is the threshold itself; factor 2 for the Routh array's margin)
    assert np.all(resolved[np.abs(eig.max_real_part_per_s) > 2 * threshold])


def test_marginal_points_stay_with_the_eigenvalue_path():
    # c = D = 0: every stable-looking point has all eigenvalues on the imaginary axis; the
    # Routh test cannot certify either side and the eigenvalue path keeps them marginal
    speeds = np.linspace(0.1, 10, 60) * WN
    eig = stability_map(S1.replace(c=0.0), speeds, "D", [0.0, 1e-3])
    fast = stability_map(S1.replace(c=0.0), speeds, "D", [0.0, 1e-3], margin=False)
    assert np.array_equal(fast.stability_class, eig.stability_class)
    assert np.any(fast.stability_class[0] == MARGINAL)
    marginal = fast.stability_class == MARGINAL
    assert np.all(np.isfinite(fast.max_real_part_per_s[marginal]))


def test_margin_false_keeps_the_default_map_unchanged():
    speeds = np.linspace(0.3, 4, 40) * WN
    drags = np.geomspace(1e-6, 0.1, 30)
    default = stability_map(S1, speeds, "D", drags)
    assert np.all(np.isfinite(default.max_real_part_per_s))
    fast = stability_map(S1, speeds, "D", drags, margin=False)
    assert np.array_equal(fast.stability_class, default.stability_class)
    assert set(np.unique(fast.stability_class)) <= {STABLE, UNSTABLE, MARGINAL}
    assert UNRESOLVED == MARGINAL  # unresolved points never leave the verdict path unclassified
    # condition_cap=None asks for condition numbers everywhere: eigenvalue path, margin everywhere
    full = stability_map(S1, speeds, "D", drags, condition_cap=None, margin=False)
    assert np.all(np.isfinite(full.max_real_part_per_s))


def test_points_at_the_boundary_are_left_to_the_eigenvalue_path():
    # within 1e-9 omega_n of the threshold the growth rate is ~1e-9 omega_n, inside the band
    # |growth| < 2 x 10 cap eps ||J||_F (~1e-6 omega_n here) that the eigenvalue path screens
    # for ill-conditioning: the Routh path must not decide there, and reports that path's
    # growth rate and class (the honest marginal verdict stays possible)
    from balancer.adb import stable_speed_intervals

    low = stable_speed_intervals(S1, 10 * WN, xtol_ratio=1e-12).lowest_stable_speed_rad_s
    speeds = low + np.array([-1e-9, 0.0, 1e-9]) * WN
    fast = stability_map(S1, speeds, "D", [S1.D], margin=False)
    eig = stability_map(S1, speeds, "D", [S1.D])
    assert np.all(np.isfinite(fast.max_real_part_per_s))
    assert np.array_equal(fast.stability_class, eig.stability_class)


def test_another_family_member_gets_the_same_verdicts():
    # n = 3, a non-symmetric balanced member (S6 of adb.md): rho^2 comes from the actual angles
    from balancer.adb import balanced_ball_angles

    p = S1.replace(n=3)
    member = balanced_ball_angles(p, free_angles_rad=[2.0])
    speeds = np.linspace(0.3, 6.0, 120) * p.natural_frequency_rad_s
    eig = stability_map(p, speeds, "D", [1e-4, 1e-3, 1e-2], ball_angles_rad=member)
    fast = stability_map(p, speeds, "D", [1e-4, 1e-3, 1e-2], ball_angles_rad=member, margin=False)
    assert np.array_equal(fast.stability_class, eig.stability_class)
    assert np.any(fast.stability_class == STABLE) and np.isnan(fast.max_real_part_per_s).mean() > 0.9
