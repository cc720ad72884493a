"""Noise on a shaker test's force channel: H1 reads the FRF low whatever the averages, and says so
(modal.estimate.excitation_noise, warned by estimate_frf and `modal fit` on a time file)."""
from __future__ import annotations

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import modal
from modal.errors import QualityWarning
from modal.estimate.excitation_noise import EXCITATION_NOISE_LIMIT
from modal.io.timewrite import write_time
from modal.synthetic_time import random_record
from support.paths import ROOT
from support.timedata import DigitalModes

FS = 1024.0
PLANT = DigitalModes(np.array([40.0, 95.0]), np.array([0.02, 0.015]), np.array([[1.0, 0.5], [0.6, -0.8]]), FS)


def _record(force_noise: float, seed: int = 0, duration_s: float = 60.0):
    """A shaker record whose force channel holds white noise of ``force_noise`` times the force's RMS that
    the structure never felt (the structure is driven by the clean force): the share of the measured force's
    power that the responses do not follow is q = f² / (1 + f²)."""
    return random_record(PLANT, duration_s, force_rms_n=10.0, force_noise=force_noise, response_noise=0.02,
                         names=["1+Z", "1+Z", "2+Z"], seed=seed).record


def _estimate(record, **options):
    return modal.estimate_frf(record.signals[0], record.signals[1:], FS, kind="accelerance", **options)


def test_force_noise_is_warned_and_h1_is_low_by_the_share_it_names():
    record = _record(force_noise=1.0)  # q = 0.5: H1 half the FRF
    with pytest.warns(QualityWarning, match=r"do not follow about (4[5-9]|5[0-5]) % of its power.*--estimator H2"):
        estimate = _estimate(record)
    # what the warning is about: H1 is half the true FRF on every line; the median ratio over the 10–200 Hz
    # lines averages out each line's random error (≈ 0.13 relative: γ² = 0.5, 29 Hann averages)
    band = (estimate.frequency_hz > 10) & (estimate.frequency_hz < 200)
    truth = PLANT.frf(estimate.frequency_hz[band], "accelerance")[0]
    assert np.median(np.abs(estimate.response[0, band]) / np.abs(truth)) == pytest.approx(0.5, abs=0.03)


def test_h2_on_the_same_record_is_not_warned():
    # H2 divides by the cross-spectrum, which the force's noise does not enter: not biased by it, and not warned
    # (a warning would raise here). The median ratio over the 10–200 Hz lines holds to the same 0.03 as H1's above
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        estimate = _estimate(_record(force_noise=1.0), estimator="H2")
    band = (estimate.frequency_hz > 10) & (estimate.frequency_hz < 200)
    truth = PLANT.frf(estimate.frequency_hz[band], "accelerance")[0]
    assert np.median(np.abs(estimate.response[0, band]) / np.abs(truth)) == pytest.approx(1.0, abs=0.03)


@pytest.mark.parametrize("force_noise", [0.0, 0.05])
def test_a_clean_force_is_not_warned(force_noise):
    # q = 0 and 0.0025, far below the limit (the estimate's floor on clean records is ≈ 0.001–0.014)
    assert EXCITATION_NOISE_LIMIT == 0.1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _estimate(_record(force_noise))


def test_the_share_is_measured_not_assumed():
    from modal.estimate import spectra
    from modal.estimate.excitation_noise import excitation_noise_share
    from modal.estimate.windows import segment_window

    record = _record(force_noise=0.5)  # q = 0.25 / 1.25 = 0.2
    length = 4096
    window = segment_window("hann", length)
    starts = np.arange(0, record.n_samples - length + 1, length // 2)
    sums = spectra.accumulate(record.signals[:1], record.signals[1:], starts, length, window, window)
    share = excitation_noise_share(sums.sxx[0, 0].real, sums.syx[:, 0], sums.syy, sums.n_records)
    # the median over ~2000 lines of 1 − γ̂² (29 averages) scatters by well under 0.01; the responses' own 2 %
    # noise adds ~0.004 at the median line
    assert share == pytest.approx(0.2, abs=0.02)
    assert excitation_noise_share(sums.sxx[0, 0].real, sums.syx[:, 0], sums.syy, 2) is None  # cannot split


def test_modal_fit_on_a_time_file_warns_naming_the_file(tmp_path):
    path = tmp_path / "shaker_body.csv"
    write_time(_record(force_noise=1.0, duration_s=30.0), path)
    env = {**os.environ, "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-m", "modal", "frf", str(path), "--out", str(tmp_path / "frf.h5"), "--json"],
                         capture_output=True,
                         text=True, cwd=ROOT, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    assert f"warning: {path.name}" in out.stderr or f"warning: {path}" in out.stderr
    assert "the responses do not follow about" in out.stderr and "--estimator H2" in out.stderr
    assert "the responses do not follow about" in out.stdout  # --json keeps it with the estimate
