"""Lab mistakes in an ambient record: mixed units refused; dropouts, clipping and channels that move in no
mode warned of, naming the channel; none of it on the shipped real record or a clean synthetic one."""
from __future__ import annotations

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import modal
from modal.errors import ParameterError, QualityWarning
from modal.io.timedata import TimeRecord, read_time
from modal.io.timewrite import write_time
from modal.operational.inputs import prepare
from modal.operational.selection import shape_mac
from modal.operational.screen import (HELD_FRACTION, MIN_STUCK_SAMPLES, TRANSIENT_KURTOSIS, TRANSIENT_SIGMAS,
                                     held_factor, screen_samples, stuck_runs, transient_kurtosis)
from support.ambient import anchor_record
from support.cli import run_module

ROOT = Path(__file__).resolve().parents[3]
REAL = ROOT / "data" / "real" / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff"
BAND = (1.0, 30.0)
ACC = "acceleration"


@pytest.fixture(scope="module")
def record():
    """The anchor case (8 sensors, six modes), 300 s: enough for every mode's shape entries to stand
    well clear of their errors."""
    return anchor_record(7, noise=0.1, tones=False, duration_s=300)


def _oma(signals, rate, **kwargs):
    """modal.oma's result and the texts of the QualityWarnings it raised."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = modal.oma(signals, rate, band_hz=BAND, **kwargs)
    return result, [str(w.message) for w in caught if issubclass(w.category, QualityWarning)]


def _screen_warnings(signals, rate=100.0, names=()):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        screen_samples(signals, rate, names, "rec")
    return [str(w.message) for w in caught]


def _write(path, signals, units, quantities, rate=100.0):
    names = tuple(f"{k + 1}+Z" for k in range(signals.shape[0]))
    write_time(TimeRecord(signals, rate, names, tuple(quantities), tuple(units), source=str(path)), path)
    return path


# -- units -----------------------------------------------------------------------------------------------


def test_velocity_among_accelerations_is_refused(tmp_path, record):
    # the file says what each channel measured; a shape mixing m/s and m/s² entries is wrong by ω and 90°
    path = _write(tmp_path / "mixed.h5", record.signals, ["m/s^2"] * 4 + ["mm/s"] + ["m/s^2"] * 3,
                  [ACC] * 4 + ["velocity"] + [ACC] * 3)
    with pytest.raises(ParameterError, match=r"mixed\.h5: the channels are in different units \(1, 2, 3, 4, 6, 7, "
                                             r"8 in m/s\^2 \(acceleration\); 5 in m/s \(velocity\)\)"):
        modal.oma(path, band_hz=BAND)


def test_a_channel_in_volts_among_si_channels_is_refused_on_the_command_line(tmp_path, record):
    path = _write(tmp_path / "volts.h5", record.signals, ["m/s^2"] * 4 + ["V"] + ["m/s^2"] * 3,
                  [ACC] * 4 + [None] + [ACC] * 3)
    done = run_module("modal", "oma", path, "--band", 1, 30, cwd=ROOT)  # the hammer file's test runs the process
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.startswith("error: ") and done.stderr.count("\n") == 1
    assert "volts.h5: the channels are in different units" in done.stderr and "; 5 in V)" in done.stderr


def test_g_and_si_channels_are_converted_and_accepted(tmp_path, record):
    # a channel the file labels in g is converted to m/s² on reading: one unit, the shape as in SI throughout
    signals = record.signals.copy()
    signals[4] /= 9.80665
    mixed = _write(tmp_path / "g.h5", signals, ["m/s^2"] * 4 + ["g"] + ["m/s^2"] * 3, [ACC] * 8)
    si = _write(tmp_path / "si.h5", record.signals, ["m/s^2"] * 8, [ACC] * 8)
    a, _ = _oma(read_time(mixed), None)
    b, _ = _oma(read_time(si), None)
    assert len(a) == len(b) == 6
    for ma, mb in zip(a, b):  # the same numbers to rounding (g → m/s² is one multiplication)
        assert np.allclose(ma.mode_shape, mb.mode_shape, rtol=1e-6, atol=1e-9)


# -- dropouts and clipping -------------------------------------------------------------------------------


def test_stuck_runs_are_found_exactly():
    rng = np.random.default_rng(0)
    row = rng.standard_normal(20_000)
    row[1000:1000 + MIN_STUCK_SAMPLES] = 0.25  # just long enough
    row[5003:5003 + MIN_STUCK_SAMPLES - 1] = 0.5  # one short: not a dropout
    row[9001:12_345] = row[9000]  # held from sample 9000 on
    assert stuck_runs(row) == [(1000, MIN_STUCK_SAMPLES), (9000, 12_345 - 9000)]
    assert stuck_runs(rng.standard_normal(20_000)) == []


def test_dropout_on_every_channel_is_one_warning(record):
    signals = record.signals.copy()
    signals[:, 10_000:11_500] = 0.0  # 15 s of zeros: the recorder lost the signal
    texts = _screen_warnings(signals)
    assert len(texts) == 1
    assert "rec: every channel holds the value 0 for 1500 samples (15 s) from sample 10001 (5 % of the record)" \
        in texts[0] and "dropout" in texts[0]


def test_held_value_on_one_channel_is_warned_of_by_oma(record):
    signals = record.signals.copy()
    signals[5, 10_000:11_500] = signals[5, 9_999]  # a stuck converter repeats its last sample
    _, texts = _oma(signals, record.sample_rate_hz)
    held = [t for t in texts if "stuck converter" in t]
    assert len(held) == 1 and held[0].startswith("<array>: channel 6 holds the value") and "1501 samples" in held[0]


def test_clipped_channel_is_warned_of(record):
    signals = record.signals.copy()
    rail = 0.4 * np.abs(signals[2]).max()
    signals[2] = np.clip(signals[2], -rail, rail)
    texts = _screen_warnings(signals, names=[f"a{k}" for k in range(8)])
    assert len(texts) == 1 and texts[0].startswith(f"rec: channel 3 (a2) clipped at {rail:.6g} (flat tops")


def test_quantised_record_without_dropouts_is_not_warned_of(record):
    # a 16-bit converter whose range the signal spans to a quarter: codes repeat between neighbours, but
    # never for MIN_STUCK_SAMPLES samples, and no flat top stands at an extreme
    signals = record.signals
    code = 4 * np.abs(signals).max() / 2**16
    assert _screen_warnings(np.round(signals / code) * code) == []


def test_real_record_and_clean_synthetic_pass_the_screen(record):
    real = read_time(REAL)
    assert _screen_warnings(real.signals, real.sample_rate_hz, real.names) == []
    assert _screen_warnings(record.signals) == []


# -- channels that move in no mode -----------------------------------------------------------------------


def _unresponsive(texts):
    return [t for t in texts if "moves in none of the" in t]


def test_clean_record_has_no_unresponsive_channel(record):
    result, texts = _oma(record.signals, record.sample_rate_hz)
    assert len(result) == 6 and _unresponsive(texts) == []


def test_disconnected_sensor_is_named(record):
    # the sensor's cable is off: its channel holds the amplifier's noise alone, 1000 times below the others
    signals = record.signals.copy()
    signals[3] = 1e-3 * signals[3].std() * np.random.default_rng(1).standard_normal(signals.shape[1])
    result, texts = _oma(signals, record.sample_rate_hz)
    assert len(result) == 6
    found = _unresponsive(texts)
    assert len(found) == 1 and found[0].startswith("<array>: channel 4 moves in none of the 6 modes")


def test_loud_noise_channel_is_named_and_leaves_the_shapes_alone(record):
    # a broken cable picking up noise 1000 times the response's RMS: in its own units the channel's shape entry
    # (noise) is the largest; the shapes must be normalised to an entry the record determines, so that the
    # other channels keep their shapes and the noise channel alone is named (dividing by its entry made every
    # other channel read as unmoving and every mode complex)
    signals = record.signals.copy()
    signals[5] = 1e3 * signals[5].std() * np.random.default_rng(3).standard_normal(signals.shape[1])
    result, texts = _oma(signals, record.sample_rate_hz)
    assert len(result) == 6
    found = _unresponsive(texts)
    assert len(found) == 1 and found[0].startswith("<array>: channel 6 moves in none of the 6 modes")
    others = np.r_[0:5, 6:8]
    for k, mode in enumerate(result):
        assert "complex_shape" not in mode.flags
        # the other channels' shapes: the MAC criterion for modes found with confidence, against the truth, as
        # on a clean record
        if "high_uncertainty" not in mode.flags:
            assert shape_mac(mode.mode_shape[others], record.mode_shape[others, k]) >= 0.98
        assert abs(mode.mode_shape[5]) <= 3 * mode.std.mode_shape[5]


def test_shape_lead_is_a_determined_entry_or_the_largest_when_none_is():
    from modal.operational.modes import _physical_shape

    unit = np.array([0.5, 1.0, 0.2 + 0.1j])  # found on unit-RMS channels, its own lead (entry 1) exact
    scale = np.array([1.0, 2.0, 1000.0])  # the third channel 1000 times louder
    deviations = np.zeros((5, 3), complex)
    deviations[:, 2] = 0.5  # the third entry undetermined (0.22 against errors of 1.1)
    shape, std = _physical_shape(unit, deviations, scale)
    assert shape[1] == 1 and abs(shape[2]) > 1 and std[2] > abs(shape[2]) / 3
    # no errors at all (NaN deviations): the largest entry, as without error bars
    shape, std = _physical_shape(unit, np.full((5, 3), np.nan), scale)
    assert shape[2] == 1 and np.all(np.isnan(std))


def test_hammer_force_among_the_responses_is_named(record):
    # a hammer's force channel of unknown unit left in the record: a train of short pulses, no mode in it
    n = record.signals.shape[1]
    force = np.zeros(n)
    force[::2000] = 50.0
    force += 0.01 * np.random.default_rng(2).standard_normal(n)
    _, texts = _oma(np.vstack([record.signals, force]), record.sample_rate_hz)
    found = _unresponsive(texts)
    assert len(found) == 1 and found[0].startswith("<array>: channel 9 moves in none of the 6 modes")


# -- records of transients (a hammer test's responses) ---------------------------------------------------


def _hammer_responses(hit_every_s: float, duration_s: float = 60.0):
    """A hammer test of the anchor structure (responses only, 100 Hz): hits every ``hit_every_s``, each mode
    ringing down over seconds, as a roving-hammer file's accelerometers are."""
    from modal.synthetic_time import DigitalModes, impact_record
    from support.ambient import FN, ZETA, anchor_shapes

    shapes = anchor_shapes()
    system = DigitalModes(FN, ZETA, shapes * shapes[0][None, :], 100.0)
    hits = list(np.arange(1.0, duration_s - 1.0, hit_every_s))
    made = impact_record(system, hits, duration_s, pulse_width_s=0.03, amplitude_variation=0.2,
                         response_noise=0.01, seed=1)
    return made.record.signals[1:]


def test_hammer_responses_given_to_oma_are_flagged_non_stationary():
    # the responses of a hammer test, hits every 8 s: SSI finds the modes, but the frequency errors it reports
    # are 8-13 times too small (7.3953 ± 0.0004 Hz for 7.4) because nothing in the record is stationary
    signals = _hammer_responses(8.0)
    result, texts = _oma(signals, 100.0)
    assert len(result) >= 5
    assert all("non_stationary" in mode.flags for mode in result)
    record_level = [t for t in texts if t.startswith("<array>: the record is not stationary random response")]
    assert len(record_level) == 1
    assert "kurtosis" in record_level[0] and "modal fit --impact" in record_level[0]
    # the quick look's peaks carry it too
    quick, _ = _oma(signals, 100.0, method="efdd")
    assert len(quick) and all("non_stationary" in mode.flags for mode in quick)


def test_frequent_hits_are_flagged_as_well():
    # hits every 2 s: the decays overlap, the kurtosis is only about 7, still far beyond a Gaussian record's spread;
    # SSI printed mode 1 at 3.011 ± 0.003 Hz for 3.1 Hz
    kurtosis, std, _ = transient_kurtosis(prepare(_hammer_responses(2.0), 100.0, BAND, screen=False))
    assert kurtosis > TRANSIENT_KURTOSIS and kurtosis - 3 > TRANSIENT_SIGMAS * std


def test_kurtosis_error_of_gaussian_records_is_calibrated():
    # stationary Gaussian response, one lightly damped mode dominating a short record (few independent samples):
    # the kurtosis's deviation from 3 in its own standard errors has SD near 1 (the first-order formula is a
    # little conservative: 0.72 over 150 records), far from TRANSIENT_SIGMAS in every record
    from modal.synthetic import ambient_modal_response

    z = []
    for seed in range(40):
        rec = ambient_modal_response([5.0], [0.005], [[1.0], [0.7]], 100.0, 6000, noise=0.05, seed=seed)
        kurtosis, std, _ = transient_kurtosis(prepare(rec.signals, 100.0, screen=False))
        z.append((kurtosis - 3) / std)
    z = np.array(z)
    # 40 draws: a sample SD within about ±25 % of its value, around 0.72
    assert 0.45 < z.std() < 1.15 and abs(z.mean()) < 0.5
    assert np.abs(z).max() < TRANSIENT_SIGMAS / 2


def test_real_and_clean_records_are_not_flagged_non_stationary(record):
    real = read_time(REAL)
    for prepared in (prepare(real, screen=False), prepare(record.signals, 100.0, BAND, screen=False)):
        kurtosis, std, _ = transient_kurtosis(prepared)
        assert abs(kurtosis - 3) < 3 * std  # Gaussian within its spread (real: 3.17 ± 0.16)


def test_hammer_file_given_to_modal_oma_says_so_on_the_command_line(tmp_path):
    path = _write(tmp_path / "hammer_responses.h5", _hammer_responses(8.0), ["m/s^2"] * 8, [ACC] * 8)
    done = subprocess.run([sys.executable, "-m", "modal", "oma", str(path), "--band", "1", "30", "--json"],
                          capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    flags = [mode["flags"] for mode in doc["modes"]]
    assert flags and all("non_stationary" in f for f in flags)
    assert "hammer_responses.h5: the record is not stationary random response" in done.stderr


# -- samples held: a record written at a multiple of the rate it was sampled at ----------------------------


def test_held_samples_above_their_nyquist_frequency_are_refused():
    # a 50 Hz record written at 100 Hz by holding each sample twice: over the default band (to 40 Hz) SSI reported
    # unflagged 'modes' at 38.58 Hz (0.36 %) and 38.81 Hz, images of the 11.41 and 11.2 Hz modes about 25 Hz
    slow = anchor_record(7, noise=0.1, tones=False, duration_s=300, sample_rate_hz=50.0)
    held = np.repeat(slow.signals, 2, axis=1)
    with pytest.raises(ParameterError, match=r"<array>: every channel repeats each sample 2 times: sampled at 50 Hz "
                                             r"and written at 100 Hz, so above 25 Hz .* expected a band up to 25 Hz"):
        prepare(held, 100.0)
    # over a band below its real Nyquist frequency the record is what it is
    assert prepare(held, 100.0, (1.0, 24.0)).band_hz == (1.0, 24.0)
    # one channel held among channels sampled at the record's rate is named
    mixed = anchor_record(8, noise=0.1, tones=False, duration_s=300).signals.copy()
    mixed[2] = held[2]
    with pytest.raises(ParameterError, match=r"<array>: channel 3 repeats each sample 2 times"):
        prepare(mixed, 100.0, (1.0, 30.0))


def test_real_and_quantised_records_are_not_held(record):
    real = read_time(REAL)
    assert [held_factor(row) for row in real.signals] == [1] * 4
    # quantised to a few codes: many neighbours repeat, in runs of every length
    code = 2 * record.signals.std()  # three codes or so: 59 % of neighbours repeat
    coarse = np.round(record.signals / code) * code
    assert np.mean(coarse[0, 1:] == coarse[0, :-1]) > HELD_FRACTION
    assert [held_factor(row) for row in coarse] == [1] * 8
