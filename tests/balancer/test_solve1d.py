"""The one-dimensional solvers (balancer.solve1d): known roots and minima to the stated tolerances."""
from __future__ import annotations

import math

import pytest

from balancer.solve1d import find_root, minimize_bounded
from modal.errors import ParameterError

EPS = 2.220446049250313e-16

# (function, bracket, exact root)
ROOTS = [
    (lambda x: x * x - 2.0, (0.0, 2.0), math.sqrt(2.0)),
    (math.cos, (0.0, 3.0), 0.5 * math.pi),
    (lambda x: math.exp(x) - 10.0, (-5.0, 5.0), math.log(10.0)),
    (lambda x: math.atan(x - 0.3), (30.0, -10.0), 0.3),  # ends in either order
    (lambda x: (x - 1.0) ** 3, (0.0, 3.0), 1.0),  # triple root: interpolation stalls, bisection must take over
    (lambda x: x ** 9, (-1.0, 2.0), 0.0),  # flat at the root: |x| < xtol is all a tolerance can ask
    (lambda x: 1.0 if x > 0.25 else -1.0, (0.0, 1.0), 0.25),  # a jump: the sign change is found
    (lambda x: x - 1e6, (0.0, 1e7), 1e6),  # large root: the relative tolerance governs
]


@pytest.mark.parametrize("f, bracket, root", ROOTS)
@pytest.mark.parametrize("xtol", [1e-15, 1e-12, 1e-6])
def test_root_within_the_stated_tolerance(f, bracket, root, xtol):
    x = find_root(f, *bracket, xtol=xtol, rtol=4 * EPS)
    # the documented guarantee: within xtol + rtol |x| of the sign change (plus the rounding of the
    # exact root itself, 1 ulp)
    assert abs(x - root) <= xtol + 4 * EPS * abs(x) + math.ulp(root)


def test_root_at_an_end_is_returned_exactly():
    assert find_root(lambda x: x - 2.0, 2.0, 5.0) == 2.0
    assert find_root(lambda x: x - 5.0, 2.0, 5.0) == 5.0


def test_root_is_faster_than_bisection_on_a_smooth_function():
    calls = []

    def f(x):
        calls.append(x)
        return x ** 3 - 2.0 * x - 5.0

    x = find_root(f, 2.0, 3.0, xtol=1e-15)
    assert abs(f(x)) < 1e-13
    # bisection would need log2(1 / 1e-15) = 50 halvings; superlinear steps need far fewer
    assert len(calls) < 15


def test_root_bracket_errors_name_what_was_expected():
    with pytest.raises(ParameterError, match=r"f\(low\) = 1.0 and f\(high\) = 4.0 .*expected opposite signs"):
        find_root(lambda x: x * x, 1.0, 2.0)
    with pytest.raises(ParameterError, match="low = nan: expected a finite number"):
        find_root(lambda x: x, math.nan, 1.0)
    with pytest.raises(ParameterError, match="expected finite values"):
        find_root(lambda x: math.inf if x < 0 else x, -1.0, 1.0)
    with pytest.raises(ParameterError, match="expected xtol >= 0 and rtol >= 4 eps"):
        find_root(lambda x: x, -1.0, 1.0, rtol=0.0)
    with pytest.raises(ParameterError, match="in 3 iterations .*expected a continuous function"):
        find_root(lambda x: (x - 0.1) ** 3, -1.0, 1.0, xtol=1e-15, maxiter=3)


# (function, bounds, exact minimiser)
MINIMA = [
    (lambda x: (x - 0.7) ** 2, (0.0, 2.0), 0.7),
    (lambda x: math.cosh(x - 0.3) + 1.0, (-1.0, 3.0), 0.3),
    (lambda x: abs(x - 1.234), (0.0, 5.0), 1.234),  # a kink: golden sections only
    (lambda x: -math.sin(x), (0.0, 3.0), 0.5 * math.pi),
    (lambda x: x, (2.0, 3.0), 2.0),  # minimum at a bound (never evaluated): approached to the tolerance
]


@pytest.mark.parametrize("f, bounds, minimiser", MINIMA)
@pytest.mark.parametrize("xatol", [1e-5, 1e-10])
def test_minimum_within_the_stated_tolerance(f, bounds, minimiser, xatol):
    x = minimize_bounded(f, *bounds, xatol=xatol)
    assert bounds[0] < x < bounds[1]
    # stop rule: the bracket around x has half-width <= 2 tol, tol = sqrt(eps) |x| + xatol / 3; the
    # minimiser of a unimodal function lies inside it
    tol = math.sqrt(EPS) * abs(x) + xatol / 3.0
    assert abs(x - minimiser) <= 4.0 * tol


def test_minimum_errors_name_what_was_expected():
    with pytest.raises(ParameterError, match="expected low < high"):
        minimize_bounded(lambda x: x * x, 1.0, 1.0)
    with pytest.raises(ParameterError, match="xatol = 0.0: expected a tolerance > 0"):
        minimize_bounded(lambda x: x * x, -1.0, 1.0, xatol=0.0)
    with pytest.raises(ParameterError, match=r"f\(.*\) = nan: expected a finite value"):
        minimize_bounded(lambda x: math.nan, -1.0, 1.0)
    with pytest.raises(ParameterError, match="no minimum to xatol = 1e-10 in 4 evaluations"):
        minimize_bounded(lambda x: (x - 0.1) ** 2, -1.0, 1.0, xatol=1e-10, maxiter=4)
