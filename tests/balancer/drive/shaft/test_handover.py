"""The shaft's hand-over to a ball-balancer study (balancer.drive.shaft.handover): motor to rotor speed and
stiffness, in the note's worked example (``shared/reference/crank_drive.md`` section 4).
"""
from __future__ import annotations

import math

import pytest

from balancer.drive import belt_stage
from balancer.drive.shaft import (
    PointLoad,
    allowable_shear_stress_pa,
    analyse_shaft,
    endurance_limit_pa,
    rotor_handover,
    shaft_diameter_soderberg,
    shaft_torque_n_m,
)

from support.drive import SHAFT_1


# --------------------------------------------------------------------------- worked example
def test_worked_example_motor_to_ball_balancer_input():
    # Motor 0.75 kW at 930 rpm -> stage A -> shaft 1 (belt load at 5 deg on the overhang)
    # -> Soderberg diameter -> 25 mm -> stiffness and critical speed with a 2 kg rotor at
    # the pulley.  Expected: W = 775 rpm = 81.158 rad/s; k = 3EI/(a^2 (L + a)) = 403.2 kN/m;
    # Dunkerley 2010 rpm = 2.59 x running; 2x separation 0.297 passes a 20 % margin; the
    # shaft runs subcritical, where a ball balancer cannot balance (adb.md).
    stage = belt_stage(0.100, 0.120, 0.300, 930.0, 750.0, 1.3, per_belt_rating_w=1275.0,
                       arc_correction_factor=1.0, length_correction_factor=0.88,
                       centrifugal_factor_kg_per_m=0.217, standard_lengths_m=(0.900, 0.975, 1.050))
    shaft = analyse_shaft(SHAFT_1, [PointLoad.from_direction(1.30, stage.shaft_load_n, 5.0, "pulley")],
                          shaft_torque_n_m(stage.power_w, stage.driven_speed_rpm))
    sizing = shaft_diameter_soderberg(shaft.max_moment_n_m, shaft.torque_n_m, 490e6,
                                      endurance_limit_pa(420e6, 0.75, 0.7), allowable_shear_stress_pa(490e6, 2.5),
                                      bending_factor=1.8)
    handover = rotor_handover(stage.driven_speed_rad_s, SHAFT_1, sizing.standard_diameter_m, 1.30, 2.0)
    assert handover.speed_rad_s == pytest.approx(775.0 * 2 * math.pi / 60, rel=1e-12)
    assert handover.speed_rpm == pytest.approx(775.0, rel=1e-12)
    assert handover.layout == "overhung"
    # tip of an overhang a = 0.15 m beyond a simply supported span L = 1.15 m:
    # k = 3 E I / (a^2 (L + a)), E = 205 GPa, I = pi d^4 / 64 (crank_drive.md: EI = 3931 N m^2,
    # k = 403 kN/m for d = 25 mm)
    a, span = 1.30 - 1.15, 1.15
    ei = 205e9 * math.pi * sizing.standard_diameter_m**4 / 64
    k = 3 * ei / (a**2 * (span + a))
    assert sizing.standard_diameter_m == 0.025 and round(ei) == 3931 and round(k / 1e3) == 403
    assert handover.stiffness_n_per_m == pytest.approx(k, rel=1e-12)
    assert handover.rotor_natural_frequency_rad_s == pytest.approx(math.sqrt(k / 2.0), rel=1e-12)
    # Dunkerley with the shaft's own mode: "2010 rpm, which is 2.6x the running speed"
    critical_rpm = handover.critical.critical_speed_rpm
    assert critical_rpm == pytest.approx(2010, abs=0.5)
    assert handover.margin.critical_to_running_ratio == pytest.approx(critical_rpm / 775.0, rel=1e-12)
    assert handover.margin.critical_to_running_ratio == pytest.approx(2.6, abs=0.05)
    assert handover.margin.separation_2x == pytest.approx(abs(critical_rpm / (2 * 775.0) - 1), rel=1e-12)
    assert handover.margin.ok_1x and handover.margin.ok_2x
    assert not handover.margin.supercritical
    assert handover.speed_ratio == pytest.approx((775.0 * 2 * math.pi / 60) / math.sqrt(k / 2.0), rel=1e-12)


def test_a_rotor_mass_in_grams_or_a_thin_shaft_is_refused():
    """The 2 kg rotor overhung 0.15 m beyond bearing B of a 25 mm shaft bends it at 2 × 9.81 × 0.15 / (π 0.025³/32)
    = 1.9 MPa under its weight. Its mass in g written as kg (2000), or the diameter 2.5 mm, makes that 1.9 GPa,
    above the strongest shaft steels' yield, and a hand-over with Ω/ω = 5.7 and 18 printed with exit 0: refused,
    naming the mass, the shaft and the stress. Between the bearings the moment is W a b / L."""
    from modal.errors import ParameterError

    assert rotor_handover(81.0, SHAFT_1, 0.025, 1.30, 2.0).rotor_mass_kg == 2.0
    with pytest.raises(ParameterError, match=r"rotor_mass_kg = 2000 kg at 1.3 m would bend the 0.025 m shaft at "
                                             r"1.92 GPa under its weight alone"):
        rotor_handover(81.0, SHAFT_1, 0.025, 1.30, 2000.0)
    with pytest.raises(ParameterError, match=r"the 0.0025 m shaft at 1.92 GPa"):
        rotor_handover(81.0, SHAFT_1, 0.0025, 1.30, 2.0)
    # mid-span of the 1.15 m span: W L / 4 = 2000 × 9.81 × 0.2875 against the 25 mm section: 3.68 GPa
    with pytest.raises(ParameterError, match=r"at 3.68 GPa"):
        rotor_handover(81.0, SHAFT_1, 0.025, 0.575, 2000.0)


@pytest.mark.parametrize("modulus", [205.0, 205e3, 2.05e14])  # GPa or MPa written as Pa; 1000 times too large
def test_a_youngs_modulus_in_the_wrong_unit_is_refused(modulus):
    """205 (GPa written as Pa) made the 25 mm shaft's stiffness 4e-4 N/m and a hand-over with Ω/ω = 5720, exit 0."""
    from modal.errors import ParameterError

    import re

    with pytest.raises(ParameterError, match=re.escape(f"youngs_modulus_pa = {modulus:.6g} Pa; expected a solid "
                                                       "shaft's modulus, 0.1-1200 GPa")):
        rotor_handover(81.0, SHAFT_1, 0.025, 1.30, 2.0, youngs_modulus_pa=modulus)
