"""The work of one file on a Dask worker: read, fit, store the result, return what the client keeps."""
from __future__ import annotations

import time
import warnings

from ..errors import ModalError
from ..fitting import FitOptions, fit_path
from .discover import file_sha256
from .fitproc import DEFAULT_FILE_TIMEOUT_S, fit_in_process
from .records import Entry, FileFit, one_line
from .store import PartStore, entry_of, table_text

__all__ = ["fit_one", "fit_and_store"]


def fit_one(path: str, options: FitOptions, sha256: str | None = None) -> FileFit:
    """Fit one file as ``modal fit`` does; never raises for a bad file.

    Parameters
    ----------
    path : str
    options : FitOptions
    sha256 : str, optional
        The hash the caller computed; the file is hashed again here and that hash is recorded
        (a file replaced in between is keyed by what was fitted).

    Returns
    -------
    FileFit
        With ``error`` set (one line) when the file could not be read or fitted.
    """
    settings, settings_hash = options.settings_json(), options.settings_hash()
    start = time.perf_counter()
    try:
        sha256 = file_sha256(path)
    except OSError as exc:
        return FileFit(source=path, sha256=sha256 or "", settings=settings, settings_hash=settings_hash,
                       error=one_line(exc), retry=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = fit_path(path, options)
        except ModalError as exc:  # the file's verdict: kept for reruns of the same content
            return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                           error=one_line(exc), fit_time_s=time.perf_counter() - start)
        except MemoryError as exc:  # past the fitting process's memory budget (the worker's memory limit)
            return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                           error=f"{path}: out of memory ({one_line(exc)}); a file may use the worker's memory "
                                 "limit at most", retry=True, fit_time_s=time.perf_counter() - start)
        except Exception as exc:  # noqa: BLE001 - per-file failures are data; a rerun tries again
            return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                           error=one_line(exc), retry=True, fit_time_s=time.perf_counter() - start)
    frf = out.frf
    texts = tuple(dict.fromkeys(" ".join(str(w.message).split()) for w in caught))
    return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                   kind=frf.kind, n_channels=int(frf.n_channels), n_lines=int(frf.n_freq),
                   frequency_range_hz=(float(frf.frequency_hz[0]), float(frf.frequency_hz[-1])),
                   results=tuple(out.results), warnings=texts, fit_time_s=time.perf_counter() - start,
                   table=table_text(out.results))


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
