"""What ``modal batch`` takes from the folders and patterns it is given: symbolic links only where
they stay inside those folders (or with ``--follow-symlinks``), and one line for a path that does
not exist."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from modal.batch import find_files
from modal.errors import ModalWarning, ParameterError
from modal.io import write_frf

from support.batchfiles import mobility
from support.cli import run_module


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "modal", "batch", *map(str, args)], capture_output=True, text=True,
                          timeout=300, cwd=cwd)


@pytest.fixture
def planted(tmp_path):
    """``data/`` with two FRFs, a link to /etc/passwd, a link to an FRF outside, a link to a folder
    outside, a link back to ``data/`` itself and a link to an FRF inside; ``outside/`` beside it."""
    data, outside = tmp_path / "data", tmp_path / "outside"
    (data / "sub").mkdir(parents=True)
    outside.mkdir()
    write_frf(mobility(seed=0), data / "a.uff")
    write_frf(mobility(seed=1), data / "sub" / "b.uff")
    write_frf(mobility(seed=2), outside / "c.uff")
    (data / "passwd.txt").symlink_to("/etc/passwd")
    (data / "c_link.uff").symlink_to(outside / "c.uff")
    (data / "outside_dir").symlink_to(outside, target_is_directory=True)
    (data / "sub" / "loop").symlink_to(data, target_is_directory=True)
    (data / "b_link.uff").symlink_to(data / "sub" / "b.uff")
    return data, outside


def names(found):
    return sorted(Path(p).name for p in found)


def test_links_leading_out_of_the_folder_are_not_followed(planted):
    data, outside = planted
    with pytest.warns(ModalWarning, match=r"3 symbolic link\(s\) lead outside the folders given") as caught:
        found = find_files(data)
    # a.uff and b.uff once each (b_link.uff leads to b.uff, inside: the same file, kept once)
    assert len(found) == 2 and {Path(p).resolve() for p in found} == {data / "a.uff", data / "sub" / "b.uff"}
    message = str(caught[0].message)
    assert str(data / "passwd.txt") in message and "--follow-symlinks" in message


def test_a_link_into_another_folder_given_is_followed(planted):
    data, outside = planted
    with pytest.warns(ModalWarning, match=r"1 symbolic link\(s\)"):  # only /etc/passwd stays out
        found = find_files([data, outside])
    assert {Path(p).resolve() for p in found} == {data / "a.uff", data / "sub" / "b.uff", outside / "c.uff"}


def test_follow_symlinks_takes_every_link_and_walks_each_real_folder_once(planted):
    data, outside = planted
    found = find_files(data, follow_symlinks=True)  # no warning (pytest turns warnings into errors)
    real = sorted(str(Path(p).resolve()) for p in found)
    assert real == sorted({str(data / "a.uff"), str(data / "sub" / "b.uff"), str(outside / "c.uff"),
                           "/etc/passwd"})


def test_glob_matches_that_lead_out_are_not_taken(planted):
    data, _ = planted
    with pytest.warns(ModalWarning, match="passwd.txt"):
        found = find_files(str(data / "*.txt"))
    assert found == []
    with pytest.warns(ModalWarning, match="c_link.uff"):
        assert names(find_files(str(data / "*.uff"))) == ["a.uff", "b_link.uff"]


def test_batch_does_not_read_a_file_outside_through_a_link(planted, tmp_path, dask_cluster):
    data, _ = planted
    done = run_cli(data, "--out", tmp_path / "r.h5", "--scheduler", dask_cluster[0], "--json")
    assert done.returncode == 0, done.stderr
    assert "warning: 3 symbolic link(s) lead outside the folders given" in done.stderr
    table = (tmp_path / "r.csv").read_text()
    assert "passwd" not in table and "c_link" not in table and "outside_dir" not in table
    assert '"files": 2' in done.stdout


def test_a_missing_path_is_one_line(tmp_path):
    write_frf(mobility(), tmp_path / "a.uff")
    missing = tmp_path / "no_such_folder"
    with pytest.raises(ParameterError, match="no_such_folder: no such file or folder"):
        find_files([tmp_path, missing])
    done = run_module("modal", "batch", missing, "--out", tmp_path / "r.h5")  # in-process: the link test runs it
    assert done.returncode == 2
    assert done.stderr == f"error: {missing}: no such file or folder; expected folders, glob patterns or files\n"
    assert not (tmp_path / "r.h5").exists()


def test_a_failure_line_names_the_file_once(tmp_path, dask_cluster):
    write_frf(mobility(), tmp_path / "a.uff")
    broken = tmp_path / "broken.csv"
    broken.write_text("not,an\nfrf,file\n")
    done = run_module("modal", "batch", tmp_path, "--out", tmp_path / "r.h5", "--scheduler", dask_cluster[0])
    assert done.returncode == 1
    line, = [ln for ln in done.stderr.splitlines() if ln.startswith("failed:")]
    assert line.startswith(f"failed: {broken}: ") and line.count(str(broken)) == 1, line
    assert os.path.basename(broken) in line


def test_a_geometry_uff_beside_the_measurements_is_left_out_with_a_word(tmp_path):
    """data/synthetic holds the plate's FRFs and its geometry (datasets 15 and 82) side by side, as a lab folder
    does: `modal batch` on the folder failed on the geometry file ("no dataset 58") and exited 1. A UFF file found
    in a folder that opens no dataset 58 is left out, named in one warning; a file named on its own is taken as
    named (and fails, saying why); a damaged UFF that opens one is taken."""
    import shutil
    import warnings

    from support.paths import SYNTHETIC

    for name in ("plate_frf.uff", "plate_geometry.uff"):
        shutil.copy(SYNTHETIC / name, tmp_path / name)
    (tmp_path / "cut.uff").write_bytes((SYNTHETIC / "plate_frf.uff").read_bytes()[:5000])
    with pytest.warns(ModalWarning, match=r"1 UFF file\(s\) in the folders hold no dataset 58 .* left out: "
                                          r".*plate_geometry\.uff$"):
        found = find_files(tmp_path)
    assert names(found) == ["cut.uff", "plate_frf.uff"]
    # the files are read in pieces up to their first dataset 58: an opening split between two pieces still counts
    from modal.batch.discover import _holds_no_measurement

    assert [_holds_no_measurement(tmp_path / n, chunk=7) for n in ("plate_frf.uff", "plate_geometry.uff")] == \
        [False, True]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert names(find_files(tmp_path / "plate_geometry.uff")) == ["plate_geometry.uff"]
