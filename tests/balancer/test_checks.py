"""balancer's argument checks (balancer/_checks.py): clean values through, one clear line for bad ones."""
from __future__ import annotations

import math

import numpy as np
import pytest

from balancer import _checks as checks
from modal.errors import ParameterError


def _message(check, *args, **kwargs) -> str:
    with pytest.raises(ParameterError) as info:
        check(*args, **kwargs)
    return str(info.value)


def test_unit_form_names_the_value_with_its_unit():
    assert checks.positive("power_w", np.float64(750), "W") == 750.0
    assert type(checks.non_negative("gap_m", 0, "m")) is float
    assert _message(checks.finite, "power_w", "a lot", "W") == "power_w = 'a lot' is not a number; expected a value in W"
    assert _message(checks.finite, "power_w", math.inf, "W") == "power_w = inf W is not finite; expected a finite value"
    assert _message(checks.positive, "power_w", 0, "W") == "power_w = 0.0 W must be > 0"
    assert _message(checks.non_negative, "gap_m", -1, "m") == "gap_m = -1.0 m must be >= 0"


def test_bounded_form_keeps_the_bounds_and_strictness():
    assert checks.bounded("ratio", 0.0, minimum=0.0) == 0.0
    assert checks.bounded("ratio", 2.0, minimum=1.0, maximum=2.0) == 2.0
    assert _message(checks.bounded, "crank_radius_m", 0.0, minimum=0.0, strict=True) == \
        "crank_radius_m = 0.0: expected a value > 0.0"
    assert _message(checks.bounded, "ratio", 2.5, minimum=1.0, maximum=2.0) == "ratio = 2.5: expected a value <= 2.0"
    assert _message(checks.bounded, "ratio", None) == "ratio = None: expected a real number"
    assert _message(checks.bounded, "ratio", math.nan) == "ratio = nan: expected a finite number"


def test_parameter_form_says_what_the_parameter_is():
    assert checks.parameter("c (support damping)", 0, "N s/m", positive=False) == 0.0
    assert _message(checks.parameter, "k (support stiffness)", -1, "N/m", positive=True) == \
        "k (support stiffness) = -1.0 N/m: expected > 0"
    assert _message(checks.parameter, "k (support stiffness)", "x", "N/m", positive=True) == \
        "k (support stiffness) = 'x': expected a real number in N/m"


def test_count_takes_integral_floats_but_not_booleans():
    assert checks.count("n (ball count)", 2.0) == 2 and checks.count("n (ball count)", np.int64(3)) == 3
    for bad in (True, 1.5, 0, "2"):
        assert _message(checks.count, "n (ball count)", bad) == f"n (ball count) = {bad!r}: expected an integer >= 1"


def test_finite_positive_gives_one_message_for_every_failure():
    for bad, shown in (("soon", "'soon'"), (-1, "-1.0"), (math.inf, "inf"), (0, "0.0")):
        assert _message(checks.finite_positive, "t_end_s", bad, "a finite time > 0 s") == \
            f"t_end_s = {shown}: expected a finite time > 0 s"


def test_finite_array_names_the_first_bad_entry():
    np.testing.assert_array_equal(checks.finite_array([1, 2], "amplitude"), [1.0, 2.0])
    assert _message(checks.finite_array, [1.0, math.nan, math.inf], "amplitude") == \
        "amplitude: entry 1 is nan; expected a finite number"
    assert _message(checks.finite_array, [1.0, "x"], "amplitude") == "amplitude: expected numbers, got [1.0, 'x']"


@pytest.mark.parametrize("value, kwargs, expected", [
    (True, {}, "a number"), ("1", {}, "a number"), (10**400, {}, "a finite number"), (math.nan, {}, "a finite number"),
    (0, {"positive": True}, "a number > 0"), (-1.0, {"nonneg": True}, "a number >= 0"),
])
def test_scene_numbers_report_only_what_was_expected(value, kwargs, expected):
    # the scene's schema puts the file and the key before it; booleans are not numbers in a scene file
    with pytest.raises(ValueError) as info:
        checks.scene_number(value, **kwargs)
    assert str(info.value) == expected and not isinstance(info.value, ParameterError)
    assert checks.scene_number(3, positive=True) == 3.0
