"""Equilibria at constant speed (balancer.adb.equilibria): the unbalanced states below the natural
frequency and the balanced family of three and more balls.

Reference numbers come from the research note's independent script (``adb.md`` section 2); they are
reproduced, not tuned.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from balancer.adb import (
    ADBParameters,
    ParameterBatch,
    balanced_ball_angles,
    balanced_state,
    find_equilibria,
    symmetric_spacing_rad,
)
from balancer.adb.equations import rotating_frame_jacobian
from balancer.adb.linear import eigen_analysis
from modal.errors import ParameterError


S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s


def test_unbalanced_states_at_half_speed():
    # adb.md section 2: at Omega = 0.5 the only stable state has both balls on the heavy
    # side (q = +2) with r = 0.0153 R (Green et al. 2006 report the same).
    found = find_equilibria(S1, 0.5 * WN)
    stable = [eq for eq in found if eq.stability == "stable"]
    assert len(stable) == 1
    assert stable[0].kind == "unbalanced" and stable[0].balls_on_deflection_side == 2
    assert stable[0].rotor_offset_m / S1.R == pytest.approx(0.0153, abs=5e-5)
    # the q = 0 state is the plain rotor's response
    plain = [eq for eq in found if eq.balls_on_deflection_side == 1]
    Om, zeta, eps = 0.5, S1.damping_ratio, S1.eccentricity_ratio
    expected = eps * Om**2 / math.hypot(1 - Om**2, 2 * zeta * Om)
    assert plain[0].rotor_offset_m / S1.R == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("n", [3, 5])
def test_family_members_and_zero_eigenvalues(n):
    p = S1.replace(n=n)
    symmetric = balanced_ball_angles(p)
    spacing = np.diff(np.sort(np.mod(symmetric, 2 * np.pi)))
    assert np.allclose(spacing, symmetric_spacing_rad(n, p.unbalance_ratio), atol=1e-12)
    free = [2.0] if n == 3 else 0.3 + np.array([0.0, 2.0, 4.0]) * np.pi / 3  # leave |S| <= 2
    other = balanced_ball_angles(p, free_angles_rad=free)
    for angles in (symmetric, other):
        assert abs(p.unbalance_ratio + np.sum(np.exp(1j * angles))) < 1e-13
    # the balanced family gives n - 2 exact zero eigenvalues (to rounding) in the full Jacobian
    J = rotating_frame_jacobian(balanced_state(p)[None], ParameterBatch.from_parameters(p), 3 * p.natural_frequency_rad_s)
    full = eigen_analysis(J, n, p.R, p.natural_frequency_rad_s)
    assert np.sum(np.abs(full.eigenvalues_per_s) / p.natural_frequency_rad_s < 1e-10) == n - 2
    if n == 5:  # three free balls together at the heavy side: |S| = a + 3 > 2, no completion
        with pytest.raises(ParameterError, match="free_angles_rad"):
            balanced_ball_angles(p, free_angles_rad=np.zeros(n - 2))
    with pytest.raises(ParameterError, match="residual"):
        balanced_state(p, np.zeros(n))
