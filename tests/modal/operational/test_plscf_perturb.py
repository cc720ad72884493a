"""pLSCF's first-order pole deviations: the exact linearisation of the estimator."""
from __future__ import annotations

import numpy as np
import pytest

from modal.global_.plscf import plscf_poles
from modal.operational.correlations import correlations
from modal.operational.plscf import half_spectra
from modal.operational.plscf_perturb import PlscfPerturbation
from modal.synthetic import ambient_modal_response
from support.ambient import anchor_shapes

FS = 100.0


@pytest.fixture(scope="module")
def spectra():
    rec = ambient_modal_response([5.0, 12.0, 21.0], [0.02, 0.015, 0.01], anchor_shapes(4)[:, :3], FS, 60_000,
                                 noise=0.1, seed=3)
    y = rec.signals - rec.signals.mean(axis=1, keepdims=True)
    corr = correlations(y, FS, [0, 1], 120, max_blocks=6)
    lines = np.arange(1.0, 30.0, FS / 242)
    S, _ = half_spectra(corr.mean, FS, lines)
    dS = half_spectra(corr.blocks, FS, lines)[0] - S[None]
    return 2 * np.pi * lines, S, dS


@pytest.mark.parametrize("order", [3, 8])
def test_poles_are_those_of_plscf(spectra, order):
    omega, S, dS = spectra
    s, _ = PlscfPerturbation(omega, S, dS, 10).at(order)
    pack = plscf_poles(omega, S, [order], max_damping=0.5)[0]
    expected = -pack.damping_ratio * pack.omega_n + 1j * pack.omega_n * np.sqrt(1 - pack.damping_ratio**2)
    for pole in expected:
        # the same normal equations and companion matrix, solved in another order of operations
        assert np.min(np.abs(s - pole)) < 1e-8 * abs(pole)


@pytest.mark.parametrize("order", [3, 8])
def test_deviations_match_finite_differences(spectra, order):
    # each deviation against the poles recomputed by plscf_poles from the half-spectra moved by a small step of
    # it either way (central differences). Their own error is smallest near a step of 1e-4: below it, the
    # rounding of the (ill-conditioned) normal equations grows as 1/step; above it, the
    # third-order term of the most sensitive (noise) poles as step². At 1e-4 both stay below 1e-4 of the
    # deviation, against 1e-2 and more for a wrong derivative
    omega, S, dS = spectra
    s, d_s = PlscfPerturbation(omega, S, dS, 10).at(order)
    base = plscf_poles(omega, S, [order], max_damping=0.5)[0]
    step = 1e-4

    def poles(pack):
        return -pack.damping_ratio * pack.omega_n + 1j * pack.omega_n * np.sqrt(1 - pack.damping_ratio**2)

    for b in range(dS.shape[0]):
        plus, minus = (poles(plscf_poles(omega, S + sign * step * dS[b], [order], max_damping=0.5)[0])
                       for sign in (1.0, -1.0))
        for pole in poles(base):
            numeric = (plus[np.argmin(np.abs(plus - pole))] - minus[np.argmin(np.abs(minus - pole))]) / (2 * step)
            analytic = d_s[b, np.argmin(np.abs(s - pole))]
            assert abs(numeric - analytic) < 3e-4 * abs(analytic)
