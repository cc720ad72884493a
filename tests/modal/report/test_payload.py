"""What the report's script draws: decimated curves that keep every peak, and JSON that parses."""
import json

import numpy as np

import modal
from modal.report.payload import MAX_DRAWN_CHANNELS, drawn_channels, drawn_lines, frf_payload, to_json


def test_drawn_lines_keep_every_line_below_the_limit_and_each_buckets_extremes_above():
    assert drawn_lines(np.ones(100), limit=200).tolist() == list(range(100))
    rng = np.random.default_rng(3)
    values = rng.random(100_000)
    values[[777, 54_321]] = [50.0, 80.0]  # two narrow peaks, one line wide
    values[99_000] = -1.0
    idx = drawn_lines(values, limit=1000)
    assert idx.size <= 1002  # two per bucket and both ends
    assert {777, 54_321, 99_000} <= set(idx.tolist())  # no peak (or dip) lost however narrow
    assert idx[0] == 0 and idx[-1] == 99_999


def test_channels_offered_are_spread_over_the_file():
    assert drawn_channels(5).tolist() == [0, 1, 2, 3, 4]
    many = drawn_channels(1000)
    assert many.size == MAX_DRAWN_CHANNELS and many[0] == 0 and many[-1] == 999


def test_json_is_valid_with_nan_as_null_and_no_script_end():
    text = to_json({"a": np.array([1.0, np.nan, np.inf, 1.234567e-9]), "s": "</script><b>", "n": None, "b": True,
                    "i": np.int64(3), "f": float("nan")})
    doc = json.loads(text)
    assert doc["a"] == [1.0, None, None, 1.2346e-09]  # five significant digits
    assert doc["s"] == "</script><b>" and "</script>" not in text
    assert doc["n"] is None and doc["b"] is True and doc["i"] == 3 and doc["f"] is None


def test_frf_payload_of_many_channels_offers_a_sample_and_the_rms_of_all():
    f = np.arange(1.0, 101.0)
    frf = modal.modal_frf(f, [40.0], [0.02], np.linspace(0.1, 1.0, 200)[:, None])
    payload = frf_payload(frf, [])
    assert len(payload["entries"]) == MAX_DRAWN_CHANNELS + 1
    rms = payload["entries"][0]
    np.testing.assert_allclose(rms["mag"], np.sqrt(np.mean(np.abs(frf.channels) ** 2, axis=0)))
    assert "32 of 200 channels" in payload["note"]


def test_an_frf_estimated_from_time_data_brings_its_coherence():
    rng = np.random.default_rng(8)
    fs = 1024.0
    force = rng.normal(size=16384)
    # causal: a response 100 samples ahead of its force (mode="same") is one H1 reads far too low, warned
    response = np.convolve(force, np.exp(-np.arange(200) / 20.0) * np.sin(np.arange(200) * 0.6))[:force.size]
    response = response + 0.5 * rng.normal(size=force.size)  # output noise lowers the coherence
    est = modal.estimate_frf(force, response, fs, segment_length=512)
    payload = frf_payload(est, [])
    drawn = payload["entries"][0]
    np.testing.assert_allclose(drawn["coherence"], np.atleast_2d(est.coherence)[0])
    assert 0 < np.nanmin(drawn["coherence"]) < 0.999  # the noise shows as coherence below 1
