"""Stress run: the operational method's standard errors hold over many records (OMA_SEEDS, default 50).

For the anchor case (six modes, eight sensors, a close pair 1.9 % apart, a weakly excited mode, machine
tones at 1×/2×/3×, 10 % noise), over independent records: z = (estimate − truth) / reported standard
error, per mode, for frequency and damping ratio. For calibrated errors the SD of N standard normals
has standard error 1/√(2N) (0.10 at N = 50); the issue's bound 1 ± 25 % is 2.5 of those (with fewer
records, for a quick run, the bound widens to 2.5 of them). The mean's standard error is 1/√N (0.14);
|mean| ≤ 0.6 is 4.2 of those (likewise). Every record: every mode once, no other
mode, the three tones listed apart, every shape close to the truth; for SSI (the default) and pLSCF (the
cross-check). About 4 minutes on two cores (~2 s per record and method).
"""
from __future__ import annotations

import functools
import os
import warnings

import numpy as np
import pytest

import modal
from modal.operational.selection import shape_mac
from support.ambient import FN, TONES, ZETA, anchor_record

SEEDS = int(os.environ.get("OMA_SEEDS", "50"))


@functools.lru_cache(maxsize=None)
def _trials(method: str):
    zf, zz, wrong, macs = [], [], [], []
    for seed in range(SEEDS):
        rec = anchor_record(5000 + seed, noise=0.1, tones=True)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0), method=method)
        f = np.array([m.natural_frequency_hz for m in result])
        row_f, row_z, row_mac = [], [], []
        for k, fn in enumerate(FN):
            near = np.flatnonzero(np.abs(f / fn - 1) < 0.005)
            if near.size != 1:
                wrong.append((seed, fn, f.tolist()))
                row_f.append(np.nan), row_z.append(np.nan), row_mac.append(np.nan)
                continue
            mode = result[int(near[0])]
            row_f.append((mode.natural_frequency_hz - fn) / mode.std.natural_frequency_hz)
            row_z.append((mode.damping_ratio - ZETA[k]) / mode.std.damping_ratio)
            row_mac.append(shape_mac(mode.mode_shape, rec.mode_shape[:, k]))
        if len(result) != len(FN) or len(result.harmonics_hz) != 3 \
                or not np.allclose(sorted(result.harmonics_hz), TONES, atol=0.01):
            wrong.append((seed, "modes/tones", f.tolist(), result.harmonics_hz))
        zf.append(row_f), zz.append(row_z), macs.append(row_mac)
    return np.array(zf), np.array(zz), wrong, np.array(macs)


@pytest.mark.stress
@pytest.mark.parametrize("method", ["ssi", "plscf"])
def test_every_mode_once_and_no_tone_as_a_mode(method):
    _, _, wrong, _ = _trials(method)
    assert not wrong


@pytest.mark.stress
@pytest.mark.parametrize("method", ["ssi", "plscf"])
@pytest.mark.parametrize("quantity", ["frequency", "damping"])
def test_standard_errors_are_calibrated(method, quantity):
    zf, zz, _, _ = _trials(method)
    z = zf if quantity == "frequency" else zz
    sd, mean = np.nanstd(z, axis=0), np.nanmean(z, axis=0)
    assert np.all(np.abs(sd - 1) <= max(0.25, 2.5 / np.sqrt(2 * SEEDS))), sd
    assert np.all(np.abs(mean) <= max(0.6, 4.2 / np.sqrt(SEEDS))), mean


@pytest.mark.stress
@pytest.mark.parametrize("method, least_mac", [("ssi", 0.98), ("plscf", 0.95)])
def test_shapes_match_the_truth(method, least_mac):
    # the MAC >= 0.98 for the default method; the cross-check's weakly excited mode (excited 10 times
    # less, its entries' errors a few hundredths) came out at 0.978 on 1 record of 50 (seeds 5000-5049), while
    # a shape taken from another mode (as its residue fit over the whole band did, on 4 records of 20) has MAC
    # below 0.1 to its own
    _, _, _, macs = _trials(method)
    assert np.nanmin(macs) >= least_mac, np.nanmin(macs, axis=0)
