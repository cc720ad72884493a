"""Each file's fit in a fitting process beside the worker (modal/batch/fitproc.py) and the batch's
time limit per file (``--file-timeout``): a pathological file is listed as failed and the batch goes on."""
from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from modal.archive import read_archive
from modal.batch import fit_files
from modal.batch.fitproc import FitProcess, ProcessEnded, fit_in_process, shutdown
from modal.errors import ParameterError
from modal.fitting import FitOptions
from modal.io import write_frf

from support.batchfiles import FRF_MODES_HZ, mobility, write_hanging_hdf5, write_many_modes
from support.cli import run_module


def run_cli(*args):
    """``modal batch ARGS`` in this process (support.cli): the fits run in the cluster's fitting processes either
    way; test_batch.py and test_cluster.py run the command as a subprocess."""
    return run_module("modal", "batch", *args)


def session_members(sid: int) -> list[int]:
    """Processes of session ``sid`` (Linux /proc)."""
    members = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":  # fields after the name: state, ppid, pgrp, session
            members.append(int(stat.parent.name))
    return members


def test_a_pathological_file_times_out_and_the_batch_goes_on(dask_cluster, tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    write_many_modes(folder / "many_modes.h5")  # 150 modes on 60 000 lines: minutes of identification
    for k in range(3):
        write_frf(mobility(seed=k), folder / f"good{k}.uff")
    out = tmp_path / "r.h5"
    start = time.monotonic()
    done = run_cli(folder, "--out", out, "--scheduler", dask_cluster[0], "--file-timeout", 3, "--json")
    elapsed = time.monotonic() - start
    assert done.returncode == 1, done.stderr
    doc = json.loads(done.stdout)
    assert doc["fitted"] == 3
    assert doc["failed"] == [{"file": str(folder / "many_modes.h5"),
                              "error": f"{folder / 'many_modes.h5'}: timed out after 3 s"}]
    assert elapsed < 60  # the file alone identifies for minutes
    fits = {Path(f.source).name: f for f in read_archive(out)["files"]}
    slow = fits["many_modes.h5"]
    assert slow.retry and slow.fit_time_s == 3.0 and slow.results == ()  # a rerun tries it again
    for k in range(3):
        modes = sorted(m.natural_frequency_hz for m in fits[f"good{k}.uff"].results[0].modes)
        assert modes == pytest.approx(FRF_MODES_HZ, abs=0.05)  # standard errors ~1e-3 Hz


def test_a_timed_out_process_and_the_reader_it_forked_are_ended(tmp_path):
    """The hanging HDF5 reader runs in a child the fitting process forked; at the time limit the
    whole session goes: no process is left spinning in libhdf5."""
    write_hanging_hdf5(tmp_path / "hang.h5")
    proc = FitProcess()
    with pytest.raises(ProcessEnded, match="timed out after 2 s") as caught:
        proc.fit(str(tmp_path / "hang.h5"), FitOptions(), None, 2.0)
    assert caught.value.timed_out and not proc.alive()
    # SIGKILL to the session is delivered at once but a killed process ends only when next scheduled (seconds on
    # a loaded machine): the session must empty soon after, and stay empty
    deadline = time.monotonic() + 10
    while session_members(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert session_members(proc.pid) == []


def test_fitted_in_a_process_equals_fitted_here(tmp_path):
    from modal.batch.fitone import fit_one

    path = tmp_path / "a.uff"
    write_frf(mobility(), path)
    here = fit_one(str(path), FitOptions(method="nls"))
    try:
        there = fit_in_process(str(path), FitOptions(method="nls"), None, 60.0)
        again = fit_in_process(str(path), FitOptions(method="nls"), None, 60.0)  # the same process, kept
    finally:
        shutdown()
    assert there.ok and there.table == here.table == again.table and there.sha256 == here.sha256


def test_the_time_limit_must_be_a_positive_time(tmp_path):
    write_frf(mobility(), tmp_path / "a.uff")
    for bad in (0, -1, float("nan"), float("inf"), "soon", True):
        with pytest.raises(ParameterError, match="file timeout"):
            fit_files(tmp_path, file_timeout_s=bad)
    done = run_cli(tmp_path, "--out", tmp_path / "r.h5", "--file-timeout", -5)
    assert done.returncode == 2 and "--file-timeout -5: expected seconds > 0" in done.stderr


def test_a_file_needing_more_memory_than_its_budget_fails_alone(tmp_path):
    """The fitting process may grow by its budget (in a batch: the worker's memory limit) at most:
    a 48-channel 100 000-line FRF (77 MB of complex data, more than the budget on its own, whatever the
    BLAS's thread count adds) does not fit in 60 MB and fails with one line; the same process then fits a
    small file."""
    import numpy as np

    from modal.synthetic import add_noise, modal_frf

    freq = np.linspace(10.0, 5010.0, 100_000)
    big = add_noise(modal_frf(freq, [500.0, 2000.0], [0.01, 0.01], np.ones((48, 2)), kind="mobility"), 1e-3, seed=0)
    write_frf(big, tmp_path / "big.h5")
    write_frf(mobility(), tmp_path / "small.uff")
    proc = FitProcess(memory_budget_bytes=60e6)
    try:
        failed = proc.fit(str(tmp_path / "big.h5"), FitOptions(), None, 120.0)
        assert failed.retry and failed.error.startswith(f"{tmp_path / 'big.h5'}: out of memory (MemoryError: ")
        fitted = proc.fit(str(tmp_path / "small.uff"), FitOptions(), None, 120.0)
        assert fitted.ok and proc.alive()
    finally:
        proc.close()


def test_in_a_worker_the_budget_is_the_workers_memory_limit(dask_cluster):
    from distributed import Client

    from modal.batch.fitproc import worker_memory_limit

    assert worker_memory_limit() is None  # not in a worker: no budget
    with Client(dask_cluster[0], timeout="30s", set_as_default=False) as client:
        limits = {w["memory_limit"] for w in client.scheduler_info()["workers"].values()}
        assert client.submit(worker_memory_limit, pure=False).result() in limits and min(limits) > 0


@pytest.mark.slow  # a cluster and four files: 10-40 s with the load
def test_a_pathological_file_is_capped_and_flagged_while_the_batch_fits_every_file(dask_cluster, tmp_path):
    """The cap by design instead of the time limit: 40 modes at random on 4000 lines, 1 % noise (close pairs
    and weak modes the global method's significance tests and missing-mode search refit again and again: 626
    model evaluations, minutes on a loaded machine) under a budget of 30 evaluations ends in seconds, fitted,
    its modes flagged work_capped; the ordinary files (3-4 evaluations each) are not touched by it."""
    from support.manymodes import many_modes_frf

    folder = tmp_path / "in"
    folder.mkdir()
    write_frf(many_modes_frf(40, 4000, "random"), folder / "many_modes.h5", format="hdf5")
    for k in range(3):
        write_frf(mobility(seed=k), folder / f"good{k}.uff")
    out = tmp_path / "r.h5"
    done = run_cli(folder, "--out", out, "--scheduler", dask_cluster[0], "--max-evaluations", 30,
                   "--file-timeout", 240, "--json")
    assert done.returncode == 0, done.stderr
    doc = json.loads(done.stdout)
    assert doc["fitted"] == 4 and doc["failed"] == []
    fits = {Path(f.source).name: f for f in read_archive(out)["files"]}
    capped = fits["many_modes.h5"].results[0]
    assert capped.settings["max_evaluations"] == 30 and capped.settings["evaluations"] <= 30 + 1  # the start counts
    assert capped.modes and all("work_capped" in m.flags for m in capped.modes)
    for k in range(3):
        good = fits[f"good{k}.uff"].results[0]
        assert not any("work_capped" in m.flags for m in good.modes)
        modes = sorted(m.natural_frequency_hz for m in good.modes)
        assert modes == pytest.approx(FRF_MODES_HZ, abs=0.05)  # standard errors ~1e-3 Hz
