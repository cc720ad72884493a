"""Splitting a correction onto fixed holes (balancer.influence.split)."""
from __future__ import annotations

import numpy as np
import pytest

from balancer.influence import equally_spaced_deg, split_correction
from modal.errors import ParameterError


# ---------------------------------------------------------------- splitting onto holes
def test_split_is_exact_on_random_vectors():
    rng = np.random.default_rng(3)
    for n_holes in (3, 5, 8, 12):
        positions = np.sort(rng.uniform(0, 360, n_holes)) if n_holes == 12 else equally_spaced_deg(n_holes, 10.0)
        gaps = np.diff(np.concatenate([np.sort(positions), [np.sort(positions)[0] + 360]]))
        if gaps.max() >= 180:
            continue
        u = (rng.normal(size=500) + 1j * rng.normal(size=500)) * 10 ** rng.uniform(-4, 0, 500)
        amounts = split_correction(u, positions)
        rebuilt = amounts @ np.exp(1j * np.deg2rad(positions))
        np.testing.assert_allclose(rebuilt, u, rtol=0, atol=1e-12 * np.abs(u).max())
        assert np.all(amounts >= 0)
        assert np.all((amounts > 0).sum(axis=1) <= 2)
        order = np.argsort(np.mod(positions, 360))
        for row in amounts[:, order]:  # non-zero amounts on adjacent holes (cyclically)
            nz = np.flatnonzero(row)
            if nz.size == 2:
                assert nz[1] - nz[0] in (1, n_holes - 1)
    np.testing.assert_allclose(split_correction(2.0 * np.exp(1j * np.deg2rad(90)), [0, 90, 180, 270]), [0, 2, 0, 0], atol=1e-15)


def test_split_refuses_a_gap_wider_than_half_a_turn():
    with pytest.raises(ParameterError, match="positions_deg"):
        split_correction(np.exp(1j * np.deg2rad(200)), [0.0, 90.0])
