"""The Jeffcott rotor's influence coefficient (balancer.influence.jeffcott) against the ball balancer's equations."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from balancer.influence import jeffcott_influence, trial_mass_kg


# ---------------------------------------------------------------- Jeffcott model against the adb equations
@pytest.mark.parametrize("speed_ratio", [0.6, 1.0, 1.7])
def test_jeffcott_influence_matches_direct_simulation(speed_ratio):
    """Steady 1x orbit of the adb rotor without balls, integrated from rest, against the model alpha.

    Transients decay as exp(-zeta omega_n t) = exp(-0.1 * 100 * 2.5) ~ 1e-11; DOP853 at rtol 1e-11:
    the fitted amplitude agrees to 1e-6.
    """
    from balancer.adb.equations import scalar_rhs

    M, k, e = 2.0, 2e4, 1e-4  # omega_n = 100 rad/s
    c = 2 * 0.1 * math.sqrt(k * M)  # zeta = 0.1
    omega = speed_ratio * math.sqrt(k / M)
    rhs = scalar_rhs(M, 0.0, 0, 0.05, e, k, c, 0.0, frame="fixed")
    t_end = 2.5
    period = 2 * math.pi / omega
    t_fit = np.linspace(t_end - 2 * period, t_end, 200)
    sol = solve_ivp(lambda t, y: rhs(y, omega, 0.0), (0.0, t_end), np.zeros(5), method="DOP853",
                    rtol=1e-11, atol=1e-16, t_eval=t_fit)
    x, y, theta = sol.y[0], sol.y[1], sol.y[4]
    # fit x + i y = X exp(i theta) + X' exp(-i theta) (forward and backward whirl; the latter ~ 0)
    basis = np.column_stack([np.exp(1j * theta), np.exp(-1j * theta)])
    forward, backward = np.linalg.lstsq(basis, x + 1j * y, rcond=None)[0]
    assert abs(backward) <= 1e-6 * abs(forward)
    # lag convention: reading = conj(rotation-convention amplitude), unbalance M e at angle 0
    predicted = jeffcott_influence(k, c, M, omega) * (M * e)
    assert np.conj(forward) == pytest.approx(predicted, rel=1e-6)
    lag = math.degrees(np.angle(predicted))
    assert lag == pytest.approx(math.degrees(math.atan2(c * omega, k - M * omega**2)), abs=1e-9)


def test_jeffcott_velocity_and_trial_mass():
    k, c, M, w = 1e5, 50.0, 10.0, 150.0
    d = jeffcott_influence(k, c, M, w)
    assert jeffcott_influence(k, c, M, w, "velocity") == pytest.approx(-1j * w * d)
    assert jeffcott_influence(k, c, M, w, "acceleration") == pytest.approx(-w * w * d)
    # 100 kg rotor, 3000 rpm, trial at 0.2 m on one of two planes: 10 % of 490 N -> 49.03 N = m r Omega^2
    m_t = trial_mass_kg(100.0, 3000.0, 0.2, n_planes=2)
    assert m_t * 0.2 * (math.pi * 100) ** 2 == pytest.approx(0.1 * 100 * 9.80665 / 2, rel=1e-12)
