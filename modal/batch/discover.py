"""Finding the FRF files of a batch and hashing their content.

Symbolic links: a folder's walk (and a glob's matches) takes a link only when it leads to a
place inside the folders given (a glob's folder is the part of the pattern before its first
wildcard), so that a link planted in a data folder cannot make a batch read, fit and archive a
file from elsewhere (``/etc/passwd``); ``follow_symlinks=True`` takes every link, and walks into
linked folders (each real folder once). A file named on its own is taken as named.
"""
from __future__ import annotations

import glob
import hashlib
import os
import re
import warnings
from collections.abc import Iterable, Sequence
from pathlib import Path

from ..errors import ModalWarning, ParameterError

__all__ = ["FRF_EXTENSIONS", "find_files", "file_sha256"]

#: Extensions a folder is searched for (UFF, CSV/text, MAT, HDF5); a file named explicitly is taken whatever its name.
FRF_EXTENSIONS = (".uff", ".unv", ".58", ".csv", ".txt", ".mat", ".h5", ".hdf5")


def _inside(path: Path, roots: Sequence[Path]) -> bool:
    return any(path == root or root in path.parents for root in roots)


def _walk(folder: Path, follow: bool, links_out: list[str], roots: Sequence[Path]) -> Iterable[Path]:
    """FRF files under ``folder`` (hidden entries skipped); links as the module says."""
    stack, visited = [folder], {folder.resolve()}
    while stack:
        current = stack.pop()
        try:
            entries = list(os.scandir(current))
        except OSError:  # unreadable folder: nothing found there
            continue
        for entry in entries:
            if entry.name.startswith("."):
                continue
            path = Path(entry.path)
            if entry.is_symlink():
                target = path.resolve()
                if not target.exists():
                    continue  # a dangling link
                if not (follow or _inside(target, roots)):
                    links_out.append(os.fspath(path))
                    continue
                if target.is_dir():
                    # a link inside the folders leads where the walk goes anyway
                    if follow and target not in visited:
                        visited.add(target)
                        stack.append(path)
                    continue
                if path.suffix.lower() in FRF_EXTENSIONS and target.is_file():
                    yield path
            elif entry.is_dir(follow_symlinks=False):
                real = path.resolve()
                if real not in visited:
                    visited.add(real)
                    stack.append(path)
            elif path.suffix.lower() in FRF_EXTENSIONS and entry.is_file(follow_symlinks=False):
                yield path


#: UFF extensions, and the opening of a dataset 58 or 58b (a function: FRFs and time records alike)
_UFF_EXTENSIONS = (".uff", ".unv", ".58")
_DATASET_58 = re.compile(rb"(?:^|\n)    -1\r?\n[ \t]*58b?[ \t\r\n]")


def _holds_no_measurement(path: Path, chunk: int = 1 << 20) -> bool:
    """A UFF file found in a folder that opens no dataset 58 (geometry, trace lines, results beside the
    measurements): nothing to fit. An unreadable file is taken (the batch reports why it fails). Read in pieces
    up to the first dataset 58: a measurement file opens one near its start, and only files without one are
    read whole."""
    if path.suffix.lower() not in _UFF_EXTENSIONS:
        return False
    tail, delimited = b"", False
    try:
        with open(path, "rb") as fh:
            while block := fh.read(chunk):
                data = tail + block
                if _DATASET_58.search(data):
                    return False
                delimited = delimited or b"    -1" in data
                tail = data[-16:]  # a dataset's opening split between two pieces
    except OSError:
        return False
    return delimited


def _glob_root(pattern: str) -> Path:
    """The folder of a glob pattern: its components before the first one with a wildcard."""
    parts = Path(pattern).parts
    fixed = []
    for part in parts:
        if glob.has_magic(part):
            break
        fixed.append(part)
    return Path(*fixed) if fixed else Path(".")


def find_files(inputs: str | os.PathLike | Sequence[str | os.PathLike],
               exclude: Sequence[str | os.PathLike] = (), follow_symlinks: bool = False) -> list[str]:
    """Every FRF file named by folders, glob patterns or file names.

    Parameters
    ----------
    inputs : path-like or sequence of path-likes
        A folder (searched recursively for :data:`FRF_EXTENSIONS`, hidden entries skipped),
        a glob pattern (``**`` recurses) or a file.
    exclude : sequence of path-likes
        Files and folders never taken (the batch's own archive, table, parts folder and lock).
    follow_symlinks : bool
        Take symbolic links wherever they lead; by default only those leading inside the folders
        given (see the module's description).

    Returns
    -------
    list of str
        Sorted, each file once (by its resolved path), spelled as found.

    Raises
    ------
    ParameterError
        An input that is neither a file, a folder nor a glob pattern names nothing that exists.

    Warns
    -----
    ModalWarning
        Links not followed because they lead outside the folders given (named, with the way to
        follow them).
    """
    items = [inputs] if isinstance(inputs, (str, os.PathLike)) else list(inputs)
    skip = [Path(p).resolve() for p in exclude]
    folders = [Path(item) for item in items if Path(item).is_dir()]
    patterns = [os.fspath(item) for item in items if not Path(item).exists() and glob.has_magic(os.fspath(item))]
    roots = [f.resolve() for f in folders] + [_glob_root(p).resolve() for p in patterns]
    found: dict[Path, str] = {}
    links_out: list[str] = []
    no_measurement: list[str] = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            candidates = list(_walk(path, follow_symlinks, links_out, roots))
            no_measurement += [os.fspath(c) for c in candidates if _holds_no_measurement(c)]
            candidates = [c for c in candidates if os.fspath(c) not in no_measurement]
        elif path.is_file():
            candidates = [path]  # named on its own: taken as named
        elif os.fspath(item) in patterns:
            candidates = []
            for match in map(Path, glob.glob(os.fspath(item), recursive=True)):
                if not (follow_symlinks or _inside(match.resolve(), roots)):
                    links_out.append(os.fspath(match))  # the match is, or lies under, a link leading out
                elif match.is_dir():
                    candidates += _walk(match, follow_symlinks, links_out, roots)
                elif match.is_file():
                    candidates.append(match)
        else:
            raise ParameterError(f"{os.fspath(item)}: no such file or folder; expected folders, glob patterns "
                                 "or files")
        for candidate in candidates:
            real = candidate.resolve()
            if any(real == s or s in real.parents for s in skip):
                continue
            found.setdefault(real, os.fspath(candidate))
    if no_measurement:
        shown = ", ".join(sorted(no_measurement)[:3]) + (f" and {len(no_measurement) - 3} more"
                                                          if len(no_measurement) > 3 else "")
        warnings.warn(f"{len(no_measurement)} UFF file(s) in the folders hold no dataset 58 (no FRF or time record: "
                      f"geometry or results) and were left out: {shown}", ModalWarning, stacklevel=2)
    if links_out:
        shown = ", ".join(sorted(links_out)[:3]) + (f" and {len(links_out) - 3} more" if len(links_out) > 3 else "")
        warnings.warn(f"{len(links_out)} symbolic link(s) lead outside the folders given and were not followed: "
                      f"{shown}; --follow-symlinks (follow_symlinks=True) follows them", ModalWarning, stacklevel=2)
    return sorted(found.values())


def file_sha256(path: str | os.PathLike, chunk: int = 1 << 20) -> str:
    """SHA-256 (hex) of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            digest.update(block)
    return digest.hexdigest()
