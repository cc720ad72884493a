"""``modal batch`` on files whose fits warn: the warnings and the count of flagged modes in the table and the
JSON document (they were printed on stderr only, so the table a lab opens in a spreadsheet looked clean),
one-hit hammer files that look like takes of one test (said once, with the command that averages them; never
combined by the batch), and files copied in twice. On a real Dask cluster (the session fixture ``dask_cluster``), the CLI in a subprocess."""
from __future__ import annotations

import csv
import json
import shlex
import subprocess
import sys
from pathlib import Path

from modal.batch import TABLE_COLUMNS
from modal.batch.fitone import take_setup
from modal.flags import INFORMATIONAL
from modal.io import write_frf
from modal.io.timedata import read_time

from support.batchfiles import mobility
from support.cli import run_module
from support.paths import ROOT, SYNTHETIC

HAMMER = SYNTHETIC / "hammer.csv"  # eight hits 1.25 s apart from 0.2 s, 1024 samples/s (data/synthetic/generate.py)


def cut_hits(folder: Path, hits, rename: tuple[str, str] | None = None) -> list[Path]:
    """One file per hit of the shipped hammer record (1.25 s around it, its time from 0), as an analyser saves
    each triggered hit; ``rename`` edits the header (another response point)."""
    lines = HAMMER.read_text().splitlines()
    header, rows = lines[0], lines[1:]
    if rename is not None:
        header = header.replace(*rename)
    paths = []
    for hit in hits:
        first = round((0.1 + 1.25 * hit) * 1024)
        block = [r.split(",") for r in rows[first:first + 1280]]
        t0 = float(block[0][0])
        path = folder / f"hit{hit + 1}{'' if rename is None else '_other'}.csv"
        path.write_text("\n".join([header] + [",".join([repr(float(r[0]) - t0), *r[1:]]) for r in block]) + "\n")
        paths.append(path)
    return paths


def _batch(*args):
    return subprocess.run([sys.executable, "-m", "modal", "batch", *map(str, args)], capture_output=True, text=True,
                          timeout=600, cwd=ROOT)


def _batch_here(*args):
    return run_module("modal", "batch", *args, cwd=ROOT)


def test_warnings_and_flagged_modes_are_in_the_table_and_takes_are_named_once(dask_cluster, tmp_path):
    folder = tmp_path / "point1"
    folder.mkdir()
    takes = cut_hits(folder, range(3))  # three hits at one point, saved one per file
    other = cut_hits(folder, [3], rename=("1+Z [m/s^2]", "2+Z [m/s^2]"))[0]  # one hit of another point
    write_frf(mobility(), folder / "clean.uff")  # an FRF file that fits cleanly
    (folder / "sub").mkdir()
    (folder / "sub" / "clean_copy.uff").write_bytes((folder / "clean.uff").read_bytes())  # copied in twice
    out = tmp_path / "survey.h5"
    for status in ("fitted", "reused"):  # what is said comes with the results, reused ones too
        # the first run a process of its own, the second the same main in this process (support.cli)
        done = (_batch if status == "fitted" else _batch_here)(folder, "--out", out, "--scheduler", dask_cluster[0],
                                                                "--json")
        assert done.returncode == 0, done.stderr
        summary = json.loads(done.stdout)
        assert summary[status] == 6
        # the copy: named once, with the file it copies (the table has both, as they were found)
        assert summary["duplicates"] == [[str(folder / "clean.uff"), str(folder / "sub" / "clean_copy.uff")]]
        copies = [line for line in done.stderr.splitlines() if "hold the same bytes" in line]
        assert copies == [f"note: 2 files hold the same bytes (copies?): {folder / 'clean.uff'}, "
                          f"{folder / 'sub' / 'clean_copy.uff'}; the table holds their results once for each"]
        with open(tmp_path / "survey.csv", newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            assert tuple(reader.fieldnames) == TABLE_COLUMNS and TABLE_COLUMNS[-2:] == ("warnings", "flagged_modes")
            rows = list(reader)
        by_file: dict[str, list[dict]] = {}
        for row in rows:
            by_file.setdefault(row["file"], []).append(row)
        clean = by_file[str(folder / "clean.uff")]
        assert all(row["warnings"] == "" and row["flagged_modes"] == "0" for row in clean)
        warned = {item["file"]: item for item in summary["warnings"]}
        assert str(folder / "clean.uff") not in warned
        for path in [*takes, other]:
            mine = by_file[str(path)]
            # fitted without --impact: the estimate warned of the hit, and the cell says so without the file's
            # name (the row's first column has it)
            cell = mine[0]["warnings"]
            assert "short pulse(s)" in cell and "--impact" in cell and str(path) not in cell
            assert {row["warnings"] for row in mine} == {cell}  # the file's, on each of its rows
            # the count agrees with the flags column: modes with a flag beyond the informational ones
            flagged = {row["mode"] for row in mine if set(row["flags"].split()) - INFORMATIONAL}
            assert flagged and {row["flagged_modes"] for row in mine} == {str(len(flagged))}
            assert warned[str(path)]["flagged_modes"] == len(flagged)
            assert any("short pulse(s)" in w for w in warned[str(path)]["warnings"])
        # the three hits of one point: one note and one JSON group, not the other point's hit, not the FRF file
        command = "python -m modal fit " + " ".join(shlex.quote(str(p)) for p in takes) + " --impact"
        assert summary["takes"] == [{"files": [str(p) for p in takes], "command": command}]
        notes = [line for line in done.stderr.splitlines() if line.startswith("note: ") and "takes" in line]
        assert len(notes) == 1 and notes[0].startswith("note: 3 files look like takes of one test")
        assert notes[0].endswith(command) and str(other) not in notes[0]
    # the text summary counts the files to look at
    text = _batch_here(folder, "--out", out, "--scheduler", dask_cluster[0])
    assert "4 with warnings or flagged modes (table columns warnings, flagged_modes)" in text.stdout


def test_only_one_hit_time_files_have_a_take_setup(tmp_path):
    # the key by which takes are grouped: a one-hit file's rate and channels; none for several hits (a test of
    # its own), for continuous excitation or for the same hit with another response point
    one = cut_hits(tmp_path, [0])[0]
    other = cut_hits(tmp_path, [0], rename=("1+Z [m/s^2]", "2+Z [m/s^2]"))[0]
    setups = [take_setup((read_time(path), [0], [1])) for path in (one, other, HAMMER)]
    assert setups[0].startswith("1024.0 Hz, excitation 1:") and "1+Z [force, N]" in setups[0]
    assert setups[1] and setups[1] != setups[0]
    assert setups[2] == ""  # eight hits
    assert take_setup(None) == ""  # an FRF file
