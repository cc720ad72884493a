"""modal.quantiles against scipy.special (the library does without it; the tests use it as the reference).

Tolerances: the functions are computed to a few units in the last place of their inputs' conditioning.
Comparisons allow 1e-10 relative (the target; scipy itself differs from exact values by up to 1e-15 in
these ranges). Where a reference takes ``1 - tail`` (scipy's fdtri, gammaincinv at tails near 1), that
rounding alone moves the tail by ``eps / tail``: those cases are checked the other way, by putting our
quantile back through scipy's tail function.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import special

from modal.quantiles import (beta_lower, beta_upper, chi2_upper_quantile, f_survival, f_upper_quantile, gamma_lower,
                             gamma_lower_inverse, gamma_upper, gamma_upper_inverse)

RTOL = 1e-10

#: shape parameters: the checks use channel counts 1 … hundreds and half degrees of freedom from 1 to ~1e5;
#: the edges: tiny (1e-3), just below and at Stirling's switch (10), huge (1e6)
SHAPES = [1e-3, 0.3, 0.5, 1.0, 2.0, 4.5, 9.99, 10.0, 30.0, 100.0, 1000.0, 1e4, 1e5, 1e6]
TAILS = [1e-300, 1e-100, 1e-12, 1e-6, 0.01, 0.5, 0.99, 1 - 1e-9]


def _relative(ours, reference):
    ours, reference = np.asarray(ours, float), np.asarray(reference, float)
    scale = np.where(reference == 0, 1.0, np.abs(reference))
    return np.abs(ours - reference) / scale


@pytest.mark.parametrize("a", SHAPES)
def test_incomplete_gamma_tails_match_scipy_to_1e_10_each_in_its_far_tail(a):
    xs = [1e-8, 1e-3, 0.5, 1.0, 1.5, a / 2, a, a + 1, 1.2 * a, 2 * a, a + 10 * math.sqrt(a), 5 * a + 50]
    for x in xs:
        p, q = gamma_lower(a, x), gamma_upper(a, x)
        ref_p, ref_q = special.gammainc(a, x), special.gammaincc(a, x)
        # below 1e-290 scipy's own values lose digits to subnormal arithmetic
        if ref_p > 1e-290:
            assert _relative(p, ref_p) < RTOL, (a, x, p, ref_p)
        if ref_q > 1e-290:
            assert _relative(q, ref_q) < RTOL, (a, x, q, ref_q)
    assert gamma_lower(a, 0.0) == 0.0 and gamma_upper(a, 0.0) == 1.0
    assert gamma_lower(a, math.inf) == 1.0 and gamma_upper(a, math.inf) == 0.0


@pytest.mark.parametrize("a", SHAPES)
def test_gamma_quantiles_invert_the_tails_and_match_scipy(a):
    for tail in TAILS:
        upper = gamma_upper_inverse(a, tail)
        lower = gamma_lower_inverse(a, tail)
        if upper > 0:  # a = 1e-3 has upper quantiles below the smallest float: 0, as scipy says
            # put back through scipy's tail: conditioning of Q in x is x Q'/Q, a few × 1e-16 per unit
            assert _relative(special.gammaincc(a, upper), tail) < RTOL * max(1.0, upper * 1e-5), (a, tail)
            if a <= 1e5 or tail < 0.5:  # scipy's inverses lose 1e-10 at a = 1e6 from the lower side
                assert _relative(upper, special.gammainccinv(a, tail)) < RTOL, (a, tail)
        else:
            assert special.gammainccinv(a, tail) == 0.0
        if lower > 0 and (a <= 1e5 or tail > 0.5):  # scipy's gammaincinv itself is off by 1e-9 at a = 1e6
            assert _relative(lower, special.gammaincinv(a, tail)) < RTOL, (a, tail, lower)
    assert gamma_upper_inverse(a, 1.0) == 0.0 and gamma_upper_inverse(a, 0.0) == math.inf
    assert gamma_lower_inverse(a, 0.0) == 0.0 and gamma_lower_inverse(a, 1.0) == math.inf


def test_huge_shape_gamma_quantile_inverts_its_own_tail_where_scipy_loses_digits():
    # a = 1e6: our lower quantile puts back to the tail asked (a 1-ulp change of x moves P by ~1e-11 here)
    for tail in (1e-12, 1e-6):
        x = gamma_lower_inverse(1e6, tail)
        assert _relative(gamma_lower(1e6, x), tail) < 1e-10


def test_chi_square_upper_quantile_matches_scipy():
    for dof in (1, 2, 4, 18, 40, 200, 2e4):
        for tail in (1e-12, 1e-6, 0.01, 0.5):
            assert _relative(chi2_upper_quantile(dof, tail), special.chdtri(dof, tail)) < RTOL, (dof, tail)


#: degrees of freedom of the F tests: the levels' tests take 2 and 2 (hits − 2), the hidden-mode check
#: 2 + 2 × channels and thousands of residual degrees of freedom; the edges again tiny and huge
DOFS = [0.1, 1.0, 2.0, 4.0, 10.0, 19.9, 20.0, 42.0, 100.0, 1000.0, 1e4, 1e6]


@pytest.mark.parametrize("dfn", DOFS)
def test_f_survival_matches_scipy_over_the_whole_range_of_f(dfn):
    f = np.array([0.0, 1e-8, 1e-3, 0.1, 0.5, 0.9, 1.0, 1.1, 2.0, 3.0, 10.0, 30.0, 100.0, 1e4, 1e8, np.inf])
    for dfd in [0.1, 1.0, 2.0, 4.0, 10.0, 20.0, 50.0, 200.0, 5000.0, 1e5, 1e6]:
        ours, reference = f_survival(dfn, dfd, f), special.fdtrc(dfn, dfd, f)
        kept = reference > 1e-290
        assert np.all(_relative(ours[kept], reference[kept]) < RTOL), (dfn, dfd, f[kept][np.argmax(
            _relative(ours[kept], reference[kept]))])
        assert np.all(ours[~kept] < 1e-280)
    assert f_survival(dfn, 5.0, [[1.0, 2.0]]).shape == (1, 2)
    assert np.isnan(f_survival(dfn, 5.0, np.nan))


@pytest.mark.parametrize("dfn", DOFS[:-1])
def test_f_upper_quantile_puts_back_to_the_tail_asked(dfn):
    for dfd in [0.1, 1.0, 2.0, 4.0, 10.0, 20.0, 50.0, 200.0, 5000.0, 1e5, 1e6]:
        for tail in TAILS:
            f = f_upper_quantile(dfn, dfd, tail)
            if math.isinf(f):  # tiny degrees of freedom: the quantile is beyond the largest float
                # the tail at the largest float, I_x(dfd/2, dfn/2) with x = dfd / (dfd + dfn F) (fdtrc overflows)
                assert special.betainc(dfd / 2, dfn / 2, dfd / dfn / np.finfo(float).max) > tail
                continue
            # scipy's tail at our quantile: a relative change δ of F moves the tail by δ F f(F)/tail
            # (a few units here), so 1e-10 on the tail is 1e-10 on F
            if tail < 1e-200:  # scipy's fdtrc loses up to 2 % of a 1e-300 tail (checked with 50-digit
                # arithmetic, where ours kept 1e-13): put back through our own, tested above against scipy
                assert _relative(f_survival(dfn, dfd, f), tail) < RTOL, (dfn, dfd, tail)
            elif tail <= 0.5:
                assert _relative(special.fdtrc(dfn, dfd, f), tail) < RTOL, (dfn, dfd, tail)
            else:  # the smaller tail, below F (1 - tail is exact here); fdtrc rounds x = 1 - 1e-18 to 1
                assert _relative(special.fdtr(dfn, dfd, f), 1 - tail) < RTOL, (dfn, dfd, tail)
            if tail >= 1e-3:  # where scipy's fdtri (which takes 1 - tail) keeps 1e-13 of the tail
                assert _relative(f, special.fdtri(dfn, dfd, 1 - tail)) < RTOL, (dfn, dfd, tail)


def test_the_quantiles_the_checks_use_match_scipy():
    # the hidden-mode check of 8 channels over 2000 lines, the missing-peak threshold, the exp-mean median
    assert _relative(f_upper_quantile(18, 32000, 1e-6), special.fdtri(18, 32000, 1 - 1e-6)) < 1e-9
    for n in (1, 2, 8, 64, 500):
        assert _relative(gamma_lower_inverse(n, 0.5), special.gammaincinv(n, 0.5)) < RTOL
        assert _relative(gamma_upper_inverse(n, 1e-6 / 4096), special.gammainccinv(n, 1e-6 / 4096)) < RTOL


def test_beta_tails_are_complements_each_precise_where_small():
    x = np.linspace(0.0, 1.0, 41)
    for a, b in [(0.5, 0.5), (1.0, 30.0), (12.0, 15.0), (300.0, 2.0)]:
        lower, upper = beta_lower(a, b, x), beta_upper(a, b, x)
        np.testing.assert_allclose(lower, special.betainc(a, b, x), rtol=RTOL, atol=1e-300)
        np.testing.assert_allclose(upper, special.betaincc(a, b, x), rtol=RTOL, atol=1e-300)


@pytest.mark.parametrize("call", [lambda: gamma_lower(0.0, 1.0), lambda: gamma_upper(1.0, -1.0),
                                  lambda: gamma_upper_inverse(2.0, 1.5), lambda: gamma_lower_inverse(math.inf, 0.5),
                                  lambda: f_survival(2.0, 4.0, -1.0), lambda: f_upper_quantile(0.0, 4.0, 0.1),
                                  lambda: f_upper_quantile(2.0, 4.0, -0.1), lambda: beta_lower(-1.0, 2.0, 0.5)])
def test_arguments_outside_the_domain_are_refused(call):
    with pytest.raises(ValueError):
        call()
