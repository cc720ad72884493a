"""The rotor without balls along a constant speed or a linear run-up: exact modal solution
(the demo's comparison run, without a second integration) against solve_ivp."""
from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

from balancer.adb import ADBParameters, ConstantSpeed, LinearRunUp

simulate_module = importlib.import_module("balancer.adb.simulate")
P = ADBParameters(M=1.0042, m=0.02, n=2, R=0.05, e=5e-4, k=10055.0, c=20.03, D=1e-3)


def _both(monkeypatch, params, profile, frame, position, velocity, speed0, times):
    window = times >= 0.9 * times[-1]
    exact = simulate_module._without_balls(params, profile, frame, position, velocity, speed0, times, 1e-11, window)
    with monkeypatch.context() as patch:
        patch.setattr(simulate_module, "_without_balls_exact", lambda *args: None)
        reference = simulate_module._without_balls(params, profile, frame, position, velocity, speed0, times, 1e-11,
                                                   window)
    return exact, reference


@pytest.mark.parametrize("profile, frame, speed0", [
    (LinearRunUp(0.0, 200.0, 3.0), "fixed", 0.0),
    (LinearRunUp(10.0, 150.0, 1.3, 0.6913), "fixed", 10.0),  # both kinks between samples
    (ConstantSpeed(250.0), "rotating", 250.0),
])
@pytest.mark.parametrize("samples", [None, 40])  # 40: samples far apart, panels subdivide them
def test_exact_response_matches_a_tight_integration(monkeypatch, profile, frame, speed0, samples):
    # DOP853 at rtol 1e-11 (atol 1e-3 rtol R) over ~1e4 steps accumulates well below 1e-9 of
    # the peak; the modal solution is exact up to Gauss-Legendre (8 nodes on panels of
    # <= 0.5 rad: ~1e-16) and rounding
    times = simulate_module._sample_times(3.0, samples, 250.0)
    for position, velocity in (((0.0, 0.0), (0.0, 0.0)), ((1e-3, -2e-3), (0.05, 0.01))):
        exact, reference = _both(monkeypatch, P, profile, frame, position, velocity, speed0, times)
        peak = np.max(reference[2])
        assert np.max(np.abs(exact[0] - reference[0])) < 1e-9 * peak
        assert np.max(np.abs(exact[1] - reference[1])) < 1e-9 * peak
        assert exact[3] == pytest.approx(reference[3], rel=1e-8)


def test_critical_damping_falls_back_to_the_integrator(monkeypatch):
    critical = P.replace(c=2 * math.sqrt(P.k * P.M))  # double root: the modal split is singular
    times = simulate_module._sample_times(1.0, None, 200.0)
    assert simulate_module._without_balls_exact(critical, LinearRunUp(0.0, 200.0, 0.5), (0, 0), (0, 0), times) is None
    exact, reference = _both(monkeypatch, critical, LinearRunUp(0.0, 200.0, 0.5), "fixed", (0, 0), (0, 0), 0.0, times)
    assert np.array_equal(exact[0], reference[0])
