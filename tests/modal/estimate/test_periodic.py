"""Periodic excitation whose period divides the records (periodic chirp, pseudo-random): no leakage is modelled
(modal.estimate.periodic), so the damping is not corrected for a bias the records do not hold."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy import signal

import modal
from modal.errors import QualityWarning
from modal.estimate.periodic import repeats_every, shortest_period
from modal.io.timedata import TimeRecord
from modal.io.timewrite import write_time
from support.paths import ROOT
from support.timedata import DigitalModes

FS = 1024.0
DAMPING = (0.02, 0.015)
PLANT = DigitalModes(np.array([40.0, 95.0]), np.array(DAMPING), np.array([[1.0, 0.5], [0.6, -0.8]]), FS)


def _chirp_record(period_samples: int = 2048, periods: int = 15, seed: int = 0):
    """Force: a linear chirp 5–200 Hz repeated every ``period_samples``; responses in steady state (the
    structure driven by the same periods for 5 s before the record), 2 % noise on each response."""
    rng = np.random.default_rng(seed)
    t = np.arange(period_samples) / FS
    one = 10.0 * signal.chirp(t, 5.0, period_samples / FS, 200.0)
    warm = int(np.ceil(5 * FS / period_samples))
    force = np.tile(one, warm + periods)
    response = PLANT.respond(force, "acceleration")[:, warm * period_samples:]
    response = response + 0.02 * response.std(axis=1, keepdims=True) * rng.standard_normal(response.shape)
    return force[warm * period_samples:], response


def test_repeats_every_tells_whole_periods_from_random_and_from_periods_that_do_not_fit():
    force, response = _chirp_record()
    channels = [force, *response]
    assert repeats_every(channels, 2048) and repeats_every(channels, 4096)  # one or two periods per record
    assert not repeats_every(channels, 3072)  # a record of 1.5 periods
    noise = np.random.default_rng(1).standard_normal(2**15)
    assert not repeats_every([noise], 2048)
    assert not repeats_every([force[:3000]], 2048)  # less than two records: nothing to compare


def test_a_periodic_chirp_in_rectangular_records_keeps_its_damping():
    # the records hold whole periods: the FRF is exact at its lines, and the random-excitation leakage model
    # (lag window 1 − τ/N, the decay cut at the record's end) took a bias out that was not there: damping
    # 1.689 ± 0.009 % and 1.378 ± 0.003 % for 2 % and 1.5 %
    force, response = _chirp_record()  # a period per record: 0.5 Hz lines, 3 in mode 1's half-power band
    estimate = modal.estimate_frf(force, response, FS, window="rect", segment_length=2048, overlap=0.0,
                                  kind="accelerance", response_quantity="acceleration",
                                  excitation_points=["1+Z"], response_points=["1+Z", "2+Z"])
    assert estimate.noise_model.lag_window is None
    result = modal.identify(estimate, "nls")
    assert len(result.modes) == 2
    for mode, truth in zip(result.modes, DAMPING):
        # within 4 of its own standard errors (the response noise is the only error left)
        assert abs(mode.damping_ratio - truth) < 4 * mode.std.damping_ratio, (mode.damping_ratio, truth)


def test_a_random_record_keeps_its_leakage_model():
    rng = np.random.default_rng(2)
    force = rng.standard_normal(2**15)
    response = PLANT.respond(force, "acceleration")
    estimate = modal.estimate_frf(force, response, FS, window="rect", segment_length=1024, kind="accelerance",
                                  response_quantity="acceleration")
    assert estimate.noise_model.lag_window is not None


def test_modal_fit_on_a_periodic_chirp_file(tmp_path):
    force, response = _chirp_record(periods=10)
    path = tmp_path / "chirp.csv"
    write_time(TimeRecord(np.vstack([force, response]), FS, ("1+Z", "1+Z", "2+Z"),
                          ("force", "acceleration", "acceleration"), ("N", "m/s^2", "m/s^2"), str(path)), path)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-m", "modal", "fit", str(path), "--window", "rect", "--segment-length",
                          "2048", "--overlap", "0", "--json"], capture_output=True, text=True, cwd=ROOT, env=env,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    found = {round(m["natural_frequency_hz"]): m for m in json.loads(out.stdout)["modes"] if m["driving_point"]}
    for frequency, truth in zip((40, 95), DAMPING):
        mode = found[frequency]
        assert abs(mode["damping_ratio"] - truth) < 4 * mode["std"]["damping_ratio"], mode
    assert pytest.approx(1.0, rel=0.01) == found[40]["mass_kg"]


def test_records_of_several_periods_are_warned_with_the_period(tmp_path):
    # a 1 s chirp in 2 s records: every other line held the force's noise alone, and `modal fit` printed four
    # modes (two invented beside 95 Hz), every one flagged, with no word of why
    force, response = _chirp_record(period_samples=1024, periods=20)
    force = force + 0.01 * force.std() * np.random.default_rng(3).standard_normal(force.size)
    with pytest.warns(QualityWarning, match=r"^<array>: the excitation repeats every 1024 samples \(1 s\), 2 times in "
                                            r"each 2048-sample record: one line in 2 holds it.*segment_length 1024"):
        modal.estimate_frf(force, response, FS, window="rect", segment_length=2048, overlap=0.0, kind="accelerance",
                           response_quantity="acceleration")
    assert shortest_period([force], 2048) == 1024 and shortest_period([force], 1024) == 1024
    assert shortest_period([np.random.default_rng(4).standard_normal(8192)], 2048) == 2048
