"""One run per output: a second ``modal batch`` on a running one's output refuses at once naming it, a
killed run's lock is taken over, and results are reused by their content, never by their position."""
from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from modal.archive import read_archive
from modal.batch import file_sha256, fit_files, iter_fit
from modal.batch.lock import OutputInUseError, RunLock, lock_path
from modal.errors import ArchiveError, ModalWarning
from modal.io import write_frf

from support.batchfiles import mobility


def modes_of(index: int) -> tuple[float, float]:
    """File ``index``'s two natural frequencies, Hz: each file its own, 3 Hz apart from the next."""
    return 50.0 + 3.0 * index, 150.0 + 3.0 * index


def write_files(folder: Path, indices) -> dict[str, tuple[float, float]]:
    folder.mkdir(parents=True, exist_ok=True)
    truth = {}
    for index in indices:
        path = folder / f"f{index:03d}.uff"
        write_frf(mobility(modes_of(index), seed=index), path)
        truth[str(path)] = modes_of(index)
    return truth


def assert_archive_true(out: Path, truth: dict[str, tuple[float, float]]) -> None:
    """Every group: its source's content (sha256 of the file now) and that file's modes (within
    0.05 Hz; the standard errors are ~1e-3 Hz, neighbouring files' modes 3 Hz away)."""
    fits = read_archive(out)["files"]
    assert sorted(f.source for f in fits) == sorted(truth)
    for fit in fits:
        assert fit.ok and fit.sha256 == file_sha256(fit.source), fit.source
        found = sorted(m.natural_frequency_hz for m in fit.results[0].modes)
        assert found == pytest.approx(truth[fit.source], abs=0.05), fit.source


def test_a_second_run_refuses_at_once_naming_the_first_which_finishes_unharmed(dask_cluster, tmp_path):
    """The first run is this process's, held after its first file (the generator waits for its next ``next``:
    the rest in flight or to come); the second is ``modal batch`` in a process of its own."""
    truth = write_files(tmp_path / "in", range(12))
    out = tmp_path / "r.h5"
    first = iter_fit(tmp_path / "in", out=out, client=dask_cluster[0])
    try:
        assert next(first).status == "fitted"
        second = subprocess.run([sys.executable, "-m", "modal", "batch", tmp_path / "in", "--out", out,
                                 "--workers", "1"], capture_output=True, text=True, timeout=120)
        # the first run is still held: the second finished without waiting for it
        assert second.returncode == 1
        holder = json.loads(lock_path(out).read_text())
        assert holder["pid"] == os.getpid() and holder["host"] == socket.gethostname()
        assert second.stderr == (f"error: {out}: another modal batch run is writing it (pid {os.getpid()} on "
                                 f"{socket.gethostname()}, started {holder['started']}: {holder['command']}); "
                                 f"wait for it to finish or choose another --out (lock {lock_path(out)})\n")
        assert not out.exists() and not (tmp_path / "r.csv").exists()  # nothing written by the second
        rest = list(first)  # the first run goes on to its end
    finally:
        first.close()
    assert len(rest) == 11 and all(o.status == "fitted" for o in rest)
    assert_archive_true(out, truth)
    assert not lock_path(out).exists() and not (tmp_path / "r.h5.parts").exists()


def test_reuse_is_by_content_when_the_archive_is_replaced_during_the_run(dask_cluster, tmp_path):
    """Another run replaces the archive between this run's index and its final copy: the results
    are found by content in the new file (which holds the same contents at other positions)."""
    truth = write_files(tmp_path / "in", range(6))
    out = tmp_path / "r.h5"
    fit_files(tmp_path / "in", client=dask_cluster[0], out=out)
    mirror = tmp_path / "mirror"  # the same contents under names in the reverse order
    mirror.mkdir()
    for k, path in enumerate(sorted(truth)[::-1]):
        shutil.copy(path, mirror / f"g{k:03d}.uff")
    fit_files(mirror, client=dask_cluster[0], out=tmp_path / "mirror.h5")

    run = iter_fit(tmp_path / "in", out=out, client=dask_cluster[0])
    first = next(run)  # indexed: every file reused from out's groups 0..5
    assert first.status == "reused"
    os.replace(tmp_path / "mirror.h5", out)  # meanwhile, the archive is replaced
    rest = list(run)
    assert [o.status for o in rest] == ["reused"] * 5
    assert_archive_true(out, truth)
    table = (tmp_path / "r.csv").read_text().splitlines()[1:]
    for row in table:  # the table's numbers are each file's own, too
        path, _, mode, _, value = row.split(",")[:5]
        assert float(value) == pytest.approx(truth[path][int(mode) - 1], abs=0.05)


def test_an_archive_replaced_by_one_without_the_results_is_an_error_and_keeps_nothing_half(dask_cluster,
                                                                                          tmp_path):
    write_files(tmp_path / "in", range(3))
    write_files(tmp_path / "other", range(10, 13))
    out = tmp_path / "r.h5"
    fit_files(tmp_path / "in", client=dask_cluster[0], out=out)
    fit_files(tmp_path / "other", client=dask_cluster[0], out=tmp_path / "other.h5")
    run = iter_fit(tmp_path / "in", out=out, client=dask_cluster[0])
    next(run)
    os.replace(tmp_path / "other.h5", out)
    replaced = out.read_bytes()
    with pytest.raises(ArchiveError, match=r"no longer holds the result of .*f000\.uff .*replaced during the run"):
        list(run)
    assert out.read_bytes() == replaced and not lock_path(out).exists()


def test_a_lock_left_by_a_killed_run_is_taken_over(dask_cluster, tmp_path):
    out = tmp_path / "r.h5"
    script = f"""
import os, signal
from modal.batch.lock import RunLock
RunLock({str(out)!r}).acquire()
os.kill(os.getpid(), signal.SIGKILL)
"""
    killed = subprocess.Popen([sys.executable, "-c", script])
    assert killed.wait(timeout=60) == -signal.SIGKILL
    left = json.loads(lock_path(out).read_text())  # its words are still there, its lock is not
    assert left["pid"] == killed.pid
    write_files(tmp_path / "in", range(2))
    with pytest.warns(ModalWarning, match=rf"taking over from a run that ended without releasing its lock "
                                          rf"\(pid {left['pid']} on"):
        result = fit_files(tmp_path / "in", out=out, client=dask_cluster[0])
    assert result.fitted == 2 and not lock_path(out).exists()


def test_the_lock_refuses_while_held_and_is_free_after(tmp_path):
    out = tmp_path / "r.h5"
    with RunLock(out):
        assert lock_path(out).exists()
        with pytest.raises(OutputInUseError, match=rf"pid {os.getpid()} on {socket.gethostname()}, started "):
            RunLock(out).acquire()
    assert not lock_path(out).exists()
    with RunLock(out):  # free again, no word of a takeover (a warning would fail this test)
        pass
