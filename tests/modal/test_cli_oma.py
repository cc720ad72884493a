"""python -m modal oma: a table, JSON, the diagram and an archive from ambient time files; modal fit points
response-only records to it."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import h5py
import pytest
import numpy as np

import modal.cli
from support.ambient import FN, anchor_record
from support.cli import run_main

ROOT = Path(__file__).resolve().parents[2]
REAL = ROOT / "data" / "real" / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff"


def _write(path, rec, channels=None):
    channels = list(range(rec.signals.shape[0])) if channels is None else channels
    with h5py.File(path, "w") as fh:
        ds = fh.create_dataset("signals", data=rec.signals[channels])
        ds.attrs["sample_rate_hz"] = rec.sample_rate_hz
        ds.attrs["quantities"] = ["acceleration"] * len(channels)
        ds.attrs["units"] = ["m/s^2"] * len(channels)
    return path


def _run(*args):
    """``python -m modal ARGS`` in this process; the README's command below runs in a real subprocess."""
    return run_main(modal.cli.main, args, cwd=ROOT)


def test_json_table_plot_and_archive(tmp_path):
    path = _write(tmp_path / "ambient.h5", anchor_record(51, noise=0.1, tones=True))
    done = _run("oma", path, "--band", 1, 30, "--json", "--rotor-speed-hz", 4.8, "--plot", tmp_path / "d.png",
                "--archive", tmp_path / "r.h5")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    found = [m["natural_frequency_hz"] for m in doc["modes"]]
    assert len(found) == 6 and np.allclose(sorted(found), FN, rtol=5e-3)
    assert doc["warnings"] == [line.removeprefix("warning: ") for line in done.stderr.splitlines()
                               if line.startswith("warning: ")]
    assert np.allclose(sorted(doc["harmonics_hz"]), [4.8, 9.6, 14.4], atol=0.01)
    assert doc["modes"][0]["std"]["natural_frequency_hz"] > 0
    assert (tmp_path / "d.png").stat().st_size > 10_000
    from modal.archive import read_archive

    result = read_archive(tmp_path / "r.h5")["oma_ssi"]
    assert len(result) == 6 and result.harmonics_hz == tuple(doc["harmonics_hz"])
    table = _run("oma", path, "--band", 1, 30)
    assert table.returncode == 0 and "machine tones [Hz]: 4.8" in table.stdout


def test_setups_are_merged(tmp_path):
    one = _write(tmp_path / "s1.h5", anchor_record(52, noise=0.1, tones=False), [0, 5, 1, 2, 3])
    two = _write(tmp_path / "s2.h5", anchor_record(53, noise=0.1, tones=False), [0, 5, 4, 6, 7])
    done = _run("oma", one, two, "--band", 1, 30, "--reference-channels", 1, 2, "--json")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["n_channels"] == 8 and all(len(m["mode_shape"]) == 8 for m in doc["modes"])
    refused = _run("oma", one, two, "--band", 1, 30)
    assert refused.returncode == 1 and refused.stderr.startswith("error:") and "--reference-channels" in refused.stderr


def test_setups_with_a_mode_missing_from_one_print_json(tmp_path):
    # setup 2 holds the two lowest modes only: the merged shapes of the others are NaN there, which --json wrote
    # as {"re": NaN} and stopped on with a traceback (JSON has no NaN)
    from modal.synthetic import ambient_modal_response
    from support.ambient import FN, ZETA, anchor_shapes

    one = _write(tmp_path / "s1.h5", anchor_record(52, noise=0.1, tones=False), [0, 5, 1, 2, 3])
    two = _write(tmp_path / "s2.h5", ambient_modal_response(FN[:2], ZETA[:2], anchor_shapes()[[0, 5, 4, 6, 7], :2],
                                                            100.0, 100_000, seed=44))
    done = _run("oma", one, two, "--band", 1, 30, "--reference-channels", 1, 2, "--json")
    assert done.returncode == 0, done.stderr
    modes = json.loads(done.stdout)["modes"]
    missing = [m for m in modes if "missing_in_setup" in m["flags"]]
    assert missing and all(v["re"] is None for m in missing for v in m["mode_shape"][5:])
    # the warnings shown on stderr travel in the document too
    shown = [line.removeprefix("warning: ") for line in done.stderr.splitlines() if line.startswith("warning: ")]
    assert shown and json.loads(done.stdout)["warnings"] == shown


def test_bad_band_is_one_error_line(tmp_path):
    path = _write(tmp_path / "ambient.h5", anchor_record(54, noise=0.1, tones=False, duration_s=300))
    done = _run("oma", path, "--band", 10, 80)
    assert done.returncode == 1 and done.stderr.count("\n") == 1 and "FMAX <= 50 Hz" in done.stderr


def test_fit_on_a_response_only_record_points_to_oma():
    done = _run("fit", REAL)
    assert done.returncode == 1 and "python -m modal oma" in done.stderr and done.stderr.count("\n") == 1
    # an accelerometer named as the excitation: refused by the record's role check, not divided by
    done = _run("fit", REAL, "--excitation", 1)
    assert done.returncode == 1 and "named as the excitation but measured acceleration" in done.stderr


def test_readme_real_record_as_written(tmp_path):
    """The README's command on the shipped ambient record, run as written, prints the table the README shows."""
    import shlex

    text = (ROOT / "README.md").read_text()
    section = text.split("### The shipped ambient record", 1)[1].split("\n## ", 1)[0]
    command = section.split("```sh\n", 1)[1].split("```", 1)[0].strip()
    shown = section.split("```text\n", 1)[1].split("```", 1)[0].strip()
    words = shlex.split(command.replace("out/", f"{tmp_path.as_posix()}/"))
    assert words[0] == ".venv/bin/python"
    done = subprocess.run([sys.executable, *words[1:]], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert done.returncode == 0, done.stderr
    table = done.stdout.strip().splitlines()[1:]  # the first line names the file
    assert table == shown.splitlines()
    assert (tmp_path / "oma_real.png").stat().st_size > 10_000


def test_mass_change_scales_to_k_c_m(tmp_path):
    """--mass-change AFTER --added-mass-kg CH KG: the first record's modes mass-normalised, k, c, m at every
    channel (as modal.scale_by_mass_change gives them; its accuracy is tested in operational/test_scaling.py)."""
    from scipy.linalg import eigh

    from modal.synthetic import ambient_response, chain_matrices

    masses, springs, added = np.array([2.0, 1.5, 1.0, 1.2]), np.array([8e3, 6e3, 5e3, 4e3]), [0.2, 0.15, 0.1, 0.12]
    M, C, K = chain_matrices(masses, springs, 0.01)
    before = _write(tmp_path / "before.h5", ambient_response(M, C, K, 200.0, 300_000, noise=0.1, seed=1))
    after = _write(tmp_path / "after.h5", ambient_response(M + np.diag(added), C, K, 200.0, 300_000, noise=0.1,
                                                           seed=2))
    masses_args = [a for ch, kg in enumerate(added, start=1) for a in (ch, kg)]
    words = []
    for k in range(0, len(masses_args), 2):
        words += ["--added-mass-kg", *masses_args[k:k + 2]]
    done = _run("oma", before, "--band", 1, 60, "--mass-change", after, *words, "--json")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert len(doc["modes"]) == 4
    w2, phi = eigh(K, M)
    for k, mode in enumerate(doc["modes"]):
        m = np.array(mode["mass_kg"])
        # each channel a driving point of the mass-normalised shape: m_j = 1/psi_j^2 = 1/phi_j^2 (psi' M psi = 1);
        # within 20 %: the shape's 10 % (test_scaling) squared
        assert np.all(np.abs(m * phi[:, k] ** 2 - 1) < 0.2)
        assert np.allclose(mode["stiffness_n_per_m"], m * (2 * np.pi * mode["natural_frequency_hz"]) ** 2)
        assert all(s > 0 for s in mode["std"]["mass_kg"])
    table = _run("oma", before, "--band", 1, 60, "--mass-change", after, *words)
    assert table.returncode == 0 and "k [N/m]" in table.stdout
    # the two records in swapped order: every mode rose with the "added" mass; refused, not flagged numbers
    swapped = _run("oma", after, "--band", 1, 60, "--mass-change", before, *words)
    assert swapped.returncode == 1 and swapped.stdout == "" and swapped.stderr.count("\n") == 1
    assert "every mode rose from 'before'" in swapped.stderr and "are the records swapped?" in swapped.stderr


@pytest.mark.parametrize("args, message", [
    (["--added-mass-kg", "1", "0.2"], "--added-mass-kg needs --mass-change"),
    (["--mass-change", "{path}"], "no added mass given"),
    (["--mass-change", "{path}", "--added-mass-kg", "9", "0.2"], "added_mass_kg: .*no channel '9'"),
    (["--mass-change", "{path}", "--added-mass-kg", "1", "heavy"], "--added-mass-kg 1 heavy: expected a mass in kg"),
    (["--reference-channels", "X"], "reference_channels: .*no channel 'X'"),
])
def test_bad_mass_change_and_channels_are_one_error_line(tmp_path, args, message):
    import re

    path = _write(tmp_path / "ambient.h5", anchor_record(55, noise=0.1, tones=False, duration_s=300))
    done = _run("oma", path, "--band", 1, 30, *[a.format(path=path) for a in args])
    assert done.returncode == 1 and done.stderr.count("\n") == 1 and re.search(message, done.stderr), done.stderr


def test_a_band_that_holds_only_a_tone_says_so():
    """A result with machine tones and no structural mode (the shipped record's quick look over 5-400 Hz finds the
    182 Hz tone alone) is printed as one line saying so, not the table's header over no rows."""
    from modal.cli_oma import _table
    from modal.operational.result import oma_result

    tones_only = oma_result([], method="fdd", quantity="acceleration", band_hz=(5.0, 400.0), stabilisation=None,
                            settings={"band_hz": [5.0, 400.0], "n_channels": 4}, harmonics_hz=[181.58])
    assert _table(tones_only, "rec.uff").splitlines() == [
        "rec.uff: 4 channels, method fdd, band 5-400 Hz", "no structural mode in the band",
        "machine tones [Hz]: 181.5800"]
