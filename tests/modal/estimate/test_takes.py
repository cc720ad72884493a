"""Several takes of one test estimated as one (modal.estimate.takes): no record straddles two takes."""
from __future__ import annotations

import numpy as np
import pytest

import modal
from modal.errors import ParameterError
from modal.estimate import spectra
from modal.estimate.windows import segment_window
from modal.synthetic import DigitalModes, impact_record, random_record

FS = 1024.0
PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], FS)
HITS_S = 0.5 + 1.25 * np.arange(8)  # eight hits, 1.25 s apart, in 10 s: the last one's 1 s record is cut by the end


def _impact(record, **kwargs):
    return modal.estimate_frf(record.signals[0], record.signals[1:], FS, impact=True, window="force",
                              kind="accelerance", response_quantity="acceleration", **kwargs)


def test_hits_split_between_takes_give_the_estimate_of_one_recording():
    # cut in the quiet between hit 4 (4.25 s) and hit 5 (5.5 s), after hit 4's 1024-sample record ends (5.23 s):
    # every hit record lies within one take, so the sums, and the estimate, are those of the whole recording
    record = impact_record(PLANT, HITS_S, 10.0, force_noise=0.002, response_noise=0.01, seed=1).record
    cut = int(5.3 * FS)
    whole = _impact(record, segment_length=1024)
    takes = _impact(record, segment_length=1024, take_lengths=[cut, record.n_samples - cut],
                    take_names=["a.csv", "b.csv"])
    assert takes.averages == whole.averages == 7
    np.testing.assert_allclose(takes.response, whole.response, rtol=1e-12)
    np.testing.assert_allclose(takes.noise_std, whole.noise_std, rtol=1e-12)
    np.testing.assert_allclose(takes.hit_times_s, whole.hit_times_s)


def test_a_hit_cut_by_the_end_of_its_take_is_rejected_and_named():
    # a cut 0.3 s after hit 4: its record (1 s) would run into the next take, whose first samples belong to
    # another recording; the hit is rejected as cut, naming its take, and counted within it
    record = impact_record(PLANT, HITS_S, 10.0, force_noise=0.002, response_noise=0.01, seed=2).record
    cut = int((HITS_S[3] + 0.3) * FS)
    est = _impact(record, segment_length=1024, take_lengths=[cut, record.n_samples - cut],
                  take_names=["a.csv", "b.csv"])
    assert est.averages == 6
    assert [(r["take_name"], r["hit"], r["reason"]) for r in est.rejected] == [
        ("a.csv", 4, "record cut by the start or end of the data"),
        ("b.csv", 4, "record cut by the start or end of the data")]
    assert est.rejected[0]["time_s"] == pytest.approx(HITS_S[3], abs=2 / FS)
    # the same record as one recording keeps that hit
    assert _impact(record, segment_length=1024).averages == 7


def test_a_take_without_hits_is_named():
    record = impact_record(PLANT, HITS_S[:4], 10.0, force_noise=0.002, seed=3).record
    cut = int(5.3 * FS)  # the second take holds noise only
    with pytest.raises(ParameterError, match=r"^b\.csv: impact record expected, but force has no hit"):
        _impact(record, take_lengths=[cut, record.n_samples - cut], take_names=["a.csv", "b.csv"])


def test_continuous_takes_are_segmented_within_each_take():
    # two takes of 20000 and 12000 samples, 4096-sample Hann segments at half overlap: (20000 − 4096)//2048 + 1
    # = 8 segments in the first, 4 in the second, none across the join; the estimate is H1 of those sums
    record = random_record(PLANT, 32000 / FS, response_noise=0.05, seed=4).record
    x, y = record.signals[:1], record.signals[1:]
    est = modal.estimate_frf(x, y, FS, kind="accelerance", response_quantity="acceleration", segment_length=4096,
                             take_lengths=[20000, 12000])
    assert est.averages == 12
    starts = np.concatenate([np.arange(0, 20000 - 4096 + 1, 2048), 20000 + np.arange(0, 12000 - 4096 + 1, 2048)])
    window = segment_window("hann", 4096)
    sums = spectra.accumulate(x, y, starts, 4096, window, window)
    np.testing.assert_allclose(est.response, sums.syx[:, 0] / sums.sxx[0, 0], rtol=1e-10)
    # a segment longer than the shortest take cannot be cut within it
    with pytest.raises(ParameterError, match="expected 2 to 12000 samples \\(the shortest take\\)"):
        modal.estimate_frf(x, y, FS, kind="accelerance", response_quantity="acceleration", segment_length=16384,
                           take_lengths=[20000, 12000])


def test_take_lengths_must_add_up():
    record = random_record(PLANT, 8.0, seed=5).record
    with pytest.raises(ParameterError, match="'take_lengths' adds up to 8000 samples; expected the 8192"):
        modal.estimate_frf(record.signals[0], record.signals[1:], FS, take_lengths=[4000, 4000])
