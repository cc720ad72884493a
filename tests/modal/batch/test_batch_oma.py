"""modal batch --oma: folders of ambient records (responses only) through operational analysis, on a real
Dask cluster (the session fixture ``dask_cluster``), the command line in a subprocess."""
from __future__ import annotations

import csv
import json
import subprocess
import sys

import h5py
import numpy as np
import pytest

from support.ambient import FN, anchor_record
from support.cli import run_module
from support.paths import ROOT


def _write(path, rec):
    with h5py.File(path, "w") as fh:
        ds = fh.create_dataset("signals", data=rec.signals)
        ds.attrs["sample_rate_hz"] = rec.sample_rate_hz
        ds.attrs["quantities"] = ["acceleration"] * rec.signals.shape[0]
        ds.attrs["units"] = ["m/s^2"] * rec.signals.shape[0]


def _batch(*args):
    return subprocess.run([sys.executable, "-m", "modal", "batch", *map(str, args)], capture_output=True, text=True,
                          timeout=600, cwd=ROOT)


def _batch_here(*args):
    """``modal batch ARGS`` in this process (support.cli): a run after the first of its test, and usage errors."""
    return run_module("modal", "batch", *args, cwd=ROOT)


def test_a_folder_of_ambient_records(dask_cluster, tmp_path):
    folder = tmp_path / "ambient"
    folder.mkdir()
    for seed in (61, 62):
        _write(folder / f"run{seed}.h5", anchor_record(seed, noise=0.1, tones=True, duration_s=600))
    (folder / "bad.h5").write_bytes(b"not hdf5")
    out = tmp_path / "survey.h5"
    done = _batch(folder, "--oma", "--band", 1, 30, "--rotor-speed-hz", 4.8, "--out", out, "--scheduler",
                  dask_cluster[0], "--json")
    assert done.returncode == 1, done.stderr  # the bad file fails, the others are identified
    summary = json.loads(done.stdout)
    assert summary["fitted"] == 2 and len(summary["failed"]) == 1 and "bad.h5" in summary["failed"][0]["file"]
    with open(tmp_path / "survey.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh)]
    for seed in (61, 62):
        mine = [r for r in rows if r["file"].endswith(f"run{seed}.h5") and r["channel"] in ("0", "1")]
        found = sorted({float(r["natural_frequency_hz"]) for r in mine})
        assert len(found) == 6 and np.allclose(found, FN, rtol=5e-3)  # the six modes, no tone among them
        assert {r["method"] for r in mine} == {"ssi"}
        assert all(r["mass_kg"] == "" for r in mine)  # unscaled: no k, c, m (an empty cell)
    again = _batch_here(folder, "--oma", "--band", 1, 30, "--rotor-speed-hz", 4.8, "--out", out, "--scheduler",
                   dask_cluster[0], "--json")
    assert json.loads(again.stdout)["reused"] == 2  # same files, same options: nothing identified again
    other = _batch_here(folder, "--oma", "--band", 1, 25, "--out", out, "--scheduler", dask_cluster[0], "--json")
    assert json.loads(other.stdout)["fitted"] == 2  # other OMA options: a new settings hash


@pytest.mark.parametrize("args, message", [
    (["--oma", "--band", 1, 10, "--band", 12, 20], "--oma takes one --band"),
    (["--oma", "--method", "nls"], "--oma identifies from responses with ssi"),
    (["--rotor-speed-hz", 4.8], "apply to --oma"),
])
def test_bad_oma_options_exit_2(tmp_path, args, message):
    _write(tmp_path / "a.h5", anchor_record(63, noise=0.1, tones=False, duration_s=300))
    done = _batch_here(tmp_path, "--out", tmp_path / "r.h5", *args)
    assert done.returncode == 2 and message in done.stderr and "Traceback" not in done.stderr


def test_the_files_warnings_are_printed_on_every_run(dask_cluster, tmp_path):
    # a record with a dropout (15 s of zeros on every channel): modal oma warns of it; the batch printed nothing
    # of any file's warnings (they were in the archive only), so its table read as clean numbers
    folder = tmp_path / "ambient"
    folder.mkdir()
    rec = anchor_record(63, noise=0.1, tones=False, duration_s=300)
    rec.signals[:, 10_000:11_500] = 0.0
    _write(folder / "dropout.h5", rec)
    _write(folder / "clean.h5", anchor_record(64, noise=0.1, tones=False, duration_s=300))
    out = tmp_path / "survey.h5"
    for status in ("fitted", "reused"):  # the warnings come with the results, reused ones too
        done = (_batch if status == "fitted" else _batch_here)(folder, "--oma", "--band", 1, 30, "--out", out,
                                                                "--scheduler", dask_cluster[0], "--json")
        assert done.returncode == 0 and json.loads(done.stdout)[status] == 2, done.stderr
        lines = [line for line in done.stderr.splitlines() if line.startswith("warning: ")]
        dropout = [line for line in lines if "a dropout or a stuck converter" in line]
        assert len(dropout) == 1, done.stderr  # one, of dropout.h5: none of clean.h5
        assert dropout[0].startswith(f"warning: {folder / 'dropout.h5'}: every channel holds the value 0 for 1500 "
                                     "samples")
    # the same folder without --oma: each record refused, pointing to the batch's own option
    fit = _batch_here(folder, "--out", tmp_path / "fit.h5", "--scheduler", dask_cluster[0])
    failed = [line for line in fit.stderr.splitlines() if line.startswith("failed: ")]
    assert fit.returncode == 1 and len(failed) == 2
    assert all("responses only" in line and "modal batch --oma" in line for line in failed), fit.stderr
