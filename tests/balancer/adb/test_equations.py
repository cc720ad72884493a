"""Equations of motion: Jacobians, frame consistency, equilibria residuals."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from balancer.adb import ADBParameters, ParameterBatch, find_equilibria
from balancer.adb.equations import (
    fixed_frame_jacobian,
    fixed_frame_rhs,
    fixed_to_rotating,
    rotating_frame_jacobian,
    rotating_frame_rhs,
    rotating_to_fixed,
)

REFERENCE = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
EPS = np.finfo(float).eps


def _random_state(rng, n, size, R):
    state = rng.normal(size=size)
    state[:2] *= 0.1 * R
    state[2 + n:4 + n] *= 10 * R
    state[4 + n:4 + 2 * n] *= 5.0
    return state


@pytest.mark.parametrize("n", [1, 2, 5])
@pytest.mark.parametrize("frame", ["rotating", "fixed"])
def test_jacobian_matches_central_differences(n, frame):
    rng = np.random.default_rng(n)
    p = REFERENCE.replace(n=n)
    batch = ParameterBatch.from_parameters(p)
    size = 4 + 2 * n + (frame == "fixed")
    rhs, jac = (rotating_frame_rhs, rotating_frame_jacobian) if frame == "rotating" else (fixed_frame_rhs, fixed_frame_jacobian)
    state = _random_state(rng, n, size, p.R)
    speed, acc = 150.0, 40.0
    exact = jac(state[None], batch, speed, acc)[0]
    scale = np.maximum(np.abs(state), 1e-3)
    fd = np.empty_like(exact)
    for j in range(size):
        h = 1e-6 * scale[j]
        up, down = state.copy(), state.copy()
        up[j] += h
        down[j] -= h
        fd[:, j] = (rhs(up, batch, speed, acc) - rhs(down, batch, speed, acc)) / (2 * h)
    # central differences: truncation ~ h^2 f''' plus rounding ~ eps |f| / h; with h = 1e-6 scale
    # both are ~1e-9 relative to the column's size.
    col = np.maximum(np.max(np.abs(exact), axis=0), np.max(np.abs(fd), axis=0))
    assert np.all(np.abs(exact - fd) <= 1e-6 * col + 1e-12)


def test_balanced_jacobian_matches_hand_linearisation():
    # The complex-step Jacobian at the balanced state must equal the companion matrix of the
    # hand-written (M0, C0, K0) of the research note to rounding.
    from balancer.adb import linearised_matrices, balanced_state
    p = REFERENCE
    wn = p.natural_frequency_rad_s
    speed = 2.0 * wn
    M0, C0, K0 = linearised_matrices(p, speed)
    n = p.n
    A = np.block([[np.zeros((n + 2, n + 2)), np.eye(n + 2)],
                  [-np.linalg.solve(M0, K0), -np.linalg.solve(M0, C0)]])
    J = rotating_frame_jacobian(balanced_state(p)[None], ParameterBatch.from_parameters(p), speed)[0]
    S = np.concatenate([[1 / p.R] * 2, [1.0] * n, [1 / (p.R * wn)] * 2, [1 / wn] * n])
    Jnd = S[:, None] * J / S[None, :] / wn
    # a dozen flops per entry on O(1) numbers: 1e-13 absolute is ~500 eps.
    assert np.max(np.abs(Jnd - A)) < 1e-13


@pytest.mark.parametrize("n", [2, 3])
def test_fixed_and_rotating_frames_give_the_same_trajectory(n):
    p = REFERENCE.replace(n=n)
    batch = ParameterBatch.from_parameters(p)
    omega = 2.0 * p.natural_frequency_rad_s
    rot0 = np.zeros(4 + 2 * n)
    rot0[0], rot0[1] = 1e-3, -5e-4
    rot0[2:2 + n] = np.linspace(0.3, 0.5, n)
    fix0 = rotating_to_fixed(rot0, 0.0, omega, n)
    assert np.allclose(fixed_to_rotating(fix0, omega, n), rot0, rtol=0, atol=1e-18)
    t_end = 0.2
    kw = dict(method="DOP853", rtol=1e-12, atol=1e-15, dense_output=True)
    rot = solve_ivp(lambda t, y: rotating_frame_rhs(y, batch, omega), (0, t_end), rot0, **kw)
    fix = solve_ivp(lambda t, y: fixed_frame_rhs(y, batch, omega), (0, t_end), fix0, **kw)
    times = np.linspace(0, t_end, 9)
    back = rotating_to_fixed(rot.sol(times).T, omega * times, omega, n)
    xy_fixed = fix.sol(times)[:2].T
    # both runs at rtol 1e-12 over ~6 revolutions; global error << 1e-9 of the 1e-3 m amplitude.
    assert np.max(np.abs(back[:, :2] - xy_fixed)) < 1e-11
    assert np.max(np.abs(back[:, 2:2 + n] - fix.sol(times)[2:2 + n].T)) < 1e-8


def test_rhs_is_vectorised_over_a_batch():
    rng = np.random.default_rng(0)
    members = [REFERENCE.replace(D=d, c=c) for d, c in [(1e-3, 20), (5e-3, 2), (1e-4, 50)]]
    batch = ParameterBatch.from_parameters(members)
    states = np.array([_random_state(rng, 2, 8, 0.05) for _ in members])
    together = rotating_frame_rhs(states, batch, np.array([50.0, 100.0, 300.0]))
    for i, member in enumerate(members):
        alone = rotating_frame_rhs(states[i], ParameterBatch.from_parameters(member), [50.0, 100.0, 300.0][i])
        assert np.array_equal(together[i], alone)


@pytest.mark.parametrize("n, ratio", [(2, 0.5), (2, 2.0), (3, 2.0), (5, 0.8), (1, 1.5)])
def test_rhs_vanishes_at_every_equilibrium(n, ratio):
    p = REFERENCE.replace(n=n)
    found = find_equilibria(p, ratio * p.natural_frequency_rad_s)
    assert found, "at least the unbalanced states exist"
    for eq in found:
        # scaled right-hand side: rounding of O(1) quantities, a few hundred eps at most
        assert eq.rhs_norm < 1e-13


def _full_mass_matrix_rhs(p, state, omega):
    """Independent rotating-frame RHS: assemble the (n+2)x(n+2) mass matrix of the Lagrange
    equations (adb.md 1b) and solve it, instead of eliminating the balls analytically."""
    n, M, m, R, e, k, c, D = p.n, p.M, p.m, p.R, p.e, p.k, p.c, p.D
    total = M + n * m
    u, v, phi, du, dv, dphi = state[0], state[1], state[2:2 + n], state[2 + n], state[3 + n], state[4 + n:]
    s, co = np.sin(phi), np.cos(phi)
    mass = np.zeros((n + 2, n + 2))
    mass[0, 0] = mass[1, 1] = total
    mass[0, 2:] = mass[2:, 0] = -m * R * s
    mass[1, 2:] = mass[2:, 1] = m * R * co
    mass[2:, 2:] = m * R * R * np.eye(n)
    spin = (omega + dphi) ** 2
    force = np.empty(n + 2)
    force[0] = (M * e * omega**2 + m * R * np.sum(spin * co) + total * (2 * omega * dv + omega**2 * u)
                - c * (du - omega * v) - k * u)
    force[1] = m * R * np.sum(spin * s) - total * (2 * omega * du - omega**2 * v) - c * (dv + omega * u) - k * v
    force[2:] = -D * dphi - m * R * (co * (2 * omega * du - omega**2 * v) + s * (2 * omega * dv + omega**2 * u))
    return np.concatenate([[du, dv], dphi, np.linalg.solve(mass, force)])


@pytest.mark.parametrize("n", [1, 2, 4])
def test_analytic_elimination_matches_full_mass_matrix(n):
    rng = np.random.default_rng(10 + n)
    p = REFERENCE.replace(n=n)
    for _ in range(5):
        state = _random_state(rng, n, 4 + 2 * n, p.R)
        fast = rotating_frame_rhs(state, ParameterBatch.from_parameters(p), 250.0)
        slow = _full_mass_matrix_rhs(p, state, 250.0)
        # same equations, different algebra (LU vs Cramer on the Schur complement):
        # agreement to ~1e-12 relative to the largest acceleration
        assert np.allclose(fast, slow, rtol=1e-11, atol=1e-11 * np.max(np.abs(slow)))


def test_equilibria_of_random_parameter_sets_are_fixed_points():
    # 30 random sets (n = 1-6, a up to n, speeds 0.2-8 omega_n): every equilibrium found, balanced
    # or not, makes the scaled right-hand side vanish to rounding.
    rng = np.random.default_rng(2024)
    for _ in range(30):
        n = int(rng.integers(1, 7))
        p = ADBParameters.from_nondimensional(
            n=n, mass_ratio=float(rng.uniform(0.002, 0.8 / (n + 1))), unbalance_ratio=float(rng.uniform(0.0, n)),
            damping_ratio=float(10 ** rng.uniform(-3, 0)), drag_ratio=float(10 ** rng.uniform(-3, 2)),
        )
        for eq in find_equilibria(p, float(rng.uniform(0.2, 8.0)) * p.natural_frequency_rad_s):
            assert eq.rhs_norm < 1e-12, (n, eq.kind)
