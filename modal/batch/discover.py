"""Finding the FRF files of a batch and hashing their content."""
from __future__ import annotations

import glob
import hashlib
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

__all__ = ["FRF_EXTENSIONS", "find_files", "file_sha256"]

#: Extensions a folder is searched for (UFF, CSV/text, MAT, HDF5); a file named explicitly is taken whatever its name.
FRF_EXTENSIONS = (".uff", ".unv", ".58", ".csv", ".txt", ".mat", ".h5", ".hdf5")


def _hidden(path: Path, root: Path) -> bool:
    return any(part.startswith(".") for part in path.relative_to(root).parts)


def _from_folder(folder: Path) -> Iterable[Path]:
    for path in folder.rglob("*"):
        if path.suffix.lower() in FRF_EXTENSIONS and path.is_file() and not _hidden(path, folder):
            yield path


def find_files(inputs: str | os.PathLike | Sequence[str | os.PathLike],
               exclude: Sequence[str | os.PathLike] = ()) -> list[str]:
    """Every FRF file named by folders, glob patterns or file names.

    Parameters
    ----------
    inputs : path-like or sequence of path-likes
        A folder (searched recursively for :data:`FRF_EXTENSIONS`, hidden entries skipped),
        a glob pattern (``**`` recurses) or a file.
    exclude : sequence of path-likes
        Files and folders never taken (the batch's own archive, table and parts folder).

    Returns
    -------
    list of str
        Sorted, each file once (by its resolved path), spelled as found.
    """
    items = [inputs] if isinstance(inputs, (str, os.PathLike)) else list(inputs)
    skip = [Path(p).resolve() for p in exclude]
    found: dict[Path, str] = {}
    for item in items:
        path = Path(item)
        if path.is_dir():
            candidates = list(_from_folder(path))
        elif path.is_file():
            candidates = [path]
        else:
            candidates = [Path(p) for p in glob.glob(os.fspath(item), recursive=True)]
            candidates = [c for c in candidates if c.is_file()] + [f for c in candidates if c.is_dir()
                                                                   for f in _from_folder(c)]
        for candidate in candidates:
            real = candidate.resolve()
            if any(real == s or s in real.parents for s in skip):
                continue
            found.setdefault(real, os.fspath(candidate))
    return sorted(found.values())


def file_sha256(path: str | os.PathLike, chunk: int = 1 << 20) -> str:
    """SHA-256 (hex) of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            digest.update(block)
    return digest.hexdigest()
