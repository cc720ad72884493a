"""ADBParameters: validation, nondimensional groups, construction from identification."""
from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from balancer.adb import ADBParameters, ParameterBatch, identified_std
from modal.errors import ParameterError
from support.identified import identified_mode, within

REFERENCE = dict(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)


def test_reference_groups():
    p = ADBParameters(**REFERENCE)
    # omega_n = sqrt(1e4 / 1.04) = 98.058 rad/s (the reference case); closed forms, so rounding only.
    assert p.natural_frequency_rad_s == pytest.approx(98.058, abs=5e-4)
    assert p.total_mass_kg == pytest.approx(1.04, rel=1e-15)
    assert p.mass_ratio == pytest.approx(0.02 / 1.04, rel=1e-15)
    assert p.unbalance_ratio == pytest.approx(0.5, rel=1e-14)
    assert p.eccentricity_ratio == pytest.approx(0.5 * p.mass_ratio, rel=1e-14)
    # research note's table: zeta = .098, beta = .204
    assert p.damping_ratio == pytest.approx(0.098, abs=5e-4)
    assert p.drag_ratio == pytest.approx(0.204, abs=5e-4)
    assert p.can_balance


@pytest.mark.parametrize(
    "field, value",
    [("M", 0.0), ("M", -1.0), ("m", 0.0), ("R", -0.05), ("k", 0.0), ("c", -1.0), ("D", -1e-3),
     ("e", -1e-3), ("M", math.nan), ("k", math.inf), ("n", 0), ("n", 1.5), ("n", True), ("M", "heavy")],
)
def test_bad_parameters_raise_with_name(field, value):
    with pytest.raises(ParameterError, match=rf"^{field} "):
        ADBParameters(**{**REFERENCE, field: value})


def test_parameter_error_is_value_error():
    with pytest.raises(ValueError):
        ADBParameters(**{**REFERENCE, "m": -1.0})


def test_balancing_capacity_check():
    p = ADBParameters(**{**REFERENCE, "e": 0.05})  # M e = 0.05 > n m R = 0.002
    assert not p.can_balance
    with pytest.raises(ParameterError, match="n\\*m\\*R"):
        p.require_balancing()
    one = ADBParameters(**{**REFERENCE, "n": 1})  # a = 0.5 < 1 but one ball needs a == 1
    with pytest.raises(ParameterError, match="n = 1"):
        one.require_balancing()


def test_nondimensional_round_trip():
    p = ADBParameters(**REFERENCE)
    q = ADBParameters.from_nondimensional(
        n=2, mass_ratio=p.mass_ratio, unbalance_ratio=p.unbalance_ratio,
        damping_ratio=p.damping_ratio, drag_ratio=p.drag_ratio, M=p.M, R=p.R, k=p.k,
    )
    for name in ("m", "e", "c", "D"):
        # a few floating operations each way: rounding only
        assert getattr(q, name) == pytest.approx(getattr(p, name), rel=1e-13)


# Fed real identification results (modal.identify on a known rotor's receptance, 0.1 % noise)
def test_from_identified_scalar_and_channels():
    # one rotor measured on two driving-point channels (modal masses 1.0 and 1.1 kg)
    mode = identified_mode(np.array([1.0, 1.1]), 1e4, 20.0)
    p = ADBParameters.from_identified(mode, m=0.02, n=2, R=0.05, e=5e-4, D=1e-3, channel=1)
    assert (p.k, p.c, p.M) == (mode.stiffness_n_per_m[1], mode.damping_n_s_per_m[1], mode.mass_kg[1])
    assert within([p.k, p.c, p.M], [1.1e4, 22.0, 1.1],
                  [mode.std.stiffness_n_per_m[1], mode.std.damping_n_s_per_m[1], mode.std.mass_kg[1]])
    s = identified_std(mode, channel=1)
    assert (s.k, s.c, s.M) == (mode.std.stiffness_n_per_m[1], mode.std.damping_n_s_per_m[1], mode.std.mass_kg[1])
    assert 0 < s.k < 1e-3 * p.k and 0 < s.c < 1e-2 * p.c and 0 < s.M < 1e-3 * p.M
    single = identified_mode(1.04, 1e4, 20.0)
    scalar = ADBParameters.from_identified(single, m=0.02, n=2, R=0.05, e=5e-4, D=1e-3, mass_includes_balls=True)
    # the identified mass holds the two 0.02 kg balls: subtracted exactly
    assert scalar.M == single.mass_kg - 0.04
    assert within(scalar.M, 1.0, single.std.mass_kg)
    # a result without errors (duck-typed input): 0, not an exception
    assert identified_std(dataclasses.replace(single, std=None)).k == 0.0


def test_from_identified_rejects_bad_fields():
    with pytest.raises(ParameterError, match="stiffness_n_per_m"):
        ADBParameters.from_identified(SimpleNamespace(mass_kg=1.0), m=0.02, n=2, R=0.05, e=5e-4, D=1e-3)
    # a transfer channel: k, c, m are NaN (flag not_driving_point)
    transfer = identified_mode(np.array([1.0, 1.1]), 1e4, 20.0, driving_point=[True, False])
    with pytest.raises(ParameterError, match="finite"):
        ADBParameters.from_identified(transfer, m=0.02, n=2, R=0.05, e=5e-4, D=1e-3, channel=1)
    with pytest.raises(ParameterError, match="channel"):
        ADBParameters.from_identified(transfer, m=0.02, n=2, R=0.05, e=5e-4, D=1e-3, channel=5)
    single = identified_mode(1.0, 1e4, 20.0)
    with pytest.raises(ParameterError, match="^k "):
        ADBParameters.from_identified(dataclasses.replace(single, stiffness_n_per_m=-1.0), m=0.02, n=2, R=0.05,
                                      e=5e-4, D=1e-3)


def test_batch_requires_common_ball_count():
    p = ADBParameters(**REFERENCE)
    batch = ParameterBatch.from_parameters([p, p.replace(D=2e-3)])
    assert batch.size == 2 and batch.member(1).D == 2e-3
    with pytest.raises(ParameterError, match="ball counts"):
        ParameterBatch.from_parameters([p, p.replace(n=3)])
