"""Hits of an impact record (modal.estimate.hits): rebounds, hits inside another's response, overloads."""
from __future__ import annotations

import collections
import dataclasses
import re

import numpy as np
import pytest

import modal
from modal.estimate.hits import find_hits, pulse_train, reject_pulses_the_window_cuts
from modal.estimate.takes import hit_labels
from modal.estimate.windows import force_window
from modal.synthetic import DigitalModes, hammer_force, impact_record

FS = 2048.0
#: decay times 1/(ζωn): 0.13 s (40 Hz) and 0.084 s (95 Hz)
PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], FS)


def _estimate(record, **kwargs):
    return modal.estimate_frf(record.signals[0], record.signals[1:], record.sample_rate_hz, impact=True,
                              **{"window": "force", "kind": "accelerance", "response_quantity": "acceleration",
                                 **kwargs})


def test_a_rebound_while_the_response_rings_makes_a_double_hit():
    # a second pulse of 30 % 60 ms after hit 2, when its response is still at about e^(−0.06/0.13) ≈ 60 %
    # of its peak: today's bounce window (50 ms) missed it, so the rebound became a hit of its own and hit 2
    # was rejected as not decayed. It belongs to hit 2: the event is a double hit, and no record starts
    # at the rebound
    synthetic = impact_record(PLANT, [0.5, 2.5, 4.5, 6.5], 8.0, rebound_delay_s=[None, 0.06, None, None],
                              rebound_fraction=0.3, force_noise=0.002, response_noise=0.002, seed=2)
    est = _estimate(synthetic.record)
    assert [(r["hit"], r["reason"]) for r in est.rejected] == [(2, "double hit")]
    assert "60 ms after the first" in est.rejected[0]["detail"] and "% of its peak" in est.rejected[0]["detail"]
    assert est.averages == 3
    np.testing.assert_allclose(est.hit_times_s, [0.5, 4.5, 6.5], atol=2 / FS)
    # no record holds the rebound's force or its response: the estimate is the system's within the noise
    truth = synthetic.frf(est.frequency_hz)
    band = (est.frequency_hz > 10) & (est.frequency_hz < 200)
    error = np.abs(est.response[:, band] - truth[:, band]) / est.noise_std[:, band]
    assert np.median(error) < 2  # Rayleigh: median √ln 2 ≈ 0.83 when only noise is left


def test_a_late_rebound_after_the_response_decayed_is_a_hit_of_its_own():
    # 1.5 s after hit 1 (over 10 decay times): the response has decayed, so the pulse starts a new hit
    synthetic = impact_record(PLANT, [0.5, 4.5], 6.0, rebound_delay_s=[1.5, None], force_noise=0.002,
                              response_noise=0.002, seed=3)
    hits = find_hits(synthetic.record.signals[0], synthetic.record.signals[1:], FS)
    np.testing.assert_allclose(hits.trigger_index / FS, [0.5, 2.0, 4.5], atol=2 / FS)
    assert hits.rejected == []


def test_a_weak_hit_in_the_tail_of_a_strong_one_is_rejected():
    # hit 2 (10 N) comes 0.6 s after hit 1 (100 N): hit 1's response has fallen to about e^(−0.5/0.13) ≈ 2 %
    # of its peak 0.1 s before (decayed, by its own measure), but that is about 20 % of hit 2's peak: hit 2's
    # record would start inside hit 1's response
    n = int(4 * FS)
    force = hammer_force(n, FS, [0.5, 1.1, 2.95], width_s=0.003, amplitude_n=[100.0, 10.0, 100.0])
    response = PLANT.respond(force, "acceleration")
    hits = find_hits(force, response, FS, record_length=1024)
    assert [(r["hit"], r["reason"]) for r in hits.rejected] == [(2, "response of an earlier hit still ringing")]
    assert "of this hit's peak when it started" in hits.rejected[0]["detail"]
    assert hits.accepted.tolist() == [True, False, True]


def test_clipped_hits_are_rejected_and_the_others_kept():
    # the converter saturates at 100 N: hits above it have flat tops (3 ms pulses, 6 samples each), those
    # below are untouched. Noise on force and response (0.2 % of the peak) never repeats a value exactly
    synthetic = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, pulse_width_s=0.003, amplitude_variation=0.2,
                              full_scale=[100.0, None, None], declare_full_scale=False, force_noise=0.002,
                              response_noise=0.002, seed=1)
    force = synthetic.record.signals[0]
    on_rail = [force[int(t * FS):int(t * FS) + 8] == 100.0 for t in synthetic.hit_times_s]
    clipped = [k + 1 for k, rail in enumerate(on_rail) if rail.any()]
    assert 0 < len(clipped) < 6  # the seed gives both kinds
    # a flat top (two samples on the rail) shows where the rail is; then a hit with one sample on it is clipped too
    assert any(np.any(rail[1:] & rail[:-1]) for rail in on_rail)
    est = _estimate(synthetic.record)
    assert [r["hit"] for r in est.rejected] == clipped
    assert {r["reason"] for r in est.rejected} == {"overload (clipped)"}
    assert all(r["detail"].startswith("force clipped at 100 (flat tops") for r in est.rejected)
    assert est.averages == 6 - len(clipped)
    assert est.overloads == [{"channel": "force", "how": "flat tops", "level": 100.0, "samples": int(
        np.sum(force == 100.0)), "longest_run": est.overloads[0]["longest_run"]}]


def test_a_declared_full_scale_rejects_hits_that_reach_it():
    # one sample at the rail: no flat top to see, but the declared full scale of the response says so
    synthetic = impact_record(PLANT, [0.5, 2.5, 4.5], 6.0, amplitude_variation=0.3, force_noise=0.002,
                              response_noise=0.002, seed=4)
    record = synthetic.record
    peaks = [np.max(np.abs(record.signals[1, int(t * FS):int((t + 1) * FS)])) for t in synthetic.hit_times_s]
    level = float(np.sort(peaks)[-1]) * 1.0005  # the largest hit's response peak sits within 0.1 % of it
    est = _estimate(record, full_scale=[None, level, None])
    strongest = int(np.argmax(peaks)) + 1
    assert [(r["hit"], r["reason"]) for r in est.rejected] == [(strongest, "overload (clipped)")]
    assert "response 1 at or beyond 99.9 % of its full scale" in est.rejected[0]["detail"]


def test_no_false_rejection_on_unclipped_noisy_hits():
    # 300 realistic hits (amplitude and width scatter, noise from 0.1 % to 5 % of the peak, hits 1.2 to 3 s
    # apart: at least 9 decay times) on a three-mode structure: none may be rejected, for any reason
    plant = DigitalModes([40.0, 95.0, 310.0], [0.03, 0.02, 0.01], [[1.0, 0.5, 0.3], [0.6, -0.8, 0.2]], FS)
    reasons: collections.Counter = collections.Counter()
    for seed in range(50):
        rng = np.random.default_rng(seed)
        noise = float(rng.choice([0.001, 0.005, 0.01, 0.03, 0.05]))
        spacing = float(rng.uniform(1.2, 3.0))
        times = 0.3 + spacing * np.arange(6)
        synthetic = impact_record(plant, times, times[-1] + spacing, pulse_width_s=0.003, amplitude_variation=0.25,
                                  width_variation=0.2, force_noise=noise, response_noise=noise, seed=seed)
        hits = find_hits(synthetic.record.signals[0], synthetic.record.signals[1:], FS)
        reasons.update(r["reason"] for r in hits.rejected)
        assert hits.overloads == []
        # nor does a force window find a pulse it cuts in the noise after the hits
        cut = _force_windowed(hits, synthetic.record.signals[0])
        reasons.update(r["reason"] for r in cut.rejected)
    assert reasons == collections.Counter()


def _force_windowed(hits, force):
    """``hits`` after the check of what the estimate's force window cuts (as modal.estimate_frf windows)."""
    window = force_window(hits.record_length, int(hits.trigger_index[0] - hits.record_start[0]),
                          width=max(8, 3 * hits.pulse_samples))
    return reject_pulses_the_window_cuts(hits, force, window, FS, hit_labels(hits, None, [], FS))


@pytest.mark.parametrize("fraction, delay_s", [(0.02, 0.06), (0.04, 0.2), (0.02, 0.5)])
def test_a_pulse_below_the_trigger_that_the_force_window_cuts_makes_a_double_hit(fraction, delay_s):
    # a rebound of 2-4 % of hit 2, under the 5 % trigger: no hit of its own, so hit 2 was kept; the force window
    # took its force out of the record but not its response, and the estimate moved the 40 Hz mode's frequency
    # by 14 standard errors (2 %, 60 ms) and the damping ratios by 9-21 (4 %, 200 ms), unflagged. The
    # rebound's peak is 10-20 times the force noise (0.2 % of the peak): found, hit 2 rejected, saying why
    synthetic = impact_record(PLANT, [0.5, 2.5, 4.5, 6.5], 8.0, rebound_delay_s=[None, delay_s, None, None],
                              rebound_fraction=fraction, force_noise=0.002, response_noise=0.002, seed=2)
    est = _estimate(synthetic.record)
    assert [(r["hit"], r["reason"]) for r in est.rejected] == [(2, "double hit")]
    said = re.fullmatch(r"a pulse of ([0-9.]+) % of the hit's peak ([0-9]+) ms after it, below the trigger "
                        r"threshold: the force window cuts its force, the record keeps its response \(window "
                        r"'rect' keeps both\)", est.rejected[0]["detail"])
    # the largest sample of a half-sine 4 samples long holds at least cos(π/8) = 0.92 of its peak, and the noise
    # (0.2 % of the hit's peak) moves it by at most 0.2 % × 4 σ: the pulse's peak is told within that
    assert said and 0.92 * fraction - 0.008 <= float(said[1]) / 100 <= fraction + 0.008
    # its time to the sample, within the filter's run of two samples before the pulse's first
    assert abs(float(said[2]) / 1e3 - delay_s) <= 3 / FS + 1e-3
    truth = synthetic.frf(est.frequency_hz)
    band = (est.frequency_hz > 10) & (est.frequency_hz < 200)
    error = np.abs(est.response[:, band] - truth[:, band]) / est.noise_std[:, band]
    assert np.median(error) < 2  # Rayleigh: median √ln 2 ≈ 0.83 when only noise is left
    # a rectangular window keeps the rebound's force with its response: nothing to reject
    assert _estimate(synthetic.record, window="rect").rejected == []


def test_an_ac_coupled_quiet_force_channel_shows_no_cut_pulse():
    # an AC-coupled channel (a first-order high-pass at 1.6 Hz, τ = 0.1 s) recovers from each hit through a slow
    # undershoot of area/τ ≈ 1.3 % of the peak, over 100 times a 24-bit chain's noise (1e-4 of the peak), in the
    # first few hundred ms after the window: no pulse, as the force's local level (a straight line over 8 pulse
    # widths) takes it; taken from the force's median alone, it cut a pulse from every hit
    synthetic = impact_record(PLANT, [0.5, 2.5, 4.5, 6.5], 8.0, amplitude_variation=0.2, force_noise=1e-4,
                              response_noise=1e-4, seed=4)
    pole = np.exp(-1 / (0.1 * FS))
    coupled = synthetic.record.signals.copy()
    for ch in range(coupled.shape[0]):  # y[n] = (1 + p)/2 (x[n] − x[n−1]) + p y[n−1]
        for n in range(1, coupled.shape[1]):
            coupled[ch, n] = (1 + pole) / 2 * (synthetic.record.signals[ch, n] - synthetic.record.signals[ch, n - 1]) \
                + pole * coupled[ch, n - 1]
    hits = find_hits(coupled[0], coupled[1:], FS)
    assert hits.rejected == [] and _force_windowed(hits, coupled[0]).rejected == []


@pytest.mark.parametrize("force_noise", [0.0, 0.01, 0.03])
def test_a_hammer_force_is_a_pulse_train(force_noise):
    # six 2 ms pulses in 12 s fill 0.1 % of the record; with noise up to 3 % of the peak (far worse than a
    # hammer's sensor) the pulses still hold nearly all of the force's energy above its noise
    record = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, force_noise=force_noise, seed=4).record
    train = pulse_train(record.signals[0], FS)
    assert train.impulsive and train.count == 6 and train.duty < 0.002 and train.energy_share > 0.9


@pytest.mark.parametrize("burst_fraction", [None, 0.1, 0.5])
def test_a_shaker_force_is_no_pulse_train(burst_fraction):
    # Gaussian random: no sample above 8 robust standard deviations (probability 1e-15 per sample);
    # burst random: the bursts fill 10–50 % of the record, far above a hammer's duty
    rng = np.random.default_rng(5)
    force = rng.standard_normal(int(64 * FS))
    if burst_fraction is not None:
        force[np.arange(force.size) % 8192 >= burst_fraction * 8192] = 0.0
    assert not pulse_train(force, FS).impulsive
    assert not pulse_train(np.sin(2 * np.pi * 50.0 * np.arange(force.size) / FS), FS).impulsive


@pytest.mark.parametrize("offset", [-5.0, 5.0])
def test_a_shaker_force_with_an_offset_is_no_pulse_train(offset):
    # an amplifier's offset of 5 standard deviations put the Gaussian force's upper tail above 8 of them
    # counted from zero: 0.15 % of the samples became "hammer hits" holding all the energy above the noise
    force = offset + np.random.default_rng(5).standard_normal(int(64 * FS))
    train = pulse_train(force, FS)
    assert train.count == 0 and not train.impulsive


@pytest.mark.parametrize("offset_fraction", [0.02, 0.1])
def test_a_hammer_force_offset_finds_the_same_hits_and_the_same_frf(offset_fraction):
    # an offset of 10 % of the peak was above the trigger threshold (5 % of the peak): the whole record was one
    # "pulse", rejected as cut by the start of the data; at 2 % the hits were found, but the force window kept
    # the offset as a rectangular pulse its width: mode 1's constant 20 % low, no word. The offset is no force
    # the structure felt: the same hits and, the force centred on its median, the same FRF to rounding
    record = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, force_noise=0.002, response_noise=0.002,
                           seed=4).record
    shifted = record.signals.copy()
    shifted[0] += offset_fraction * np.max(np.abs(shifted[0]))
    clean, offset = _estimate(record), _estimate(dataclasses.replace(record, signals=shifted))
    assert offset.hit_times_s == clean.hit_times_s and offset.averages == clean.averages == 6
    np.testing.assert_allclose(offset.response, clean.response, rtol=1e-9, atol=1e-12 * np.abs(clean.response).max())


def test_a_response_offset_under_the_exponential_window_gives_the_same_frf():
    # an accelerometer's offset of 1 % of its peak, times exp(−t/τ), is a decaying pulse of its own: on the
    # shipped hammer record mode 1's mass read 1.148 ± 0.053 kg for 1.037 (5 %: every mode flagged, mode 1's
    # mass 1.95). The response's median, its offset in a record quiet but for the hits' ringing, is taken off
    record = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, force_noise=0.002, response_noise=0.002,
                           seed=4).record
    shifted = record.signals.copy()
    shifted[1:] += 0.01 * np.max(np.abs(shifted[1:]), axis=1, keepdims=True)
    def estimate(signals):
        return modal.estimate_frf(signals[0], signals[1:], FS, impact=True, window="exponential",
                                  exponential_decay_s=0.2, kind="accelerance", response_quantity="acceleration")

    clean, offset = estimate(record.signals), estimate(shifted)
    np.testing.assert_allclose(offset.response, clean.response, rtol=1e-9, atol=1e-12 * np.abs(clean.response).max())


def test_hits_estimated_as_a_continuous_record_are_named_and_a_continuous_force_refuses_impact():
    import warnings

    from modal.errors import ParameterError, QualityWarning
    from modal.synthetic import random_record

    hammer = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, force_noise=0.002, response_noise=0.002,
                           seed=6).record
    with pytest.warns(QualityWarning, match=r"hammer\.csv: force is 6 short pulse\(s\).*impact=True"):
        modal.estimate_frf(hammer.signals[0], hammer.signals[1:], FS, kind="accelerance",
                           response_quantity="acceleration", source="hammer.csv")
    shaker = random_record(PLANT, 32.0, response_noise=0.01, seed=7).record
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a shaker's record, estimated as one, raises no word
        modal.estimate_frf(shaker.signals[0], shaker.signals[1:], FS, kind="accelerance",
                           response_quantity="acceleration", source="shaker.csv")
    with pytest.raises(ParameterError, match=r"^shaker\.csv: impact record expected, but force has no hit.*"
                                             r"without impact\)$"):
        _estimate(shaker, source="shaker.csv")


def test_a_hit_just_before_the_end_does_not_shorten_every_record():
    # hits 2 s apart and a last one 0.1 s before the end of the data: the records keep the hits' spacing
    # (4096 samples) and the last hit, which the end cuts, is rejected as cut; a record sized by that
    # 0.1 s tail (128 samples, under a decay time of 0.13 s) would leave every response undecayed
    synthetic = impact_record(PLANT, [0.5, 2.5, 4.5, 6.5], 6.6, force_noise=0.002, response_noise=0.002, seed=8)
    hits = find_hits(synthetic.record.signals[0], synthetic.record.signals[1:], FS)
    assert hits.record_length == 4096
    assert [(r["hit"], r["reason"]) for r in hits.rejected] == [(4, "record cut by the start or end of the data")]


def test_hits_clipped_in_one_sample_each_are_rejected_by_their_equal_peaks():
    # 1 ms pulses (two samples at 2048/s) on a converter that saturates at 100 N: a clipped hit touches the rail in
    # one sample, with no flat top to show the rail. Fitted, such hits gave masses 25 % low with no word (the
    # rig's record clipped at 30 N of 50). Hits that were not clipped scatter by 20 % in amplitude; those on the
    # rail all peak at exactly 100 N: three or more such peaks are the rail
    synthetic = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, pulse_width_s=0.001, amplitude_variation=0.2,
                              full_scale=[100.0, None, None], declare_full_scale=False, force_noise=0.002,
                              response_noise=0.002, seed=1)
    force = synthetic.record.signals[0]
    on_rail = [force[int(t * FS):int(t * FS) + 8] == 100.0 for t in synthetic.hit_times_s]
    clipped = [k + 1 for k, rail in enumerate(on_rail) if rail.any()]
    assert 3 <= len(clipped) < 6  # the seed gives both kinds, with enough on the rail to show it
    assert not any(np.any(rail[1:] & rail[:-1]) for rail in on_rail)  # no flat top anywhere
    est = _estimate(synthetic.record)
    assert [r["hit"] for r in est.rejected] == clipped
    assert {r["reason"] for r in est.rejected} == {"overload (clipped)"}
    assert est.averages == 6 - len(clipped)
    # below the rail the same hits keep every hit: their peaks differ
    free = impact_record(PLANT, 0.5 + 2.0 * np.arange(6), 12.0, pulse_width_s=0.001, amplitude_variation=0.2,
                         force_noise=0.002, response_noise=0.002, seed=1)
    assert _estimate(free.record).rejected == []


def test_two_equal_peaks_are_not_yet_a_rail():
    from modal.estimate.overload import find_overloads

    x = np.zeros(100)
    x[[10, 40]] = 1.0  # two isolated samples at the maximum, of pulses of other heights: chance is not excluded
    x[[11, 41]] = 0.1, 0.3
    assert find_overloads(x, repeated_peaks=3) == []
    x[70], x[71] = 1.0, 0.2  # a third: a rail
    found = find_overloads(x, repeated_peaks=3)
    assert len(found) == 1 and found[0].mask.sum() == 3 and found[0].level == 1.0
    assert find_overloads(x) == []  # without repeated_peaks (a continuous record): only flat tops count
    x[[11, 41, 71]] = 0.2  # one pulse repeated exactly (a record without noise): equal flanks, no rail
    assert find_overloads(x, repeated_peaks=3) == []


def test_a_take_cut_short_while_it_rings_is_rejected_however_little_of_it_is_quiet():
    # one hit per 1 s take, 0.1 s after the start, ζ = 0.2 % at 40 Hz (decay time 2 s): the response is still at
    # a third of its peak when the record ends. Only the 0.1 s before the hit holds noise alone, less than the
    # quietest tenth of the take's blocks: the noise floor was read on the ringing (near the response's peak),
    # the hit passed as decayed and its leakage made the mass 1.50 ± 0.03 kg for 1 kg
    lightly = DigitalModes([40.0, 95.0], [0.002, 0.003], [[1.0, 0.5]], 1024.0)
    take = impact_record(lightly, [0.1], 1.0, seed=20, response_noise=1e-3, force_noise=1e-3).record
    hits = find_hits(take.signals[0], take.signals[1:], take.sample_rate_hz)
    assert [r["reason"] for r in hits.rejected] == ["response not decayed within the record"]
    with pytest.raises(modal.ParameterError, match="every hit was rejected.*an exponential window makes them decay"):
        _estimate(take)
    # the same hit with its ringing decayed within the record (ζ 3 %): the quiet blocks are its noise, kept
    damped = impact_record(PLANT, [0.1], 1.0, seed=20, response_noise=1e-3, force_noise=1e-3).record
    assert find_hits(damped.signals[0], damped.signals[1:], damped.sample_rate_hz).rejected == []


def test_a_cut_pulse_in_a_take_is_named_by_its_take():
    # two takes of 4 s joined: the rebound (3 %, 200 ms) follows the first hit of the second take
    synthetic = impact_record(PLANT, [0.5, 2.5, 4.5, 6.5], 8.0, rebound_delay_s=[None, None, 0.2, None],
                              rebound_fraction=0.03, force_noise=0.002, response_noise=0.002, seed=5)
    half = synthetic.record.n_samples // 2
    est = _estimate(synthetic.record, take_lengths=[half, half], take_names=["a.csv", "b.csv"])
    assert [(r["take_name"], r["take"], r["hit"], r["reason"]) for r in est.rejected] == [("b.csv", 2, 1, "double hit")]
    assert est.rejected[0]["time_s"] == pytest.approx(0.5, abs=2 / FS)
