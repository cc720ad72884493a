"""`python -m modal batch` and `modal.batch`: many FRF files on Dask, one archive and one table,
per-file failures as data, resumable after a crash or a lost worker.

A real Dask scheduler and two workers are started from the installed `dask` command on 127.0.0.1
(the session fixture ``dask_cluster`` of conftest.py); the local runs use the embedded LocalCluster.
The FRFs are small (301 lines, two modes, band-wise NLS) so that the module stays fast.
"""
from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from modal.archive import read_archive
from modal.batch import TABLE_COLUMNS, file_sha256, find_files, fit_files, iter_fit
from modal.errors import ModalWarning, ParameterError
from modal.io import write_frf
from modal.synthetic import add_noise, modal_frf

from support.cli import run_module
from support.daskcluster import free_port, quiet_environment, start_worker, wait_for_workers

FREQ = np.linspace(20.0, 200.0, 301)  # 0.6 Hz lines; the modes are 2.4 and 5 Hz wide (>= 4 lines per bandwidth)
NOISE = 1e-3  # of the peak magnitude: the NLS standard errors of f_n are ~1e-5 relative


def truth(index: int) -> tuple[float, float]:
    """The natural frequencies (Hz) of generated file ``index``: two well-separated modes."""
    rng = np.random.default_rng(1000 + index)
    return 60.0 + 20.0 * rng.random(), 130.0 + 20.0 * rng.random()


def write_files(folder: Path, n: int, start: int = 0) -> list[Path]:
    """``n`` UFF 58 files of a two-mode driving-point mobility with noise; every fifth in a sub-folder."""
    paths = []
    for index in range(start, start + n):
        frf = modal_frf(FREQ, list(truth(index)), [0.02, 0.02], [1.0, 0.7], kind="mobility",
                        response_points=["1+Z"], reference_points=["1+Z"])
        target = folder / ("sub" if index % 5 == 4 else "") / f"f{index:03d}.uff"
        target.parent.mkdir(parents=True, exist_ok=True)
        write_frf(add_noise(frf, NOISE, seed=index), target)
        paths.append(target)
    return paths


def run_cli(*args, cwd=None):
    """``python -m modal batch ARGS``, a process of its own; an embedded cluster it starts has the session
    cluster's quiet settings (support.daskcluster.QUIET): its subject here is the table, not Dask's defaults
    (tests/modal/batch/test_cluster.py runs the embedded cluster as configured by default)."""
    return subprocess.run([sys.executable, "-m", "modal", "batch", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300, env=quiet_environment())


def run_here(*args):
    """``modal batch ARGS`` in this process (support.cli): the tests whose subject is not the process; those
    that read Dask's log on stderr, or the process itself, use :func:`run_cli`."""
    return run_module("modal", "batch", *args)


def read_table(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        assert tuple(reader.fieldnames) == TABLE_COLUMNS
        return list(reader)


def assert_correct(rows: list[dict[str, str]]) -> None:
    """Every file's two modes at their true frequencies within 5 of their standard errors (a wrong mode,
    a swapped file or a broken fit is off by hertz; 5 sigma fails by chance with probability 6e-7 per value)."""
    assert rows
    for row in rows:
        index = int(Path(row["file"]).stem[1:])
        expected = truth(index)[int(row["mode"]) - 1]
        sigma = float(row["std_natural_frequency_hz"])
        assert 0 < sigma < 1e-2 and abs(float(row["natural_frequency_hz"]) - expected) < 5 * sigma, row
        assert float(row["stiffness_n_per_m"]) > 0 and float(row["mass_kg"]) > 0  # driving point: k, c, m known


def assert_same_tables(a: list[dict[str, str]], b: list[dict[str, str]]) -> None:
    """Same rows; numbers equal to 1e-9 relative (the same code on the same bytes: only the order of
    floating-point sums may differ between processes)."""
    assert [(r["file"], r["method"], r["mode"], r["channel"], r["flags"]) for r in a] == \
           [(r["file"], r["method"], r["mode"], r["channel"], r["flags"]) for r in b]
    numeric = [c for c in TABLE_COLUMNS if c not in ("file", "method", "mode", "channel", "flags", "warnings")]
    for ra, rb in zip(a, b):
        for column in numeric:
            va = float(ra[column]) if ra[column] else np.nan
            vb = float(rb[column]) if rb[column] else np.nan
            np.testing.assert_allclose(va, vb, rtol=1e-9, atol=0, equal_nan=True, err_msg=f"{ra['file']} {column}")


@pytest.fixture(scope="module")
def small_set(tmp_path_factory):
    folder = tmp_path_factory.mktemp("small") / "survey"
    write_files(folder, 12)
    return folder


# ---- cluster and local: identical tables --------------------------------------------------------------------

def test_cluster_and_local_runs_give_identical_tables(dask_cluster, small_set, tmp_path):
    address = dask_cluster[0]
    remote = run_cli(small_set, "--out", tmp_path / "remote.h5", "--scheduler", address, "--json")
    assert remote.returncode == 0, remote.stderr
    local = run_cli(small_set, "--out", tmp_path / "local.h5", "--workers", "2", "--json")
    assert local.returncode == 0, local.stderr
    for done in (remote, local):
        doc = json.loads(done.stdout)
        assert set(doc) == {"files", "fitted", "reused", "failed", "warnings", "takes", "duplicates", "archive",
                            "table", "wall_time_s"}
        assert (doc["files"], doc["fitted"], doc["reused"], doc["failed"]) == (12, 12, 0, [])
        assert (doc["warnings"], doc["takes"], doc["duplicates"]) == ([], [], [])  # clean FRF files: nothing to say
        assert doc["wall_time_s"] > 0 and "Traceback" not in done.stderr
    assert json.loads(remote.stdout)["table"] == str(tmp_path / "remote.csv")  # default: beside the archive
    rows = read_table(tmp_path / "remote.csv")
    assert len(rows) == 24  # 12 files x 2 modes x 1 channel
    assert_correct(rows)
    assert_same_tables(rows, read_table(tmp_path / "local.csv"))
    assert not (tmp_path / "remote.h5.parts").exists()  # the parts are in the archive now


def test_archive_has_one_group_per_file_with_hash_settings_and_modes(dask_cluster, small_set, tmp_path):
    out = tmp_path / "res.h5"
    result = fit_files(small_set, client=dask_cluster[0], out=out, method="nls")
    files = find_files(small_set)
    assert len(files) == 12 and any("/sub/" in f for f in files)  # the sub-folder was searched
    archive = read_archive(out)
    fits = archive["files"]
    assert [f.source for f in fits] == files == [o.file for o in result.outcomes]
    for fit in fits:
        assert fit.ok and fit.sha256 == file_sha256(fit.source)
        assert json.loads(fit.settings)["options"] == {"method": "nls"}
        mode = fit.results[0].modes[0]
        assert mode.method == "nls" and np.isfinite(mode.std.natural_frequency_hz) and mode.flags == ()
    info = archive["batch"]
    assert (info.n_files, info.n_fitted, info.n_reused, info.n_failed) == (12, 12, 0, 0)
    with h5py.File(out, "r") as f:  # every number carries its unit
        missing = []
        f.visititems(lambda name, node: missing.append(name) if isinstance(node, h5py.Dataset)
                     and node.dtype.kind in "biufc" and "units" not in node.attrs else None)
        assert missing == []
        assert f["files/0/fit_time_s"].attrs["units"] == "s"
        assert f["files/0/frequency_range_hz/0"].attrs["units"] == "Hz"
    assert len(result.rows()) == 24 and result.summary()["fitted"] == 12


def test_without_an_archive_the_results_come_back_whole_and_nothing_is_written(dask_cluster, small_set, tmp_path):
    before = sorted(p.name for p in small_set.rglob("*"))
    result = fit_files(small_set, client=dask_cluster[0], method="nls")
    assert (result.archive, result.table, result.fitted) == (None, None, 12)
    assert sorted(p.name for p in small_set.rglob("*")) == before  # no parts, no archive, no table
    for outcome in result.outcomes:
        fit = outcome.fit  # the whole FileFit when no archive holds it
        assert fit.ok and fit.source == outcome.file and len(fit.results[0]) == 2
        assert [r["natural_frequency_hz"] for r in outcome.rows] == [m.natural_frequency_hz for m in fit.results[0]]
    with pytest.raises(ParameterError, match="table needs out"):
        fit_files(small_set, table=tmp_path / "t.csv")


# ---- resumable: content hash and settings ---------------------------------------------------------------------

def test_rerun_refits_only_changed_files_and_changed_settings(dask_cluster, tmp_path):
    folder = tmp_path / "in"
    paths = write_files(folder, 6)
    out = tmp_path / "res.h5"
    first = fit_files(folder, client=dask_cluster[0], out=out)
    assert (first.fitted, first.reused) == (6, 0)
    frf = modal_frf(FREQ, [70.0, 140.0], [0.02, 0.02], [1.0, 0.7], kind="mobility")
    write_frf(add_noise(frf, NOISE, seed=99), paths[2])  # new content under the same name
    second = fit_files(folder, client=dask_cluster[0], out=out)
    assert (second.fitted, second.reused) == (1, 5)
    assert [o.file for o in second.outcomes if o.status == "fitted"] == [str(paths[2])]
    third = fit_files(folder, client=dask_cluster[0], out=out, method="circle")  # other settings: nothing reused
    assert (third.fitted, third.reused) == (6, 0)
    assert {row["method"] for row in third.rows()} == {"circle"}


def test_worker_killed_mid_batch_completes(dask_cluster, tmp_path):
    """A third worker is killed (SIGKILL, no nanny) while it runs a task: Dask gives its tasks to the
    others and every file is fitted (or, failing that, a rerun completes the batch); the archive is whole."""
    from distributed import Client

    address, folder, procs = dask_cluster
    files_dir = tmp_path / "in"
    write_files(files_dir, 30)
    victim = start_worker(address, "victim", folder)
    procs.append(victim)  # stopped with the cluster if anything below fails
    wait_for_workers(address, 3)
    out = tmp_path / "res.h5"
    with Client(address, timeout="30s", set_as_default=False) as client:
        victim_address = next(a for a, w in client.scheduler_info()["workers"].items() if w["name"] == "victim")
        outcomes, killed_at = [], None
        for outcome in iter_fit(files_dir, client=client, out=out):
            outcomes.append(outcome)
            if killed_at is None:
                deadline = time.monotonic() + 30
                while not client.processing(workers=[victim_address])[victim_address]:
                    assert time.monotonic() < deadline, "the victim worker never got a task"
                    time.sleep(0.005)
                victim.send_signal(signal.SIGKILL)
                victim.wait(timeout=10)
                killed_at = len(outcomes)
        assert killed_at < 30  # the kill happened with files still to do
        retried = [o for o in outcomes if o.status == "failed"]
        assert all(o.fit is not None and o.fit.retry for o in retried)  # only a lost worker may fail a file here
        if retried:
            again = fit_files(files_dir, client=client, out=out)
            assert again.failed == [] and again.reused == 30 - len(retried)
    fits = read_archive(out)["files"]
    assert len(fits) == 30 and all(f.ok for f in fits)
    assert_correct([row for fit in fits for row in _rows(fit)])


def _rows(fit):
    from modal.batch.store import parse_table

    return [{k: ("" if isinstance(v, float) and not np.isfinite(v) else str(v)) for k, v in row.items()}
            for row in parse_table(fit.source, fit.table)]


def test_killed_client_loses_only_files_in_flight_and_never_the_archive(dask_cluster, tmp_path):
    """kill -9 of the process running a batch: the earlier archive is untouched (same bytes), the files
    done so far are in the parts folder, and the rerun reuses them and finishes."""
    folder = tmp_path / "in"
    write_files(folder, 4)
    out = tmp_path / "res.h5"
    assert fit_files(folder, client=dask_cluster[0], out=out).fitted == 4
    before = out.read_bytes()
    write_files(folder, 16, start=4)
    script = textwrap.dedent(f"""
        import os, signal
        from modal.batch import iter_fit
        done = 0
        for outcome in iter_fit({str(folder)!r}, client={dask_cluster[0]!r}, out={str(out)!r}):
            done += outcome.status == "fitted"
            if done == 6:
                os.kill(os.getpid(), signal.SIGKILL)
    """)
    crashed = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert crashed.returncode == -signal.SIGKILL, crashed.stderr
    assert out.read_bytes() == before  # the archive was never touched
    # a part (one chunk of files) under its final name is always whole: written aside, checked, renamed
    # (workers may still be writing the chunks that were in flight)
    saved = [fit for part in (tmp_path / "res.h5.parts").glob("*.h5") for fit in read_archive(part)["files"]]
    assert len(saved) >= 6 and all(fit.ok for fit in saved)
    # the killed run's lock went with it (the kernel's); the words it left are taken over, and said so
    with pytest.warns(ModalWarning, match="taking over from a run that ended without releasing its lock"):
        again = fit_files(folder, client=dask_cluster[0], out=out)
    assert again.failed == [] and again.reused >= 4 + 6 and again.fitted + again.reused == 20
    assert len(read_archive(out)["files"]) == 20


# ---- 100+ files with two broken ones ------------------------------------------------------------------------

def test_hundred_files_with_two_broken_then_rerun_reuses_everything(dask_cluster, tmp_path):
    folder = tmp_path / "survey"
    good = write_files(folder, 100)
    truncated = folder / "broken_truncated.uff"
    text = good[0].read_text()
    truncated.write_text(text[: len(text) // 2])
    garbage = folder / "sub" / "broken_garbage.csv"
    garbage.write_text("not,an\nfrf,file\n")
    out = tmp_path / "res.h5"
    options = ("--out", out, "--table", tmp_path / "table.csv", "--scheduler", dask_cluster[0], "--json",
               "--method", "nls")
    first = run_here(folder, *options)
    assert first.returncode == 1, first.stderr
    doc = json.loads(first.stdout)
    assert (doc["files"], doc["fitted"], doc["reused"]) == (102, 100, 0)
    assert sorted(item["file"] for item in doc["failed"]) == sorted([str(truncated), str(garbage)])
    for item in doc["failed"]:
        assert "\n" not in item["error"] and Path(item["file"]).name in item["error"]  # one line naming the file
        assert f"failed: {item['error']}\n" in first.stderr  # the error names the file: once on the line
    rows = read_table(tmp_path / "table.csv")
    assert len(rows) == 200 and not any("broken" in r["file"] for r in rows)
    assert_correct(rows)
    archive = read_archive(out)
    assert len(archive["files"]) == 102 and archive["batch"].n_failed == 2
    assert sorted(archive["batch"].failed_files) == sorted([str(truncated), str(garbage)])

    second = run_here(folder, *options)
    assert second.returncode == 1, second.stderr
    again = json.loads(second.stdout)
    # every unchanged file reused, nothing fitted (the two broken files are reported again from the archive)
    assert (again["files"], again["fitted"], again["reused"]) == (102, 0, 100)
    assert again["failed"] == doc["failed"]
    assert_same_tables(read_table(tmp_path / "table.csv"), rows)


def test_a_worker_with_another_version_fits_nothing_and_says_why(tmp_path):
    from modal.batch.task import fit_and_store
    from modal.fitting import FitOptions

    path = str(write_files(tmp_path, 1)[0])
    entry, = fit_and_store([path], FitOptions(), [file_sha256(path)], str(tmp_path / "r.h5"), client_version="0.0.0")
    assert entry.retry and "worker has modalbal" in entry.error and "client 0.0.0" in entry.error
    assert not (tmp_path / "r.h5.parts").exists()


# ---- usage and discovery ------------------------------------------------------------------------------------

def test_bad_usage_exits_2(small_set, tmp_path, capsys):
    from modal.cli import main

    cases = [
        (tmp_path / "nothing_here", "--out", tmp_path / "r.h5"),  # no such folder
        (tmp_path / "nothing_here*", "--out", tmp_path / "r.h5"),  # no file found
        (small_set, "--out", tmp_path / "r.h5", "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"),
        (small_set, "--out", tmp_path / "r.h5", "--method", "nls", "--modes-hz", "70"),
        (small_set, "--out", tmp_path / "missing" / "r.h5"),
        (small_set, "--out", tmp_path / "r.h5", "--workers", "0"),
        (small_set, "--out", tmp_path),  # a folder, not an archive name
    ]
    for args in cases:  # in this process (the same main() as the command; a subprocess below)
        try:
            code = main(["batch", *map(str, args)])
        except SystemExit as exc:  # argparse
            code = exc.code
        assert code == 2, args
        assert "error" in capsys.readouterr().err
    done = run_cli(small_set)  # no --out
    assert done.returncode == 2 and "--out" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "r.h5").exists()


def test_unreachable_scheduler_is_one_line_and_exit_1(small_set, tmp_path):
    done = run_cli(small_set, "--out", tmp_path / "r.h5", "--scheduler", f"tcp://127.0.0.1:{free_port()}")
    assert done.returncode == 1
    assert done.stderr.strip().startswith("error: --scheduler") and "Traceback" not in done.stderr


def test_find_files_recurses_skips_hidden_and_the_outputs(tmp_path):
    write_files(tmp_path, 5)  # f004 in sub/
    (tmp_path / ".hidden").mkdir()
    (tmp_path / ".hidden" / "x.uff").write_text("-1\n")
    (tmp_path / "notes.md").write_text("not an FRF file")
    (tmp_path / "res.h5").write_bytes(b"")
    (tmp_path / "res.h5.parts").mkdir()
    (tmp_path / "res.h5.parts" / "p.h5").write_bytes(b"")
    found = find_files([tmp_path, str(tmp_path / "sub" / "*.uff")],
                       exclude=[tmp_path / "res.h5", tmp_path / "res.h5.parts"])
    assert [Path(p).name for p in found] == ["f000.uff", "f001.uff", "f002.uff", "f003.uff", "f004.uff"]
    assert [Path(p).name for p in find_files(str(tmp_path / "**" / "f00[34].uff"))] == ["f003.uff", "f004.uff"]
    with pytest.raises(ParameterError, match="unknown fit option"):
        fit_files(tmp_path, methd="nls")
    with pytest.raises(ParameterError, match="no FRF file found"):
        fit_files(tmp_path / "empty*")


def test_a_file_without_point_ids_gets_no_k_c_m_unless_its_driving_point_is_declared():
    # the beam's second file is a transfer FRF (hammer at point 2, response at point 1) and says nothing of
    # its points: k and m made from it would be numbers without meaning, so the table leaves them empty
    from support.paths import REAL

    from modal.batch.store import parse_table
    from modal.batch.task import fit_one
    from modal.fitting import FitOptions

    path = str(REAL / "pyuff_meas_point_2.txt")
    options = dict(method="nls", frequency_step=1.0, kind="accelerance", bands_hz=((270.0, 290.0),))
    rows = parse_table(path, fit_one(path, FitOptions(**options)).table)
    assert len(rows) == 1 and rows[0]["channel"] == 1  # channels counted from 1, as --driving-point names them
    assert np.isnan(rows[0]["stiffness_n_per_m"]) and np.isnan(rows[0]["mass_kg"])
    assert rows[0]["flags"].split() == ["driving_point_unknown"]
    # declared (--driving-point 1), the same file's channel gets them
    rows = parse_table(path, fit_one(path, FitOptions(**options, driving_point=("1",))).table)
    assert rows[0]["stiffness_n_per_m"] > 0 and rows[0]["mass_kg"] > 0 and "driving_point" not in rows[0]["flags"]
