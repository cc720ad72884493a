"""Clipping and overload detection (modal.estimate.overload), and what continuous estimates do with it."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.errors import QualityWarning
from modal.estimate.overload import find_overloads
from modal.io.timedata import read_time
from modal.synthetic import DigitalModes, random_record
from support.paths import REAL

FS = 1024.0
PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], FS)


def test_no_false_alarm_on_the_real_record():
    # 69.5 s of real accelerations (four channels, 3.2 kHz): no channel repeats its extreme value
    record = read_time(REAL / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff")
    assert find_overloads(record.signals) == []


def test_a_symmetric_peak_is_not_a_flat_top():
    # a half sine three samples wide peaks between two samples that agree to the last bit or two: not equal
    t = np.arange(64) / 3.0
    pulse = np.where(t < 1, np.sin(np.pi * t), 0.0)
    assert pulse[1] != pulse[2] and abs(pulse[1] - pulse[2]) < 1e-15
    assert find_overloads(pulse) == []


def test_quantised_smooth_peaks_are_not_clipping_but_a_rail_is():
    # a 12-bit converter recording a slow sine (1000.37 samples per period, 0.3 codes of noise): its top code
    # repeats over several samples, and the codes beside them are one step down; the clipped sine enters its
    # rail at about ten codes per sample
    code = 2.0 / 4096
    t = np.arange(20000)
    noise = 0.3 * code * np.random.default_rng(0).standard_normal(t.size)
    smooth = np.round((0.8 * np.sin(2 * np.pi * t / 1000.37) + noise) / code) * code
    tops = smooth == smooth.max()
    assert np.any(tops[1:] & tops[:-1])  # the top code repeats...
    assert find_overloads(smooth) == []  # ...but that is not clipping
    clipped = np.clip(np.round((1.3 * np.sin(2 * np.pi * t / 1000.37) + noise) / code) * code, -1.0, 1.0 - code)
    found = find_overloads(clipped)
    assert [(o.channel, o.how) for o in found] == [(0, "flat tops")]
    assert found[0].samples == int(np.sum((clipped == 1.0 - code) | (clipped == -1.0)))


def test_declared_full_scale_marks_samples_at_999_per_mille():
    x = np.array([[0.0, 0.5, 0.9989, 0.999, -1.2, 0.3], [0.0, 1.0, 2.0, 3.0, 2.0, 1.0]])
    found = find_overloads(x, full_scale=[1.0, None])
    assert len(found) == 1 and found[0].how == "full scale" and found[0].level == 1.0
    assert found[0].mask.tolist() == [False, False, False, True, True, False]


def test_a_clipped_continuous_record_warns_and_says_which_channel():
    clean = random_record(PLANT, 64.0, response_noise=0.01, seed=5)
    rms = np.sqrt(np.mean(clean.record.signals[2] ** 2))
    clipped = random_record(PLANT, 64.0, response_noise=0.01, seed=5, full_scale=[None, None, 2.5 * rms],
                            declare_full_scale=False)
    assert clipped.clipped_samples[2] > 0
    record = clipped.record
    with pytest.warns(QualityWarning, match=r"response p2 clipped at .* \(flat tops"):
        est = modal.estimate_frf(record.signals[0], record.signals[1:], FS, kind="accelerance",
                                 response_quantity="acceleration", response_points=["p1", "p2"])
    assert [(o["channel"], o["how"], o["samples"]) for o in est.overloads] == [
        ("response p2", "flat tops", clipped.clipped_samples[2])]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the unclipped record: no warning at all
        est = modal.estimate_frf(clean.record.signals[0], clean.record.signals[1:], FS, kind="accelerance",
                                 response_quantity="acceleration")
    assert est.overloads == []


def test_overloads_survive_the_archive(tmp_path):
    clipped = random_record(PLANT, 16.0, seed=6, full_scale=[2.0, None, None], declare_full_scale=False)
    record = clipped.record
    with pytest.warns(QualityWarning):
        est = modal.estimate_frf(record.signals[0], record.signals[1:], FS, kind="accelerance",
                                 response_quantity="acceleration")
    path = tmp_path / "est.h5"
    modal.write_frf(est, path)
    assert modal.read_frf(path).overloads == est.overloads
