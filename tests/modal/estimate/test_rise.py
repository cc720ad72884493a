"""A response channel's power at the hits against its power before them (modal.estimate.rise)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import signal

import modal
from modal.errors import QualityWarning
from modal.estimate.rise import RISE_SIGMAS, rise_tests
from modal.synthetic import DigitalModes, impact_record
from modal.synthetic_time import hammer_force

FS = 1024.0
PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5]], FS)


def _dead(n: int, scale: float, seed: int) -> np.ndarray:
    """An unplugged sensor's noise, from a generator of its own (the force's seed would make it coherent)."""
    return scale * np.random.default_rng([seed, 99]).standard_normal(n)


def test_a_dead_channel_of_a_two_hit_record_is_warned_and_survives_the_archive(tmp_path):
    # two hits: every line's coherence is 1 whatever the channel holds, and the coherence test is not made; the
    # live channel's power rises tens of standard errors at the hits, the dead one's does not
    rec = impact_record(PLANT, [0.5, 2.6], 4.6, response_noise=0.01, force_noise=1e-3, seed=1).record.signals
    responses = np.vstack([rec[1], _dead(rec.shape[1], 0.01 * np.max(np.abs(rec[1])), 1)])
    with pytest.warns(QualityWarning, match=r"response 2 shows no relation to the force: its power in 125 ms "
                                            r"about the 2 trigger\(s\) [\d.]+ times that before them") as caught:
        est = modal.estimate_frf(rec[0], responses, FS, impact=True, window="force", segment_length=1024)
    assert not any("response 1 shows" in str(w.message) for w in caught)
    assert [u["channel"] for u in est.unrelated] == ["response 2"]
    item = est.unrelated[0]
    assert item["mean_coherence"] is None and item["rise"] < np.exp(RISE_SIGMAS * item["rise_log_se"])
    path = tmp_path / "est.h5"
    modal.write_frf(est, path)
    assert modal.read_frf(path).unrelated == est.unrelated


def test_a_live_channel_in_noise_with_three_hits_is_not_called_dead():
    # noise 15 % of the response's peak, 3 hits: the mean coherence lies 2.8 standard errors above chance (seed
    # 0; 2.4-4.7 over seeds 0-5), below the 5 that call a channel related; the power at the hits rises 7.1
    # standard errors (5.3-7.2) above that before them
    rec = impact_record(PLANT, [0.5, 2.6, 4.5], 6.5, response_noise=0.15, force_noise=1e-3,
                        amplitude_variation=0.2, seed=0).record.signals
    with warnings.catch_warnings():
        warnings.simplefilter("error", QualityWarning)
        est = modal.estimate_frf(rec[0], rec[1], FS, impact=True, window="force", segment_length=1024)
    assert est.unrelated == []


@pytest.mark.parametrize("noise", ["white", "hum-ac", "pink"])
def test_a_dead_channel_s_rise_is_chance(noise):
    # 150 dead channels beside a 3-hit force: under no relation log R / its standard error is ~N(0, 1): the mean
    # of 150 within 4/√150 = 0.33 of 0 and their SD within 0.75-1.3 (its sampling SD ≈ 0.06). Mains hum 3 times
    # the noise, AC-coupled at 50 ms, and noise low-passed to a pink-like spectrum (a pole at 0.95) leave it so
    rng = np.random.default_rng(3)
    triggers = 0.5 + 2.0 * np.arange(3) + rng.uniform(0.0, 0.4, 3)
    n = int((triggers[-1] + 2.0) * FS)
    y = rng.standard_normal((150, n))
    if noise == "hum-ac":
        t = np.arange(n) / FS
        y += 3.0 * np.sin(2 * np.pi * 50.0 * t + rng.uniform(0, 2 * np.pi, (150, 1)))
        a = np.exp(-1.0 / (0.05 * FS))
        y = signal.lfilter([a, -a], [1.0, -a], y, axis=1)
    elif noise == "pink":
        y = signal.lfilter([1.0], [1.0, -0.95], y, axis=1)
    force = hammer_force(n, FS, triggers, 0.002 * np.ones(3), 100.0 * np.ones(3))
    index = np.flatnonzero(np.diff((force > 5.0).astype(int)) == 1) + 1
    z = np.array([r.sigmas for r in rise_tests(y, index, np.ones(3, bool), 1024, 3, FS)])
    assert z.size == 150
    assert abs(np.mean(z)) < 0.33
    assert 0.75 < np.std(z) < 1.3


def test_a_zero_channel_does_not_rise_and_a_short_lead_in_is_not_read():
    y = np.zeros((1, 4096))
    assert not rise_tests(y, np.array([1000, 3000]), np.ones(2, bool), 1024, 3, FS)[0].rises
    # 20 samples before the only hit: no before-window of 32 samples fits
    assert rise_tests(np.ones((1, 2048)), np.array([20]), np.ones(1, bool), 1024, 3, FS) == []
