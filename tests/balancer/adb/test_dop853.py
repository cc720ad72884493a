"""The lean DOP853 loop (balancer.adb.dop853) against SciPy's solve_ivp and exact solutions."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from balancer.adb import ADBParameters
from balancer.adb.dop853 import dop853
from balancer.adb.equations import scalar_rhs
from balancer.adb.simulate import default_initial_ball_angles
from balancer.adb.speed import LinearRunUp


def _run_up_case():
    """The demo scene's ball balancer on a run-up through the critical speed (fixed frame, 9 states)."""
    p = ADBParameters(M=1.98, m=0.02, n=2, R=0.05, e=5e-4, k=1.9e4, c=3.0, D=1e-3)
    rhs = scalar_rhs(p.M, p.m, p.n, p.R, p.e, p.k, p.c, p.D, frame="fixed")
    profile = LinearRunUp(0.0, 200.0, 3.0)

    def fun(t, y):
        return rhs(y, float(profile.speed_rad_s(t)), float(profile.acceleration_rad_s2(t)))

    y0 = np.zeros(9)
    y0[2:4] = default_initial_ball_angles(2)
    rate = 200.0
    atol = np.array([1e-11 * p.R] * 2 + [1e-11] * 2 + [1e-11 * p.R * rate] * 2 + [1e-11 * rate] * 2 + [1e-8])
    return fun, y0, np.linspace(0.0, 1.5, 1501), atol


def test_run_up_samples_equal_solve_ivp_to_rounding():
    fun, y0, times, atol = _run_up_case()
    ours = dop853(fun, (times[0], times[-1]), y0, times, rtol=1e-8, atol=atol)
    ref = solve_ivp(fun, (times[0], times[-1]), y0, method="DOP853", t_eval=times, rtol=1e-8, atol=atol)
    assert ours.status == ref.status == 0
    # the same method, step control and arithmetic, operation for operation: the same steps
    # (function evaluations) and samples equal to a few ulps of each component's scale
    assert ours.nfev == ref.nfev
    np.testing.assert_array_equal(ours.t, ref.t)
    scale = np.max(np.abs(ref.y), axis=1, keepdims=True)
    assert np.all(np.abs(ours.y - ref.y) <= 8 * np.finfo(float).eps * scale)


@pytest.mark.parametrize("rtol", [1e-6, 1e-9, 1e-12])
def test_harmonic_oscillator_error_follows_the_tolerance(rtol):
    # y'' = -w^2 y over 5 periods: exact y = cos(w t); the global error of an 8th-order method
    # run at a local tolerance rtol stays within a small multiple of rtol times the steps taken
    w = 2 * math.pi

    def fun(t, y):
        return np.array([y[1], -w * w * y[0]])

    times = np.linspace(0.0, 5.0, 401)
    out = dop853(fun, (0.0, 5.0), [1.0, 0.0], times, rtol=rtol, atol=rtol * 1e-3)
    steps = out.nfev / 15  # 12 stages + 3 for the dense output per step
    error = np.max(np.abs(out.y[0] - np.cos(w * times)))
    assert error <= 10 * rtol * steps
    assert out.y.shape == (2, times.size)


def test_blow_up_reports_a_step_too_small_as_solve_ivp():
    # y' = y^2, y(0) = 1 blows up at t = 1: the step size falls below the spacing of the times
    def fun(t, y):
        return y * y

    times = np.linspace(0.0, 2.0, 20)  # 1.0 is not a sample time
    ours = dop853(fun, (0.0, 2.0), [1.0], times, rtol=1e-8, atol=1e-10)
    ref = solve_ivp(fun, (0.0, 2.0), [1.0], method="DOP853", t_eval=times, rtol=1e-8, atol=1e-10)
    assert ours.status == ref.status == -1
    assert ours.message == ref.message
    np.testing.assert_array_equal(ours.t, ref.t)
    assert ours.t[-1] < 1.0 and np.allclose(ours.y[0], 1.0 / (1.0 - ours.t), rtol=1e-6)
