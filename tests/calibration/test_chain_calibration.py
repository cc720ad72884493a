"""Calibration of the chain, time records → FRF → modes: z = (estimate − truth) / reported std.

The cells of ``benchmarks/bench_chain.py`` the chain is held to, over 80 records each (an exactly
sampled two-mode structure, ``modal.estimate_frf`` and ``modal.identify`` with their defaults).

Tolerances, for the 80 z-values of one quantity of one mode:

* standard deviation within 0.75–1.3: the sample SD of 80 standard normals has standard error
  1/√160 = 0.079, so a calibrated estimator lies within ±0.25 (3.2 of those); the band is the one
  the chain is held to (errors up to 25 % too large, 30 % too small);
* |mean| ≤ 0.35: standard error of the mean 1/√80 = 0.11; 0.35 is 3.1 of those.

Random excitation with the default Hann segments meets the mean (the window's bias, +0.8 to +1.0
standard errors of ζ before, is fitted out) and, for the damping, the spread: its errors' line correlation
is measured over the records (near the peaks it is leakage's, not the window's) and the truncation check
reads the whitened residual (on the raw one it fired on every record and added its shift, noise, to the
errors: spread 0.69–0.88 before). The frequency's errors are still up to 1.8 times the scatter (spread
0.44–0.78 over seed sets): that test asserts only the upper bound there. The hammer with an
exponential window meets the target for both modes: its errors' correlation over the window's tens of
lines is whitened as it is (not tapered), and the force noise, which at the peaks is most of the error and
correlates through the force window, is in the noise model.
"""
from __future__ import annotations

import functools

import numpy as np
import pytest

RECORDS = 80


@functools.lru_cache(maxsize=None)
def _scores(cell: str):
    from benchmarks.bench_chain import CELLS, z_scores

    return z_scores(CELLS[cell], RECORDS)


@pytest.mark.parametrize("mode", [0, 1])
@pytest.mark.parametrize("quantity", ["fn", "zeta"])
def test_hammer_with_exponential_window_is_calibrated(quantity, mode):
    scores = _scores("hammer-exp-6")
    z = scores["z"][(quantity, mode)]
    assert scores["found"][mode] == RECORDS
    assert 0.75 <= np.std(z) <= 1.3, np.std(z)
    assert abs(np.mean(z)) <= 0.35, np.mean(z)


@pytest.mark.parametrize("mode", [0, 1])
@pytest.mark.parametrize("quantity", ["fn", "zeta"])
def test_random_excitation_is_unbiased_and_not_overconfident(quantity, mode):
    scores = _scores("random-hann-default")
    z = scores["z"][(quantity, mode)]
    assert scores["found"][mode] == RECORDS
    assert np.std(z) <= 1.3, np.std(z)
    if quantity == "zeta":
        assert np.std(z) >= 0.75, np.std(z)
    assert abs(np.mean(z)) <= 0.35, np.mean(z)
