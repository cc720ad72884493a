"""Every format ``modal fit`` reads, fitted by ``modal batch`` on a real scheduler whose two workers
run as ``dask worker`` deploys them (each a daemonic child process of its nanny) and on the embedded
cluster (whose workers are daemonic too); and the readers' protection against hostile files kept
there: a file that crashes or hangs its reader fails alone, the worker lives on, the other files
are fitted."""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

from modal.archive import read_archive
from modal.batch import file_sha256

from support.batchfiles import FRF_MODES_HZ, write_crashing_mat, write_every_format, write_hanging_hdf5, mobility
from support.cli import run_module
from support.daskcluster import quiet_environment


def run_cli(*args):
    """``python -m modal batch ARGS``: a process of its own, whose stderr holds whatever Dask logs; an embedded
    cluster it starts has the session cluster's quiet settings (support.daskcluster.QUIET): the formats are the
    subject here (tests/modal/batch/test_cluster.py runs the embedded cluster as configured by default)."""
    return subprocess.run([sys.executable, "-m", "modal", "batch", *map(str, args)], capture_output=True, text=True,
                          timeout=300, env=quiet_environment())


def frequencies_by_file(table: Path) -> dict[str, list[tuple[float, float]]]:
    found = defaultdict(list)
    with open(table, newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            found[row["file"]].append((float(row["natural_frequency_hz"]), float(row["std_natural_frequency_hz"])))
    return found


@pytest.fixture(scope="module")
def every(tmp_path_factory):
    folder = tmp_path_factory.mktemp("formats") / "every"
    return folder, write_every_format(folder)


@pytest.mark.parametrize("where", ["scheduler", "embedded"])
def test_every_format_is_fitted_on_a_cluster_with_daemonic_workers(every, where, dask_cluster, tmp_path):
    folder, truth = every
    out = tmp_path / "r.h5"
    cluster = ["--scheduler", dask_cluster[0]] if where == "scheduler" else ["--workers", 2]
    done = run_cli(folder, "--out", out, *cluster, "--kind", "mobility", "--json")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert (doc["files"], doc["fitted"], doc["failed"]) == (len(truth), len(truth), [])
    assert "Traceback" not in done.stderr
    found = frequencies_by_file(tmp_path / "r.csv")
    assert set(found) == set(truth)
    for path, modes_hz in truth.items():
        # every file's modes where the file put them: within 5 of their standard errors (a file read
        # wrongly, or another file's result, is off by hertz; the FRF files' errors are ~1e-3 Hz,
        # the time files' (an estimate from 32 s of random excitation, its errors the records' leakage)
        # 0.03 Hz at 40 Hz and 0.10 Hz at 95 Hz (ζ 2 %): below 0.15 Hz, 5 of them stay below 0.75 Hz,
        # under the hertz a misread file is off by)
        assert len(found[path]) == len(modes_hz), path
        for (value, sigma), expected in zip(sorted(found[path]), modes_hz):
            assert 0 < sigma < 0.15 and abs(value - expected) < 5 * sigma, (path, value, sigma, expected)
    fits = read_archive(out)["files"]
    assert all(fit.ok and fit.sha256 == file_sha256(fit.source) for fit in fits)


def test_a_file_that_crashes_or_hangs_its_reader_fails_alone_and_the_workers_live_on(dask_cluster, tmp_path):
    from distributed import Client

    from modal.io import write_frf

    folder = tmp_path / "in"
    folder.mkdir()
    write_crashing_mat(folder / "crash.mat")
    write_hanging_hdf5(folder / "hang.h5")
    for k in range(4):
        write_frf(mobility(seed=k), folder / f"good{k}.uff")
    with Client(dask_cluster[0], timeout="30s", set_as_default=False) as client:
        before = set(client.scheduler_info()["workers"])  # addresses: a restarted worker gets a new one
    # a 4 s limit ends the hang (the reader's own limit, 20 s, would too, later); the good files take ~0.05 s
    # in this process (support.cli): the readers crash and hang in the workers' fitting processes, not here
    done = run_module("modal", "batch", folder, "--out", tmp_path / "r.h5", "--scheduler", dask_cluster[0],
                      "--file-timeout", 4, "--json")
    assert done.returncode == 1, done.stderr
    doc = json.loads(done.stdout)
    assert doc["fitted"] == 4
    errors = {Path(item["file"]).name: item["error"] for item in doc["failed"]}
    assert set(errors) == {"crash.mat", "hang.h5"}
    assert "crash.mat: damaged MATLAB" in errors["crash.mat"] and "crashed" in errors["crash.mat"]
    assert errors["hang.h5"].endswith("hang.h5: timed out after 4 s")
    found = frequencies_by_file(tmp_path / "r.csv")
    for k in range(4):
        values = sorted(found[str(folder / f"good{k}.uff")])
        assert all(abs(v - e) < 5 * s for (v, s), e in zip(values, FRF_MODES_HZ))
    with Client(dask_cluster[0], timeout="30s", set_as_default=False) as client:
        after = set(client.scheduler_info()["workers"])
    assert after == before and len(after) == 2  # the same two workers: none died or was restarted by its nanny
