"""V-belt stages and drives (balancer.drive.belt).

Reference numbers are the machine-drive report (seed 002) as decoded in
``shared/reference/crank_drive.md`` section 4.  Where the report is sound, the
tolerance is half a unit of its last printed digit; where it erred, the test
asserts the value the consistent chain gives and says why the print differs.
"""
from __future__ import annotations

import dataclasses
import inspect
import math

import numpy as np
import pytest

from support.drive import STAGE_A, STAGE_B, STAGE_B_CATALOGUE

from balancer.drive import (
    ARC_CORRECTION_VV,
    BeltStageSpec,
    CorrectionTable,
    belt_drive,
    belt_pitch_length_m,
    belt_stage,
    center_distance_for_length_m,
    next_standard_size,
    tension_ratio_from_friction,
    tension_sum_factor_from_ratio,
)

from modal.errors import ParameterError


# --------------------------------------------------------------------------- contract
def test_entry_point_signature_is_the_contract():
    names = list(inspect.signature(belt_stage).parameters)[:6]
    assert names == ["driver_diameter_m", "driven_diameter_m", "center_distance_m",
                     "driver_speed_rpm", "power_w", "service_factor"]
    assert inspect.signature(belt_stage).parameters["service_factor"].default == 1.0


def test_entry_point_positional_call_returns_contract_fields():
    stage = belt_stage(0.100, 0.120, 0.300, 930.0, 750.0)
    for field in ("driven_speed_rpm", "design_power_w", "belt_length_m", "arc_of_contact_deg",
                  "belt_speed_m_s", "effective_pull_n"):
        assert math.isfinite(getattr(stage, field)), field
    assert stage.design_power_w == 750.0  # service factor defaults to 1


# --------------------------------------------------------------------------- stage A
def test_stage_a_speed_and_design_power(stage_a):
    # 930 * 100 / 120 = 775 exactly; 0.75 kW * 1.3 = 0.975 kW exactly: only round-off allowed.
    assert stage_a.driven_speed_rpm == pytest.approx(775.0, rel=1e-12)
    assert stage_a.driven_speed_rad_s == pytest.approx(775.0 * 2 * math.pi / 60, rel=1e-12)
    assert stage_a.design_power_w == pytest.approx(975.0, rel=1e-12)


def test_stage_a_belt_length_and_standard(stage_a):
    # printed 945.73 mm (two decimals: +-0.005 mm), standard 975 mm.
    assert stage_a.belt_length_m * 1e3 == pytest.approx(945.73, abs=0.005)
    assert stage_a.standard_length_m == 0.975
    # the centre distance at which the 975 mm belt fits gives back 975 mm (inverse formula)
    assert belt_pitch_length_m(0.1, 0.12, stage_a.center_distance_for_standard_length_m) == pytest.approx(0.975, rel=1e-12)
    assert stage_a.center_distance_for_standard_length_m > stage_a.center_distance_m


def test_stage_a_arc_of_contact_is_176_18_not_the_printed_178_28(stage_a):
    # 180 - 2 asin(20 / 600) = 176.18 deg (two decimals).  The report prints 178.28 deg,
    # which no reading of its inputs gives (L in place of C gives 178.82 deg).
    assert stage_a.arc_of_contact_deg == pytest.approx(176.18, abs=0.005)
    assert abs(stage_a.arc_of_contact_deg - 178.28) > 2.0
    assert stage_a.arc_of_contact_rad == pytest.approx(math.radians(stage_a.arc_of_contact_deg), rel=1e-15)


def test_stage_a_belt_speed_and_effective_pull(stage_a):
    # v = pi 0.1 930 / 60 = 4.8695 m/s (printed precision +-5e-5).
    assert stage_a.belt_speed_m_s == pytest.approx(4.8695, abs=5e-5)
    # F_e = 750 W / 4.8695 m/s = 154.02 N.  The report's 154.32 N is 750 / 4.86: it
    # truncated the belt speed to 4.86 m/s; that 0.2 % slip is far above print precision.
    assert stage_a.effective_pull_n == pytest.approx(154.02, abs=0.005)
    assert round(750.0 / 4.86, 2) == 154.32
    assert abs(stage_a.effective_pull_n - 154.32) > 0.25
    # k1 = 1.5 means T1/T2 = 5 with T1 - T2 = F_e
    assert stage_a.tight_side_tension_n / stage_a.slack_side_tension_n == pytest.approx(5.0, rel=1e-12)
    assert stage_a.tight_side_tension_n - stage_a.slack_side_tension_n == pytest.approx(stage_a.effective_pull_n, rel=1e-12)


def test_stage_a_belt_count(stage_a):
    # 0.975 / (1.275 * 1 * 0.88) = 0.8690 (the report truncates to 0.86) -> 1 belt.
    assert stage_a.belts_required == pytest.approx(0.975 / (1.275 * 0.88), rel=1e-12)
    assert stage_a.belts_required == pytest.approx(0.869, abs=5e-4)
    assert stage_a.belt_count == 1 and stage_a.belt_count_basis == "rating"


def test_stage_a_shaft_load_uses_exact_pull_and_whole_belts(stage_a):
    # (1.5 * 154.021 + 1 * 0.217 * 4.86947**2) * sin(176.18 deg / 2) = 236.05 N.
    # The report's 235.88 N is (1.5 * 154.32 + 0.86 * 0.217 * 23.62) * 1: the truncated
    # speed's pull, a fractional belt count and sin(theta/2) taken as 1.
    assert stage_a.shaft_load_n == pytest.approx(236.05, abs=0.005)
    report_style = 1.5 * 154.32 + 0.86 * 0.217 * 23.62
    assert report_style == pytest.approx(235.88, abs=0.01)
    assert abs(stage_a.shaft_load_n - 235.88) > 0.1


def test_stage_a_torques(stage_a):
    # 750 W at 930 rpm = 7.701 N m (motor shaft); at 775 rpm = 9.241 N m (driven shaft).
    assert stage_a.driver_torque_n_m == pytest.approx(7.701, abs=5e-4)
    assert stage_a.driven_torque_n_m == pytest.approx(9.241, abs=5e-4)


# --------------------------------------------------------------------------- the "332.1 rpm"
def test_second_speed_uses_950_rpm_not_930():
    # The report writes 950 * 125 / 350 = 332.1 rpm; that is 930 * 125 / 350 = 332.14.
    at_950 = belt_stage(0.125, 0.350, 0.600, 950.0, 4000.0)
    at_930 = belt_stage(0.125, 0.350, 0.600, 930.0, 4000.0)
    assert at_950.driven_speed_rpm == pytest.approx(339.2857, abs=5e-5)
    assert at_930.driven_speed_rpm == pytest.approx(332.14, abs=0.005)


# --------------------------------------------------------------------------- stage B
def test_stage_b_belt_length_is_2075_97_not_2218_68(stage_b):
    # 2*600 + 1.57*540 + 260**2/2400 = 2075.97 mm; the report's 2218.68 mm is +142.7 mm.
    assert stage_b.belt_length_m * 1e3 == pytest.approx(2075.97, abs=0.005)
    assert abs(stage_b.belt_length_m * 1e3 - 2218.68) > 140.0
    # the 2240 mm belt the report chose fits at C = 683.7 mm, not 600 mm
    assert center_distance_for_length_m(2.240, 0.140, 0.400) * 1e3 == pytest.approx(683.7, abs=0.05)


def test_stage_b_arc_speed_pull(stage_b):
    # with D = 400 mm the arc is 154.97 deg; the report's 154.93 deg is D = 400.4 mm (2.86 * 140)
    assert stage_b.arc_of_contact_deg == pytest.approx(154.97, abs=0.005)
    assert belt_stage(0.140, 0.4004, 0.600, 950.0, 4000.0).arc_of_contact_deg == pytest.approx(154.93, abs=0.005)
    # v = pi 0.14 950 / 60 = 6.9639 m/s
    assert stage_b.belt_speed_m_s == pytest.approx(6.9639, abs=5e-5)
    # 4000 / 6.96386 = 574.394 N.  The printed 574.38 N is 4000 / 6.964 (speed rounded to
    # 4 digits): the difference must stay within F * 0.0005 / v, the effect of that rounding.
    assert stage_b.effective_pull_n == pytest.approx(4000.0 / (math.pi * 0.14 * 950.0 / 60.0), rel=1e-12)
    bound = stage_b.effective_pull_n * 0.0005 / stage_b.belt_speed_m_s
    assert abs(stage_b.effective_pull_n - 574.38) <= bound


def test_stage_b_belt_count_and_shaft_load(stage_b):
    # 5.2 / (2.75 * 1 * 0.99) = 1.910 (the report's 1.89 omits K_L) -> 2 belts either way.
    assert stage_b.belts_required == pytest.approx(1.910, abs=5e-4)
    assert stage_b.belt_count == 2
    # (1.5 * 574.394 + 2 * 0.385 * 6.96386**2) * sin(154.97 deg / 2) = 877.58 N;
    # the report's 805.58 N is not reproduced by any reading of its own terms.
    assert stage_b.shaft_load_n == pytest.approx(877.58, abs=0.005)
    assert abs(stage_b.shaft_load_n - 805.58) > 70.0


# --------------------------------------------------------------------------- options
def test_default_arc_table_changes_the_count_factor():
    by_table = belt_stage(**STAGE_A, per_belt_rating_w=1275.0, length_correction_factor=0.88)
    # |D - d|/C = 0.0667 lies between 0.0 (1.00) and 0.1 (0.99): 1 - 0.0667 * 0.1
    assert by_table.arc_correction_factor == pytest.approx(1.0 - 0.02 / 0.3 * 0.1, rel=1e-12)
    given = belt_stage(**STAGE_A, per_belt_rating_w=1275.0, arc_correction_factor=1.0, length_correction_factor=0.88)
    assert by_table.belts_required > given.belts_required


def test_replaceable_arc_table():
    table = CorrectionTable(variable="(D - d)/C", x=(0.0, 1.0), factor=(1.0, 0.5), source="test")
    stage = belt_stage(**STAGE_A, per_belt_rating_w=1275.0, arc_correction_table=table)
    assert stage.arc_correction_factor == pytest.approx(1.0 - 0.5 * 0.02 / 0.3, rel=1e-12)
    assert ARC_CORRECTION_VV.lookup(0.5) == 0.93


def test_centrifugal_term_and_given_belt_count_change_the_shaft_load():
    base = belt_stage(**STAGE_A)
    with_k2 = belt_stage(**STAGE_A, centrifugal_factor_kg_per_m=0.217)
    three = belt_stage(**STAGE_A, centrifugal_factor_kg_per_m=0.217, belt_count=3)
    term = 0.217 * base.belt_speed_m_s**2 * math.sin(0.5 * base.arc_of_contact_rad)
    assert with_k2.shaft_load_n - base.shaft_load_n == pytest.approx(term, rel=1e-12)
    assert three.shaft_load_n - base.shaft_load_n == pytest.approx(3 * term, rel=1e-12)
    assert three.belt_count_basis == "given" and base.belt_count_basis == "default"


def test_tension_factors():
    assert tension_sum_factor_from_ratio(5.0) == pytest.approx(1.5, rel=1e-15)
    ratio = tension_ratio_from_friction(0.25, math.pi, math.radians(38.0))
    assert ratio == pytest.approx(math.exp(0.25 * math.pi / math.sin(math.radians(19.0))), rel=1e-15)
    stage = belt_stage(**STAGE_A, tension_sum_factor=tension_sum_factor_from_ratio(ratio))
    assert stage.tight_side_tension_n / stage.slack_side_tension_n == pytest.approx(ratio, rel=1e-12)


def test_next_standard_size():
    assert next_standard_size(0.94573, (0.975, 0.9, 1.0)) == 0.975
    assert next_standard_size(0.975, (0.975,)) == 0.975  # equal counts as fitting
    with pytest.raises(ParameterError, match="exceeds the largest standard size"):
        next_standard_size(2.0, (0.975, 1.0), "belt_length_m")


def test_stages_in_series():
    specs = (
        BeltStageSpec(0.100, 0.120, 0.300, per_belt_rating_w=1275.0, name="A"),
        BeltStageSpec(0.125, 0.350, 0.600, efficiency=0.95),
        BeltStageSpec(0.100, 0.200, 0.500),
    )
    result = belt_drive(930.0, 750.0, specs, service_factor=1.3)
    assert [s.name for s in result.stages] == ["A", "stage 2", "stage 3"]
    assert result.stages[1].driver_speed_rpm == pytest.approx(result.stages[0].driven_speed_rpm, rel=1e-15)
    assert result.output_speed_rpm == pytest.approx(930.0 * (100 / 120) * (125 / 350) * (100 / 200), rel=1e-12)
    assert result.overall_ratio == pytest.approx(1.2 * 2.8 * 2.0, rel=1e-12)
    # stage 2 passes on 95 %: stage 3 carries 712.5 W
    assert result.stages[2].power_w == pytest.approx(712.5, rel=1e-12)
    assert result.output_power_w == pytest.approx(712.5, rel=1e-12)
    assert result.stages[2].design_power_w == pytest.approx(712.5 * 1.3, rel=1e-12)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        (dict(center_distance_m=0.10), r"center_distance_m = 0\.1 m is too small.*\(D \+ d\)/2 = 0\.11"),
        (dict(driver_speed_rpm=0.0), r"driver_speed_rpm = 0\.0 rpm must be > 0"),
        (dict(driver_speed_rpm=-930.0), r"driver_speed_rpm = -930\.0 rpm must be > 0"),
        (dict(power_w=float("nan")), r"power_w = nan W is not finite"),
        (dict(driver_diameter_m=0.0), r"driver_diameter_m = 0\.0 m must be > 0"),
        (dict(service_factor=0.0), r"service_factor = 0\.0"),
        (dict(driven_speed=1.0), r"unexpected keyword"),
    ],
)
def test_bad_stage_input(kwargs, pattern):
    arguments = {**STAGE_A, **kwargs}
    error = TypeError if "driven_speed" in kwargs else ParameterError
    with pytest.raises(error, match=pattern):
        belt_stage(**arguments)


def test_bad_catalogue_input():
    with pytest.raises(ParameterError, match=r"belt_count = 1 is below the 1\.9.* belts"):
        belt_stage(**STAGE_B, **STAGE_B_CATALOGUE, belt_count=1)
    with pytest.raises(ParameterError, match=r"belt_count = 1\.5; expected an int >= 1"):
        belt_stage(**STAGE_A, belt_count=1.5)
    with pytest.raises(ParameterError, match=r"tension_sum_factor = 1\.0 must be > 1"):
        belt_stage(**STAGE_A, tension_sum_factor=1.0)
    with pytest.raises(ParameterError, match=r"centrifugal_factor_kg_per_m = -0\.2 kg/m must be >= 0"):
        belt_stage(**STAGE_A, centrifugal_factor_kg_per_m=-0.2)
    # |D - d|/C = 0.4/0.26 = 1.538: outside the default table (arc below 83 deg)
    with pytest.raises(ParameterError, match=r"\(D - d\)/C = 1\.538.* is outside the correction table"):
        belt_stage(0.05, 0.45, 0.26, 1000.0, 100.0, per_belt_rating_w=500.0)
    with pytest.raises(ParameterError, match=r"belt_length_m = 0\.3 m is too short"):
        center_distance_for_length_m(0.3, 0.1, 0.12)
    with pytest.raises(ParameterError, match=r"tension_ratio = 1\.0 must be > 1"):
        tension_sum_factor_from_ratio(1.0)


def test_bad_tables_and_series():
    with pytest.raises(ParameterError, match="strictly increasing"):
        CorrectionTable("x", (0.0, 0.0), (1.0, 1.0))
    with pytest.raises(ParameterError, match="factor = .* must all be > 0"):
        CorrectionTable("x", (0.0, 1.0), (1.0, 0.0))
    with pytest.raises(ParameterError, match="expected two equally long sequences"):
        CorrectionTable("x", (0.0, 1.0, 2.0), (1.0, 0.9))
    with pytest.raises(ParameterError, match=r"stages = \[\]; expected at least one"):
        belt_drive(930.0, 750.0, [])
    with pytest.raises(ParameterError, match=r"stages\[0\].efficiency = 1\.2 must be in \(0, 1\]"):
        belt_drive(930.0, 750.0, [BeltStageSpec(0.1, 0.12, 0.3, efficiency=1.2)])
    with pytest.raises(ParameterError, match=r"stages\[0\] is a dict; expected a BeltStageSpec"):
        belt_drive(930.0, 750.0, [dict(driver_diameter_m=0.1)])


# --------------------------------------------------------------------------- archivable results
def _archivable(value) -> bool:
    if dataclasses.is_dataclass(value):
        return all(_archivable(getattr(value, f.name)) for f in dataclasses.fields(value))
    if isinstance(value, tuple):
        return all(_archivable(v) for v in value)
    return isinstance(value, (bool, int, float, str, np.ndarray, np.floating, np.integer))


def test_results_are_frozen_and_archivable(stage_a):
    result = belt_drive(930.0, 750.0, [BeltStageSpec(0.1, 0.12, 0.3)])
    assert _archivable(stage_a) and _archivable(result)
    with pytest.raises(dataclasses.FrozenInstanceError):
        stage_a.belt_length_m = 1.0  # type: ignore[misc]


def test_pulley_diameters_in_millimetres_are_refused():
    """Stage A's pulleys written in mm as m (100 and 120 m, centres 300 m) ran a 4869 m/s belt and printed a drive
    with exit 0; V-belts run below 30-50 m/s, and a belt faster than 60 m/s is refused naming the diameter. At the
    limit's edge a real fast drive (a 0.25 m pulley at 3600 rpm: 47 m/s) still computes."""
    from modal.errors import ParameterError

    with pytest.raises(ParameterError, match=r"driver_diameter_m = 100 m at 930 rpm runs the belt at 4869 m/s; "
                                             r"expected below 60 m/s"):
        belt_stage(100.0, 120.0, 300.0, 930.0, 750.0)
    assert belt_stage(0.25, 0.5, 1.0, 3600.0, 5000.0).belt_speed_m_s == pytest.approx(math.pi * 0.25 * 60, rel=1e-12)


def test_a_centre_distance_in_millimetres_is_refused():
    """Stage A's centre distance written in mm as m (300 m) ran a 600 m belt with exit 0; V-belt catalogues end
    near 15 m, and a belt longer than 30 m is refused naming the distance. A long real drive (2 m centres) computes."""
    with pytest.raises(ParameterError, match=r"center_distance_m = 300 m with pulleys of 0.1 m and 0.12 m makes a "
                                             r"belt 600.3 m long; expected below 30 m"):
        belt_stage(0.100, 0.120, 300.0, 930.0, 750.0)
    assert belt_stage(0.100, 0.120, 2.0, 930.0, 750.0).belt_length_m == pytest.approx(4.346, abs=1e-3)


def test_a_motor_speed_in_rad_per_s_is_warned():
    """930 rpm written as 97.4 (rad/s) runs stage A's belt at 0.51 m/s: every speed downstream is ten times too
    slow. V-belt drives run 5-30 m/s; a belt below 1 m/s is warned of, naming the speed; at 930 rpm (4.9 m/s) no
    warning."""
    import warnings

    from modal.errors import ModalWarning

    with pytest.warns(ModalWarning, match=r"driver_diameter_m = 0.1 m at 97.4 rpm runs the belt at 0.51 m/s"):
        belt_stage(0.100, 0.120, 0.300, 97.4, 750.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        belt_stage(0.100, 0.120, 0.300, 930.0, 750.0)
