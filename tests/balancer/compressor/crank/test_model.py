"""The slider-crank mechanism (balancer.compressor.crank.model): the rod's two-mass split, exact
piston acceleration and rod couple, counterweight mass, balance fraction, and bad mechanisms.

Paper numbers come from seed 000 (hermetic compressor, Table 1) and seed 004 (slider-crank,
R = 35 mm, L = 140 mm), as decoded in ``../shared/reference/crank_drive.md``.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from balancer.compressor.crank import (
    SliderCrank,
    balance_fraction,
    evaluate_counterweight,
    shaking_force,
    two_mass_split,
)
from modal.errors import ParameterError


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


def test_balance_fraction_round_trip(seed004):
    alpha = balance_fraction(seed004, 1.0, 0.035 * 0.9)
    assert alpha == pytest.approx((0.9 - 0.55) / 1.13, rel=1e-12)
    evaluation = evaluate_counterweight(seed004, 1000.0, 1.0, 0.035 * 0.9)
    assert evaluation.balance_fraction == pytest.approx(alpha, rel=1e-12)


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
