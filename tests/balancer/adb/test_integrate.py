"""Integration of one or a stacked batch of systems (balancer.adb.integrate): the method chosen by
stiffness, the exact Jacobian, and a batch that is each member's own run."""
from __future__ import annotations

import numpy as np

from balancer.adb import ADBParameters

from balancer.adb.simulate import simulate, simulate_batch
from balancer.adb.speed import LinearRunUp


S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s


def test_batch_matches_single_runs_and_counts_as_one_system():
    members = [S1.replace(D=d, c=c) for d, c in ((1e-3, 20.0), (3e-3, 10.0), (5e-4, 30.0))]
    batch = simulate_batch(members, 3 * WN, 0.4, n_samples=101)
    assert batch.rotor_x_m.shape == (3, 101) and batch.ball_angles_rad.shape == (3, 101, 2)
    for index, member in enumerate(members):
        single = simulate(member, 3 * WN, 0.4, n_samples=101, compare_without_balls=False)
        # batch tolerance is rtol / sqrt(3): both runs within ~1e-9 relative of the truth
        assert np.max(np.abs(single.rotor_x_m - batch.rotor_x_m[index])) < 1e-6 * np.max(single.amplitude_m)
        assert batch.final_state[index] == single.final_state


def test_stiff_drag_uses_an_implicit_method_with_the_exact_jacobian():
    # research note's "SEED?" set: D = 0.2 N m s, beta ~ 1180; the ball rate D/(m R^2) = 5.1e4 /s
    seed = ADBParameters(M=8, m=0.005, n=5, R=0.028, e=8e-5, k=15000, c=70.1, D=0.2)
    speed = 2 * seed.natural_frequency_rad_s
    stiff = simulate(seed, speed, 0.05, compare_without_balls=False, rtol=1e-9)
    assert stiff.method == "LSODA" and stiff.n_jacobian_evaluations > 0
    explicit = simulate(seed, speed, 0.05, compare_without_balls=False, method="DOP853", rtol=1e-9)
    # explicit steps are stability-limited to ~3/5.1e4 s: thousands of evaluations for 0.05 s
    assert stiff.n_function_evaluations * 3 < explicit.n_function_evaluations
    assert np.max(np.abs(stiff.rotor_x_m - explicit.rotor_x_m)) < 1e-5 * np.max(explicit.amplitude_m)
    batch = simulate_batch([seed, seed.replace(D=0.3)], speed, 0.05, n_samples=51)
    assert batch.method == "LSODA"
    assert np.max(np.abs(batch.rotor_x_m[0] - stiff.rotor_x_m[:: (stiff.time_s.size - 1) // 50][:51])) < 1e-5 * np.max(
        explicit.amplitude_m
    )


def test_batch_run_up_and_implicit_methods_match_single_runs():
    # Fixed-frame batch (speed profile) and the sparse block-diagonal Jacobian path (BDF):
    # each member must match its single run to well within 1e-6 of the amplitude (rtol 1e-9).
    members = [S1, S1.replace(D=3e-3)]
    profile = LinearRunUp(0.0, 2 * WN, 0.3)
    batch = simulate_batch(members, profile, 0.3, n_samples=61)
    implicit = simulate_batch(members, 2 * WN, 0.05, n_samples=26, method="BDF")
    explicit = simulate_batch(members, 2 * WN, 0.05, n_samples=26)
    assert implicit.method == "BDF" and explicit.method == "DOP853"
    for index, member in enumerate(members):
        single = simulate(member, profile, 0.3, n_samples=61, compare_without_balls=False)
        scale = np.max(single.amplitude_m)
        assert np.max(np.abs(batch.rotor_x_m[index] - single.rotor_x_m)) < 1e-6 * scale
        assert np.max(np.abs(implicit.rotor_y_m[index] - explicit.rotor_y_m[index])) < 1e-6 * np.max(
            np.abs(explicit.rotor_y_m[index]))
