"""Shaft speed profiles (balancer.adb.speed): bad profiles and when a profile is called."""
from __future__ import annotations

import math

import pytest

from balancer.adb import ADBParameters

from balancer.adb.simulate import simulate

from modal.errors import ParameterError


S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s


@pytest.mark.parametrize(
    "speed, match",
    [(math.nan, "speed"), (math.inf, "speed"), (lambda t: math.nan if t > 0.1 else 100.0, "finite"),
     ("fast", "speed")],
)
def test_bad_speed_profiles_raise(speed, match):
    with pytest.raises(ParameterError, match=match):
        simulate(S1, speed, 0.2)


def test_callable_profile_is_never_called_before_zero():
    def speed(t):
        if t < 0:
            raise AssertionError("called at negative time")
        return 2 * WN * math.sqrt(t / 0.2) if t < 0.2 else 2 * WN

    result = simulate(S1, speed, 0.05, n_samples=51, compare_without_balls=False)
    assert result.speed_rad_s[-1] == pytest.approx(2 * WN * math.sqrt(0.25))
