"""A response channel unrelated to the force (modal.estimate.unrelated): warned, listed, calibrated to chance."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
import modal.estimate.core as core
from modal.errors import QualityWarning
from modal.estimate.unrelated import RELATED_SIGMAS, chance_tests
from modal.synthetic import DigitalModes, impact_record, random_record

FS = 1024.0
PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5]], FS)


def _dead(n: int, scale: float, seed: int) -> np.ndarray:
    """An unplugged sensor's noise, from a generator of its own (the force's seed would make it coherent)."""
    return scale * np.random.default_rng([seed, 99]).standard_normal(n)


def _random(duration_s: float, noise: float, seed: int):
    rec = random_record(PLANT, duration_s, response_noise=noise, seed=seed).record.signals
    return rec[0], np.vstack([rec[1], _dead(rec.shape[1], np.std(rec[1]), seed)])


def _sigmas(force, responses, **options) -> list[float]:
    """Standard errors above chance of each response, as the estimate computes them."""
    seen = []

    def record(*args, **kwargs):
        tests = chance_tests(*args, **kwargs)
        seen.extend(tests)
        return tests

    original, core.chance_tests = core.chance_tests, record
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)
            modal.estimate_frf(force, responses, FS, **options)
    finally:
        core.chance_tests = original
    return [t.sigmas for t in seen]


def test_a_dead_channel_of_a_random_test_is_warned_and_listed():
    force, responses = _random(16.0, 0.1, seed=1)
    with pytest.warns(QualityWarning, match=r"response 2 shows no relation to the force: mean coherence 0\.0\d+ "
                                            r"over its \d+ driven lines, chance 0\.0\d+ ± 0\.00\d+ with 31 records"):
        est = modal.estimate_frf(force, responses, FS, segment_length=1024)
    assert [u["channel"] for u in est.unrelated] == ["response 2"]
    item = est.unrelated[0]
    # chance under no relation: 1/n_eff, n_eff = 31 records over Welch's factor 1.056 (Hann, 50 %)
    assert item["chance"] == pytest.approx(1.056 / 31, rel=0.01)
    assert abs(item["mean_coherence"] - item["chance"]) < RELATED_SIGMAS * item["chance_se"]


def test_a_dead_channel_of_a_hammer_test_is_warned():
    rec = impact_record(PLANT, [0.5, 2.5, 4.5, 6.5, 8.5], 10.5, response_noise=0.01, force_noise=1e-3,
                        amplitude_variation=0.2, seed=2).record.signals
    responses = np.vstack([rec[1], _dead(rec.shape[1], 0.01 * np.max(np.abs(rec[1])), 2)])
    with pytest.warns(QualityWarning, match=r"response 2 shows no relation to the force: .* with 5 hits"):
        est = modal.estimate_frf(rec[0], responses, FS, impact=True, window="exponential",
                                 exponential_decay_s=0.5, segment_length=2048)
    assert [u["channel"] for u in est.unrelated] == ["response 2"]


def test_a_response_whose_noise_equals_its_peak_is_not_warned():
    # random excitation, response noise 4 times its RMS (about its peak): coherent on the modes' lines only. Its
    # mean coherence lies 20-27 standard errors above chance with 31 records (seeds 3-8); the median coherence
    # against the Beta(1, n - 1) 0.9 quantile, tried before, called it dead
    force, responses = _random(16.0, 4.0, seed=3)
    with pytest.warns(QualityWarning, match="response 2 shows no relation") as caught:
        est = modal.estimate_frf(force, responses, FS, segment_length=1024)
    assert [u["channel"] for u in est.unrelated] == ["response 2"]
    assert not any("response 1" in str(w.message) for w in caught)


@pytest.mark.parametrize("options", [
    dict(segment_length=512),  # Hann, 50 % overlap: overlapping records and correlated lines
    dict(impact=True, window="exponential", exponential_decay_s=0.3, segment_length=1024),  # g ≈ 1, c_out wide
    dict(impact=True, window="rect", segment_length=1024),  # 4 hits, uncorrelated lines
], ids=["random-hann", "hammer-exponential", "hammer-rect"])
def test_chance_and_its_standard_error_hold_for_dead_channels(options):
    # 120 dead channels beside one force: under no relation their standard errors above chance are ~N(0, 1):
    # the mean of 120 within 4/√120 = 0.37 of 0 and their SD within 0.75-1.3 (its sampling SD ≈ 0.065)
    if options.get("impact"):
        force = impact_record(PLANT, [0.5, 1.5, 2.5, 3.5], 4.5, force_noise=1e-3, amplitude_variation=0.2,
                              seed=4).record.signals[0]
    else:
        force = np.random.default_rng(4).standard_normal(int(8 * FS))
    responses = np.random.default_rng(5).standard_normal((120, force.size))
    z = np.array(_sigmas(force, responses, **options))
    assert z.size == 120
    assert abs(np.mean(z)) < 0.37
    assert 0.75 < np.std(z) < 1.3


def test_a_dead_channel_that_shares_the_force_s_hum_is_warned():
    # mains hum on the force and on the dead channel: coherent at 50 Hz and its record's neighbours, though
    # unrelated to the structure; the force's tone lines are not counted
    force, responses = _random(32.0, 0.1, seed=6)
    t = np.arange(force.size) / FS
    force = force + 0.05 * np.max(np.abs(force)) * np.sin(2 * np.pi * 50.0 * t)
    responses[1] += 2.0 * np.std(responses[1]) * np.sin(2 * np.pi * 50.0 * t + 1.0)
    with pytest.warns(QualityWarning, match="response 2 shows no relation"):
        est = modal.estimate_frf(force, responses, FS, segment_length=512)
    assert [u["channel"] for u in est.unrelated] == ["response 2"]


def test_unrelated_channels_survive_the_archive(tmp_path):
    force, responses = _random(16.0, 0.1, seed=7)
    with pytest.warns(QualityWarning, match="shows no relation"):
        est = modal.estimate_frf(force, responses, FS, segment_length=1024)
    path = tmp_path / "est.h5"
    modal.write_frf(est, path)
    assert modal.read_frf(path).unrelated == est.unrelated
