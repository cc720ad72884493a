"""FDD and EFDD: the quick looks."""
from __future__ import annotations

import warnings

import numpy as np

import modal
from modal.operational.selection import shape_mac
from support.ambient import FN, ZETA, anchor_record


def _run(method, seed=31):
    rec = anchor_record(seed, noise=0.1, tones=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rec, modal.oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0), method=method)


def test_fdd_peaks_are_the_separated_modes_and_tones_apart():
    rec, result = _run("fdd")
    spacing = result.settings["line_spacing_hz"]
    # the well separated, well excited modes (the close pair's second and the weak mode may hide in the
    # first singular value's peak of their neighbour)
    for k in (0, 1, 2, 5):
        # a peak of a noisy spectrum: located within the mode's half-power half-width ζ·fn
        near = [m for m in result if abs(m.natural_frequency_hz - FN[k]) <= max(spacing, ZETA[k] * FN[k])]
        assert len(near) == 1, (FN[k], [m.natural_frequency_hz for m in result])
        assert np.isnan(near[0].damping_ratio) and "high_uncertainty" in near[0].flags
        assert shape_mac(near[0].mode_shape, rec.mode_shape[:, k]) >= 0.98
    assert np.allclose(sorted(result.harmonics_hz), [4.8, 9.6, 14.4], atol=spacing)
    assert all(abs(m.natural_frequency_hz - t) > spacing for m in result for t in (4.8, 9.6, 14.4))


def test_efdd_damping_has_no_window_bias():
    # the lag window's decay is known and taken off: no doubling of damping as with a Hann-windowed
    # spectrum; what is left is EFDD's own error (bell truncation, fit range): within 35 % here
    rec, result = _run("efdd")
    for k in (0, 1, 5):
        near = [m for m in result if abs(m.natural_frequency_hz / FN[k] - 1) < 0.005]
        assert len(near) == 1
        assert abs(near[0].damping_ratio / ZETA[k] - 1) < 0.35
