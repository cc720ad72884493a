"""ADBParameters: validation, nondimensional groups, construction from identification."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from balancer.adb import ADBParameters, ParameterBatch, identified_std
from modal.errors import ParameterError

REFERENCE = dict(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)


def test_reference_groups():
    p = ADBParameters(**REFERENCE)
    # omega_n = sqrt(1e4 / 1.04) = 98.058 rad/s (issue); closed forms, so rounding only.
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


def _mode(k, c, mass, std=None):
    return SimpleNamespace(
        natural_frequency_hz=np.sqrt(np.abs(np.asarray(k)) / np.asarray(mass)) / (2 * np.pi),
        damping_ratio=np.asarray(c) / (2 * np.sqrt(np.abs(np.asarray(k)) * np.asarray(mass))),
        stiffness_n_per_m=k, damping_n_s_per_m=c, mass_kg=mass, std=std, flags=(),
    )


def test_from_identified_scalar_and_channels():
    std = SimpleNamespace(stiffness_n_per_m=np.array([100.0, 50.0]), damping_n_s_per_m=np.array([1.0, 2.0]),
                          mass_kg=np.array([0.01, 0.02]))
    mode = _mode(np.array([1e4, 1.2e4]), np.array([20.0, 22.0]), np.array([1.0, 1.1]), std)
    p = ADBParameters.from_identified(mode, m=0.02, n=2, R=0.05, e=5e-4, D=1e-3, channel=1)
    assert (p.k, p.c, p.M) == (1.2e4, 22.0, 1.1)
    s = identified_std(mode, channel=1)
    assert (s.k, s.c, s.M) == (50.0, 2.0, 0.02)
    scalar = ADBParameters.from_identified(_mode(1e4, 20.0, 1.04), m=0.02, n=2, R=0.05, e=5e-4, D=1e-3,
                                           mass_includes_balls=True)
    assert scalar.M == pytest.approx(1.0, rel=1e-15)
    assert identified_std(_mode(1e4, 20.0, 1.0)).k == 0.0


def test_from_identified_rejects_bad_fields():
    with pytest.raises(ParameterError, match="stiffness_n_per_m"):
        ADBParameters.from_identified(SimpleNamespace(mass_kg=1.0), m=0.02, n=2, R=0.05, e=5e-4, D=1e-3)
    with pytest.raises(ParameterError, match="finite"):
        ADBParameters.from_identified(_mode(math.nan, 20.0, 1.0), m=0.02, n=2, R=0.05, e=5e-4, D=1e-3)
    with pytest.raises(ParameterError, match="channel"):
        ADBParameters.from_identified(_mode(np.array([1e4, 2e4]), 20.0, 1.0), m=0.02, n=2, R=0.05,
                                      e=5e-4, D=1e-3, channel=5)
    with pytest.raises(ParameterError, match="^k "):
        ADBParameters.from_identified(_mode(-1.0, 20.0, 1.0), m=0.02, n=2, R=0.05, e=5e-4, D=1e-3)


def test_batch_requires_common_ball_count():
    p = ADBParameters(**REFERENCE)
    batch = ParameterBatch.from_parameters([p, p.replace(D=2e-3)])
    assert batch.size == 2 and batch.member(1).D == 2e-3
    with pytest.raises(ParameterError, match="ball counts"):
        ParameterBatch.from_parameters([p, p.replace(n=3)])
