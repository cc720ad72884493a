"""Shaft stiffness, critical speed and speed margin (balancer.drive.shaft.stiffness).

Reference numbers: the note's "feeding a rotor model" illustration (``shared/reference/crank_drive.md``
section 4: E = 205 GPa, steel 7850 kg/m^3, a 2 kg pulley).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from balancer.drive.shaft import (
    PointLoad,
    ShaftGeometry,
    analyse_shaft,
    bending_stiffness_n_per_m,
    critical_speed,
    rotor_layout,
    second_moment_of_area_m4,
    shaft_diagram,
    span_critical_speed_rad_s,
    speed_margin,
)

from support.drive import SHAFT_1


# --------------------------------------------------------------------------- stiffness
def test_stiffness_for_the_common_layouts():
    # d = 25 mm, E = 205 GPa: EI = 3931 N m^2; centre of the 1.15 m span k = 48EI/L^3 = 124 kN/m;
    # pulley on the 0.15 m overhang k = 3EI/(a^2 (L + a)) = 403 kN/m (the note, 3-4 digits).
    ei = 205e9 * second_moment_of_area_m4(0.025)
    assert ei == pytest.approx(3931.0, abs=0.5)
    assert bending_stiffness_n_per_m(SHAFT_1, 0.575, 0.025) == pytest.approx(48 * ei / 1.15**3, rel=1e-12)
    assert bending_stiffness_n_per_m(SHAFT_1, 0.575, 0.025) == pytest.approx(124e3, abs=500)
    assert bending_stiffness_n_per_m(SHAFT_1, 1.30, 0.025) == pytest.approx(403e3, abs=500)
    assert rotor_layout(SHAFT_1, 1.30) == "overhung" and rotor_layout(SHAFT_1, 0.5) == "between bearings"
    # an overhang on the A side is the mirror image
    mirrored = ShaftGeometry(1.30, 0.15, 1.30)
    assert bending_stiffness_n_per_m(mirrored, 0.0, 0.025) == pytest.approx(
        bending_stiffness_n_per_m(SHAFT_1, 1.30, 0.025), rel=1e-12)


@pytest.mark.parametrize("position_m", [0.2, 0.575, 0.9, 1.22, 1.30])
def test_stiffness_matches_unit_load_integration(position_m):
    # Independent check of the closed forms: deflection under a unit load is
    # integral(m(x)^2 / EI dx), with m(x) the unit-load moment from the statics solver.
    unit = analyse_shaft(SHAFT_1, [PointLoad(position_m, 1.0)])
    diagram = shaft_diagram(unit, points_per_segment=4001)
    m, x = diagram.moment_vertical_n_m, diagram.position_m
    ei = 205e9 * second_moment_of_area_m4(0.025)
    deflection = np.sum(0.5 * (m[1:] ** 2 + m[:-1] ** 2) * np.diff(x)) / ei
    # trapezoid on a quadratic integrand: relative error ~ h^2, about 1e-6 here
    assert 1.0 / deflection == pytest.approx(bending_stiffness_n_per_m(SHAFT_1, position_m, 0.025), rel=1e-5)


# --------------------------------------------------------------------------- critical speed
def test_critical_speeds_of_the_note():
    # d = 25 mm, 2 kg pulley at the overhang: span mode 2276 rpm, pulley mode 4287 rpm,
    # Dunkerley 2010 rpm = 2.6 x 775 rpm; d = 30 mm: 2498 rpm (3.2 x).  Printed to 1 rpm.
    result = critical_speed(SHAFT_1, 0.025, [2.0], [1.30])
    rpm = np.asarray(result.partial_speeds_rad_s) * 60 / (2 * math.pi)
    assert rpm[0] == pytest.approx(4287, abs=1.0)
    assert rpm[1] == pytest.approx(2276, abs=1.0)
    assert span_critical_speed_rad_s(1.15, 0.025) * 60 / (2 * math.pi) == pytest.approx(2276, abs=1.0)
    assert result.critical_speed_rpm == pytest.approx(2010, abs=1.0)
    assert result.critical_speed_rpm < rpm.min()  # Dunkerley is a lower bound
    assert critical_speed(SHAFT_1, 0.030, [2.0], [1.30]).critical_speed_rpm == pytest.approx(2498, abs=1.0)
    # without the shaft's own mass only the pulley mode is left
    alone = critical_speed(SHAFT_1, 0.025, [2.0], [1.30], include_shaft_mass=False)
    assert alone.critical_speed_rpm == pytest.approx(rpm[0], rel=1e-12)


def test_dunkerley_with_several_masses():
    # 1/w^2 adds: two masses give 1/w^2 = m1/k11 + m2/k22 (+ shaft)
    result = critical_speed(SHAFT_1, 0.025, [2.0, 5.0], [1.30, 0.575], include_shaft_mass=False)
    k11 = bending_stiffness_n_per_m(SHAFT_1, 1.30, 0.025)
    k22 = bending_stiffness_n_per_m(SHAFT_1, 0.575, 0.025)
    assert result.critical_speed_rad_s == pytest.approx((2.0 / k11 + 5.0 / k22) ** -0.5, rel=1e-12)
    assert len(result.partial_labels) == 2 and "between bearings" in result.partial_labels[1]


def test_speed_margin_checks_1x_and_2x():
    # w_c = 2.1 W: 1x separation 1.1 (passes), 2x separation 0.05 (fails a 20 % margin)
    margin = speed_margin(100.0, 210.0, required_separation=0.2)
    assert margin.separation_1x == pytest.approx(1.1, rel=1e-12)
    assert margin.separation_2x == pytest.approx(0.05, rel=1e-12)
    assert margin.ok_1x and not margin.ok_2x and not margin.supercritical
    above = speed_margin(300.0, 210.0)
    assert above.supercritical and above.separation_1x == pytest.approx(0.3, rel=1e-12)


def test_a_shaft_diameter_in_millimetres_is_refused():
    """25 (mm written as m) on the 1.3 m shaft made k = 4.0e17 N/m and a hand-over with Ω/ω_crit = 1.8e-7, exit 0:
    the bending formulas hold for a slender shaft only, and a diameter not below the length is refused."""
    from modal.errors import ParameterError

    with pytest.raises(ParameterError, match=r"diameter_m = 25 m is not below the shaft's length_m = 1\.3 m; "
                                             r"expected a slender shaft"):
        bending_stiffness_n_per_m(SHAFT_1, 1.30, 25.0)
