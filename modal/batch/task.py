"""The work of one file on a Dask worker: read, fit, store the result, return what the client keeps."""
from __future__ import annotations

from ..errors import ModalError
from ..fitting import FitOptions
from .fitone import fit_one
from .fitproc import DEFAULT_FILE_TIMEOUT_S, fit_in_process
from .records import Entry, FileFit
from .store import PartStore, entry_of

__all__ = ["fit_one", "fit_and_store"]


def fit_and_store(paths: list[str], options: FitOptions, hashes: list[str], archive: str | None = None,
                  client_version: str | None = None,
                  file_timeout_s: float | None = DEFAULT_FILE_TIMEOUT_S) -> list[Entry]:
    """:func:`fit_one` for a chunk of files, each in a fitting process of this worker
    (:mod:`modal.batch.fitproc`: a file that hangs, crashes or passes ``file_timeout_s`` fails
    alone), then (with ``archive``) their results written to one part in the archive's parts
    folder by the worker; returns the client's :class:`Entry` per file (small: the table rows and
    where the result is, or the result itself when it is not stored). A worker with another
    version of the toolkit than the client's (``client_version``) fits nothing: every file fails
    with that reason (and a rerun tries again)."""
    from .._version import __version__

    if client_version is not None and client_version != __version__:
        error = (f"worker has modalbal {__version__}, the client {client_version}; expected the same version on "
                 "every worker (install this package in the workers' environment)")
        return [entry_of(FileFit(source=path, sha256=sha, settings=options.settings_json(),
                                 settings_hash=options.settings_hash(), error=error, retry=True))
                for path, sha in zip(paths, hashes)]
    fits = [fit_in_process(path, options, sha, file_timeout_s) for path, sha in zip(paths, hashes)]
    keep = [fit for fit in fits if not fit.retry]
    if archive is None or not keep:
        return [entry_of(fit) for fit in fits]
    try:
        stored = iter(PartStore(archive).save(keep))
    except (OSError, ModalError):  # parts folder not reachable from this worker: the client stores them
        return [entry_of(fit) for fit in fits]
    return [entry_of(fit) if fit.retry else next(stored) for fit in fits]
