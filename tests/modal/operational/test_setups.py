"""Merging setups: roving sensors with shared references."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.errors import ParameterError
from modal.operational.selection import shape_mac
from support.ambient import FN, anchor_record

SETUP1 = [0, 5, 1, 2, 3]  # references 0 and 5 first
SETUP2 = [0, 5, 4, 6, 7]


def _oma(signals):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return modal.oma(signals, 100.0, band_hz=(1.0, 30.0))


def test_merged_shapes_cover_every_channel():
    one = anchor_record(41, noise=0.1, tones=False)
    two = anchor_record(42, noise=0.1, tones=False)
    merged = modal.merge_setups([_oma(one.signals[SETUP1]), _oma(two.signals[SETUP2])], reference_channels=[0, 1])
    order = SETUP1 + [4, 6, 7]
    assert merged.n_channels == 8 and len(merged) == 6
    assert merged.settings["channel_names"][5] == "setup2:2"
    for k, f in enumerate(FN):
        near = [m for m in merged if abs(m.natural_frequency_hz / f - 1) < 0.005]
        assert len(near) == 1
        assert near[0].mode_shape.shape == (8,)
        assert shape_mac(near[0].mode_shape, one.mode_shape[order, k]) >= 0.98


def test_a_mode_missing_from_a_setup_is_flagged():
    one = anchor_record(43, noise=0.1, tones=False)
    two = modal.synthetic.ambient_modal_response([3.1, 7.4], [0.015, 0.01], np.ones((5, 2)) * [[1.0, 0.5]] +
                                                 np.arange(5)[:, None] * [[0.1, -0.3]], 100.0, 100_000, seed=44)
    first = _oma(one.signals[SETUP1])
    with pytest.warns(modal.QualityWarning, match="missing_in_setup"):
        merged = modal.merge_setups([first, _oma(two.signals)], reference_channels=[0, 1])
    high = [m for m in merged if m.natural_frequency_hz > 10]
    assert high and all("missing_in_setup" in m.flags and np.all(np.isnan(m.mode_shape[5:])) for m in high)


def test_bad_references_are_refused():
    one = anchor_record(45, noise=0.1, tones=False, duration_s=400)
    r = _oma(one.signals[SETUP1])
    with pytest.raises(ParameterError, match="at least 2 setups"):
        modal.merge_setups([r], reference_channels=[0])
    with pytest.raises(ParameterError, match="setup 2 is \\[0, 9\\]"):
        modal.merge_setups([r, r], reference_channels=[[0, 1], [0, 9]])
