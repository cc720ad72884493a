"""Lab mistakes in an ambient record: mixed units refused; dropouts, clipping and channels that move in no
mode warned of, naming the channel; none of it on the shipped real record or a clean synthetic one."""
from __future__ import annotations

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
from modal.operational.screen import MIN_STUCK_SAMPLES, screen_samples, stuck_runs
from support.ambient import anchor_record

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
    done = subprocess.run([sys.executable, "-m", "modal", "oma", str(path), "--band", "1", "30"], capture_output=True,
                          text=True, cwd=ROOT, timeout=300)
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


def test_hammer_force_among_the_responses_is_named(record):
    # a hammer's force channel of unknown unit left in the record: a train of short pulses, no mode in it
    n = record.signals.shape[1]
    force = np.zeros(n)
    force[::2000] = 50.0
    force += 0.01 * np.random.default_rng(2).standard_normal(n)
    _, texts = _oma(np.vstack([record.signals, force]), record.sample_rate_hz)
    found = _unresponsive(texts)
    assert len(found) == 1 and found[0].startswith("<array>: channel 9 moves in none of the 6 modes")
