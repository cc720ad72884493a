"""Where a batch keeps its results: parts while it runs, one archive and one table at the end.

Crash safety: each chunk of fitted files (a Dask task: about four per worker, at most 16 files) is
written at once to its own small archive in the parts folder ``<archive>.parts/`` by the worker
that fitted it (atomically: temporary file, checked, renamed), so an interrupted run (Ctrl-C,
kill -9, a lost worker or client) loses at most the chunks in flight. One part per chunk rather
than per file: an HDF5 file costs about as much to create and check as a small fit. The archive itself is only ever replaced whole (temporary file, checked, renamed; see
:func:`modal.io._atomic.atomic_path`): its groups are copied from the parts and from the previous
archive (HDF5 object copies, no decoding), then the parts folder is removed. A rerun reuses a
file's result from either place when its content hash and the settings hash are unchanged; every
copy is checked by those hashes, never taken by its position. One run at a time writes an archive
and its parts (:mod:`modal.batch.lock`).
"""
from __future__ import annotations

import csv
import hashlib
import io
import math
import os
import shutil
from collections.abc import Sequence
from pathlib import Path

import h5py

from ..archive import write_archive, write_node
from ..errors import ArchiveError
from ..io._atomic import atomic_path
from ..io.hdf5 import check_schema, write_root_attrs
from .records import BatchInfo, Entry, FileFit

__all__ = ["PartStore", "TABLE_COLUMNS", "table_text", "parse_table", "write_table", "write_batch_archive",
           "parts_folder"]

#: Columns of the batch table (one row per file, method, mode and channel; channels counted from 1, as
#: ``modal fit`` numbers them and ``--driving-point`` names them). The last two are the file's: ``warnings``,
#: what its fit warned of (one line each without the file's name, joined by " | "; empty when it fitted cleanly)
#: and ``flagged_modes``,
#: how many of the file's modes of that method carry a flag beyond the informational ones.
TABLE_COLUMNS = ("file", "method", "mode", "channel", "natural_frequency_hz", "std_natural_frequency_hz",
                 "damping_ratio", "std_damping_ratio", "stiffness_n_per_m", "std_stiffness_n_per_m",
                 "damping_n_s_per_m", "std_damping_n_s_per_m", "mass_kg", "std_mass_kg", "flags", "warnings",
                 "flagged_modes")
_STD_NAMES = ("natural_frequency_hz", "damping_ratio", "stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
_INTEGER = ("mode", "channel", "flagged_modes")
_TEXT = ("file", "method", "flags", "warnings")
#: the columns a file's stored rows hold (:func:`table_text`); the file's own columns are added when written
_STORED = TABLE_COLUMNS[1:TABLE_COLUMNS.index("flags") + 1]
WARNING_SEPARATOR = " | "


def parts_folder(archive: str | os.PathLike) -> Path:
    """The folder beside the archive that holds per-file results while a batch runs."""
    archive = Path(archive)
    return archive.with_name(archive.name + ".parts")


def _cell(value) -> str:
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return str(value)


def table_text(results) -> str:
    """The batch table's rows of one file as CSV lines without the ``file`` column (numbers at full
    precision, empty where not defined; channels counted from 1)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    for result in results:
        for row in result.rows():
            cells = [row["method"], row["mode"], row["channel"] + 1]
            for name in _STD_NAMES:
                cells += [float(row[name]), float(row["std"][name])]
            cells.append(" ".join(row["flags"]))
            writer.writerow([_cell(c) for c in cells])
    return buffer.getvalue()


def _file_cells(source: str, rows: list[list[str]], warnings: Sequence[str]) -> list[list[str]]:
    """Each stored row (cells of :func:`table_text`) with the file's ``warnings`` (without the file's name, which
    the row's first column gives) and ``flagged_modes`` cells: the modes of the row's method with a flag that
    is not informational (on any of their channels)."""
    from ..flags import serious_flags

    method, mode, flags = (_STORED.index(name) for name in ("method", "mode", "flags"))
    flagged: dict[str, set[str]] = {}
    for cells in rows:
        if serious_flags(cells[flags]):
            flagged.setdefault(cells[method], set()).add(cells[mode])
    text = WARNING_SEPARATOR.join(w.removeprefix(f"{source}: ") for w in warnings)
    return [[*cells, text, str(len(flagged.get(cells[method], ())))] for cells in rows]


def parse_table(source: str, text: str, warnings: Sequence[str] = ()) -> tuple[dict, ...]:
    """Rows (dicts over :data:`TABLE_COLUMNS`) from :func:`table_text` and the file's ``warnings`` (NaN for empty
    numbers)."""
    rows = []
    for cells in _file_cells(source, list(csv.reader(io.StringIO(text))), warnings):
        row: dict = {"file": source}
        for name, cell in zip(TABLE_COLUMNS[1:], cells):
            if name in _TEXT:
                row[name] = cell
            elif name in _INTEGER:
                row[name] = int(cell)
            else:
                row[name] = float(cell) if cell else float("nan")
        rows.append(row)
    return tuple(rows)


def write_table(path: str | os.PathLike, entries: Sequence[Entry]) -> Path:
    """The batch table as CSV (columns :data:`TABLE_COLUMNS`), written atomically."""
    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(TABLE_COLUMNS)
            for entry in entries:
                for cells in _file_cells(entry.source, list(csv.reader(io.StringIO(entry.table))), entry.warnings):
                    writer.writerow([entry.source, *cells])
    return path


def _text(node) -> str | None:
    if not isinstance(node, h5py.Dataset):
        return None
    value = node[()]
    return value.decode() if isinstance(value, bytes) else str(value)


def _texts(node) -> tuple[str, ...]:
    """A stored tuple of strings (a group of datasets "0", "1", ...); empty when absent."""
    if not isinstance(node, h5py.Group):
        return ()
    return tuple(t for i in range(len(node)) if (t := _text(node.get(str(i)))) is not None)


def _entry(node, location: tuple[str, str]) -> Entry | None:
    try:
        return Entry(source=_text(node["source"]), sha256=_text(node["sha256"]), error=_text(node["error"]),
                     retry=bool(node["retry"][()]), table=_text(node["table"]), location=location,
                     warnings=_texts(node.get("warnings")), take_setup=_text(node.get("take_setup")) or "")
    except KeyError:
        return None


class PartStore:
    """Per-file results of one batch archive: the parts folder and the previous archive, keyed by
    (content hash, settings hash).

    A part is a small archive of one chunk of files (``/files/<i>``, one :class:`FileFit` each),
    written by the worker that fitted them, so that the HDF5 file overhead and the task overhead are
    paid once per chunk rather than once per file.

    Parameters
    ----------
    archive : path-like
        The batch archive (need not exist yet).
    """

    def __init__(self, archive: str | os.PathLike):
        self.archive = Path(archive)
        self.folder = parts_folder(self.archive)

    @staticmethod
    def _scan(path: Path, settings_hash: str, missing: set[str], found: dict[str, Entry]) -> None:
        with h5py.File(path, "r") as f:
            group = f.get("files")
            for name in group.keys() if isinstance(group, h5py.Group) else ():
                node = group[name]
                sha = _text(node.get("sha256"))
                if sha in missing and _text(node.get("settings_hash")) == settings_hash:
                    entry = _entry(node, (str(path), node.name))
                    if entry is not None and not entry.retry:
                        found[sha] = entry
                        missing.discard(sha)

    def index(self, settings_hash: str, wanted: set[str]) -> dict[str, Entry]:
        """Earlier results for these content hashes under these settings (parts first, then the
        previous archive), without reading them whole; results a rerun tries again (``retry``) are
        left out, and so are unreadable parts and archives (those files are fitted again)."""
        found: dict[str, Entry] = {}
        missing = set(wanted)
        sources = sorted(self.folder.glob(f"{settings_hash[:16]}-*.h5")) if self.folder.is_dir() else []
        if self.archive.is_file():
            sources.append(self.archive)
        for path in sources:
            if not missing:
                break
            try:
                self._scan(path, settings_hash, missing, found)
            except (OSError, KeyError):
                continue
        return found

    def save(self, fits: Sequence[FileFit]) -> list[Entry]:
        """Write one chunk of results to a new part, atomically; the entries that point at them."""
        self.folder.mkdir(exist_ok=True)
        key = hashlib.sha256("".join(f.sha256 for f in fits).encode()).hexdigest()[:16]
        part = self.folder / f"{fits[0].settings_hash[:16]}-{key}.h5"
        write_archive(part, {"files": list(fits)})
        return [Entry(source=fit.source, sha256=fit.sha256, error=fit.error, retry=fit.retry, table=fit.table,
                      location=(str(part), f"/files/{i}"), warnings=fit.warnings, take_setup=fit.take_setup)
                for i, fit in enumerate(fits)]

    def clear(self) -> None:
        """Remove the parts folder (once the archive holds everything)."""
        shutil.rmtree(self.folder, ignore_errors=True)


def _by_content(handle, node: str, entry: Entry, settings_hash: str):
    """The group of ``handle`` holding the result of ``entry``'s content (its sha256) under these
    settings: the group the index found (``node``) when it still does, else any that does, else None
    (the file was replaced since it was indexed). Never a group by its position alone."""
    def holds(group) -> bool:
        return (isinstance(group, h5py.Group) and _text(group.get("sha256")) == entry.sha256
                and _text(group.get("settings_hash")) == settings_hash)

    found = handle.get(node)
    if holds(found):
        return found
    files = handle.get("files")
    for name in files.keys() if isinstance(files, h5py.Group) else ():
        if holds(files[name]):
            return files[name]
    return None


def write_batch_archive(path: str | os.PathLike, info: BatchInfo, entries: Sequence[Entry]) -> Path:
    """The batch archive, written whole and atomically: ``/batch`` (:class:`BatchInfo`) and
    ``/files/<i>`` (one :class:`FileFit` per file, in the order given), read back by
    :func:`modal.archive.read_archive` as ``archive["batch"]`` and the list ``archive["files"]``.

    Stored results are copied as HDF5 objects from their part file or the previous archive (which may
    be ``path`` itself: it is replaced only after the new file is complete and checked), each found by
    its content hash and settings hash, never by its position alone (an archive replaced since it was
    indexed holds other files at those positions); a reused result of a file found under another path
    gets that path as ``source``.

    Raises
    ------
    ArchiveError
        A stored result can no longer be read, or its file no longer holds it (replaced during the run):
        nothing is written, the parts are kept, a rerun completes the archive.
    """
    path = Path(path)

    def verify(tmp: Path) -> None:
        with h5py.File(tmp, "r") as f:
            check_schema(f, str(path), error=ArchiveError)
            if "batch" not in f or len(f["files"]) != len(entries):
                raise ArchiveError(f"{path}: verification after writing found {len(f.get('files', {}))} of "
                                   f"{len(entries)} file groups")

    sources: dict[str, h5py.File] = {}
    try:
        with atomic_path(path, verify=verify) as tmp:
            with h5py.File(tmp, "w", track_order=True) as f:
                write_root_attrs(f)
                write_node(f, "batch", info)
                files = f.create_group("files")
                files.attrs["__type__"] = "list"
                files.attrs["__len__"] = len(entries)
                for i, entry in enumerate(entries):
                    if entry.location is None:
                        write_node(files, str(i), entry.fit)
                        continue
                    name, node = entry.location
                    if name not in sources:
                        try:
                            sources[name] = h5py.File(name, "r")
                        except OSError as exc:
                            raise ArchiveError(f"{path}: the saved result of {entry.source} cannot be read from "
                                               f"{name} ({' '.join(str(exc).split())}); run the batch again "
                                               "(what is saved is reused)") from None
                    stored = _by_content(sources[name], node, entry, info.settings_hash)
                    if stored is None:
                        raise ArchiveError(f"{path}: {name} no longer holds the result of {entry.source} (sha256 "
                                           f"{entry.sha256[:16]}...): it was replaced during the run; run the "
                                           "batch again")
                    sources[name].copy(stored, files, name=str(i))
                    group = files[str(i)]
                    if _text(group["source"]) != entry.source:
                        del group["source"]
                        write_node(group, "source", entry.source)
    finally:
        for handle in sources.values():
            handle.close()
    return path


def entry_of(fit: FileFit) -> Entry:
    """An entry holding the fit itself (not stored in a part)."""
    return Entry(source=fit.source, sha256=fit.sha256, error=fit.error, retry=fit.retry, table=fit.table, fit=fit,
                 warnings=fit.warnings, take_setup=fit.take_setup)


