"""``modal batch`` on a folder a recorder is still writing to: a file whose bytes change between the batch finding
it and its fit, or during the fit, fails (to be fitted by a rerun) instead of being fitted as whatever part of it
was there. Before, the part was fitted with exit 0: an FRF file cut at half its lines gave a table of one mode for
two, as plausible as a finished file's."""
from __future__ import annotations

import json

import modal.batch.fitone as fitone
import modal.batch.run as batch_run
from modal.batch import fit_files
from modal.batch.discover import file_sha256
from modal.batch.fitone import fit_one
from modal.fitting import FitOptions
from modal.io import write_frf

from support.batchfiles import mobility


def _recording(folder):
    """An FRF file as a recorder leaves it midway (its first 150 of 301 lines), and the rest of its text."""
    whole = folder / "whole.csv"
    write_frf(mobility(), whole)
    text = whole.read_text()
    whole.unlink()
    lines = text.splitlines(keepends=True)
    data = [i for i, line in enumerate(lines) if not line.startswith("#")]
    cut = data[150]
    path = folder / "recording.csv"
    path.write_text("".join(lines[:cut]))
    return path, "".join(lines[cut:])


def test_a_file_that_grows_after_the_batch_found_it_fails_and_a_rerun_fits_it(dask_cluster, tmp_path, monkeypatch):
    folder = tmp_path / "lab"
    folder.mkdir()
    write_frf(mobility(seed=1), folder / "finished.csv")
    recording, rest = _recording(folder)
    hash_of = batch_run.file_sha256

    def hash_then_record_on(path, *args, **kwargs):  # the client hashes, then the recorder writes the rest
        digest = hash_of(path, *args, **kwargs)
        if path.endswith("recording.csv") and recording.read_text().count("\n") < 200:
            with open(recording, "a") as fh:
                fh.write(rest)
        return digest

    monkeypatch.setattr(batch_run, "file_sha256", hash_then_record_on)
    out = tmp_path / "r.h5"
    result = fit_files(folder, client=dask_cluster[0], out=out)
    failed = {f["file"]: f["error"] for f in result.failed}
    assert list(failed) == [str(recording)]
    assert "its bytes changed since the batch found it (still being written" in failed[str(recording)]
    assert {row["file"] for row in result.rows()} == {str(folder / "finished.csv")}  # the finished file's rows kept
    monkeypatch.undo()
    again = fit_files(folder, client=dask_cluster[0], out=out)  # the recorder done: the rerun fits it
    assert again.failed == [] and again.reused == 1 and again.fitted == 1
    # both modes of the whole file (70 and 140 Hz), not only the first half's
    modes = sorted({round(row["natural_frequency_hz"]) for row in again.rows() if row["file"] == str(recording)})
    assert modes == [70, 140], json.dumps(again.summary())


def test_a_file_that_changes_during_its_fit_fails_to_be_retried(tmp_path, monkeypatch):
    recording, rest = _recording(tmp_path)
    fit = fitone.fit_path

    def fit_while_recording(path, options):  # the recorder appends while the fit reads
        result = fit(path, options)
        with open(recording, "a") as fh:
            fh.write(rest)
        return result

    monkeypatch.setattr(fitone, "fit_path", fit_while_recording)
    done = fit_one(str(recording), FitOptions(), file_sha256(recording))
    assert done.retry and not done.results
    assert "its bytes changed while it was fitted (still being written" in done.error


def test_a_finished_file_is_fitted_under_its_hash(tmp_path):
    path = tmp_path / "finished.csv"
    write_frf(mobility(), path)
    done = fit_one(str(path), FitOptions(), file_sha256(path))
    assert done.error == "" and done.sha256 == file_sha256(path) and len(done.results) == 1
