"""Permissible residual unbalance by ISO 21940-11 (balancer.influence.iso): the standard's worked examples."""
from __future__ import annotations

import numpy as np
import pytest

from balancer.influence import allocate_to_planes, iso_check, permissible_unbalance_kg_m
from support.balancing import polar


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
