"""Many files, one fit each, on Dask: the order of work of :func:`iter_fit` and :func:`fit_files`."""
from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ParameterError
from ..fitting import FitOptions
from ..flags import serious_flags
from .discover import file_sha256, find_files
from .fitproc import DEFAULT_FILE_TIMEOUT_S
from .lock import RunLock, lock_path
from .records import BatchInfo, Entry, FileFit, Outcome, one_line
from .store import PartStore, entry_of, parse_table, parts_folder, write_batch_archive, write_table

__all__ = ["BatchResult", "iter_fit", "fit_files", "default_table", "takes_command"]


def default_table(archive: str | os.PathLike) -> Path:
    """The table beside the archive: ``RESULTS.h5`` → ``RESULTS.csv``."""
    return Path(archive).with_suffix(".csv")


@dataclass(frozen=True)
class BatchResult:
    """What :func:`fit_files` returns: every file's outcome, in file order.

    Attributes
    ----------
    outcomes : tuple of Outcome
    archive, table : str or None
        Paths written (None without ``out``).
    wall_time_s : float
        Wall time of the run, s.
    """

    outcomes: tuple[Outcome, ...]
    archive: str | None
    table: str | None
    wall_time_s: float

    @property
    def fitted(self) -> int:
        """Files fitted in this run."""
        return sum(o.status == "fitted" for o in self.outcomes)

    @property
    def reused(self) -> int:
        """Files whose result an earlier run had (same content hash and settings)."""
        return sum(o.status == "reused" for o in self.outcomes)

    @property
    def failed(self) -> list[dict[str, str]]:
        """``[{"file", "error"}]`` for every file that could not be fitted."""
        return [{"file": o.file, "error": o.error} for o in self.outcomes if o.status == "failed"]

    def rows(self) -> list[dict]:
        """The table: one dict per file, method, mode and channel (``pandas.DataFrame(result.rows())``)."""
        return [row for o in self.outcomes for row in o.rows]

    @property
    def warned(self) -> list[dict[str, Any]]:
        """``[{"file", "warnings", "flagged_modes"}]`` for every fitted file whose fit warned or flagged a mode:
        its warnings (one line each) and how many of its modes carry a flag that is not informational (over
        its methods)."""
        out = []
        for o in self.outcomes:
            flagged = {(row["method"], row["mode"]) for row in o.rows
                       if serious_flags(row["flags"])}
            if o.status != "failed" and (o.warnings or flagged):
                out.append({"file": o.file, "warnings": list(o.warnings), "flagged_modes": len(flagged)})
        return out

    @property
    def takes(self) -> list[list[str]]:
        """Files that look like takes of one test, fitted one by one: groups of two or more time files whose
        excitation holds one hammer hit each, recorded with the same channels (names, quantities, units) at the
        same sample rate (:attr:`FileFit.take_setup`), in file order. A single hit gives a single average:
        together (``modal fit FILE... --impact``) the hits are averaged and their scatter measures the noise.
        They are never combined by the batch itself (the folder may hold repeats of one point on purpose)."""
        groups: dict[str, list[str]] = {}
        for o in self.outcomes:
            if o.take_setup and o.status != "failed":
                groups.setdefault(o.take_setup, []).append(o.file)
        return [files for files in groups.values() if len(files) >= 2]

    @property
    def duplicates(self) -> list[list[str]]:
        """Files that hold the same bytes (a file copied into the folder twice), in groups of two or more, in file
        order: the table holds the same results once for each."""
        groups: dict[str, list[str]] = {}
        for o in self.outcomes:
            if o.sha256:
                groups.setdefault(o.sha256, []).append(o.file)
        return [files for files in groups.values() if len(files) >= 2]

    def summary(self) -> dict[str, Any]:
        """The ``--json`` document: files, fitted, reused, failed, warnings (:attr:`warned`), takes (:attr:`takes`
        with the command that fits each group together), duplicates (:attr:`duplicates`), archive, table,
        wall_time_s."""
        return {"files": len(self.outcomes), "fitted": self.fitted, "reused": self.reused, "failed": self.failed,
                "warnings": self.warned, "takes": [{"files": files, "command": takes_command(files)}
                                                   for files in self.takes],
                "duplicates": self.duplicates, "archive": self.archive, "table": self.table,
                "wall_time_s": self.wall_time_s}


def takes_command(files: Sequence[str]) -> str:
    """The command that estimates one-hit files together, as takes of one test (their hits averaged)."""
    import shlex

    return " ".join(["python -m modal fit", *map(shlex.quote, files), "--impact"])


def _progress(total: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, unit="file", disable=not enabled, leave=False, dynamic_ncols=True)


def iter_fit(paths: str | os.PathLike | Sequence[str | os.PathLike], *, client: Any = None,
             out: str | os.PathLike | None = None, table: str | os.PathLike | None = None,
             workers: int | None = None, progress: bool = False,
             file_timeout_s: float | None = DEFAULT_FILE_TIMEOUT_S, dashboard: bool | str = False,
             follow_symlinks: bool = False, **fit_options: Any) -> Iterator[Outcome]:
    """Fit every FRF file, yielding each file's :class:`Outcome` as it is done.

    Parameters
    ----------
    paths : path-like or sequence of path-likes
        Folders (searched recursively), glob patterns or files (:func:`modal.batch.find_files`).
        A symbolic link is followed only when it leads inside the folders given, unless ``follow_symlinks``.
    client : distributed.Client or str, optional
        A Dask client, or a scheduler address ``tcp://HOST:PORT``; default an embedded local
        cluster of ``workers`` processes, started only when some file needs fitting.
    out : path-like, optional
        Batch archive; with it, results of an earlier run with the same file content and options
        are reused, each chunk of fitted files is saved at once (``<out>.parts/``), and the archive and the
        table are written when the iteration ends. Without it nothing is written.
    table : path-like, optional
        CSV table (default ``out`` with suffix ``.csv``).
    workers : int, optional
        Workers of the local cluster (default: the cores).
    progress : bool
        Show a progress bar on stderr.
    file_timeout_s : float or None
        Time limit of one file's fit, s (default :data:`~modal.batch.fitproc.DEFAULT_FILE_TIMEOUT_S`);
        a file still fitting then is listed as failed (``timed out after N s``, tried again by a
        rerun) and the batch goes on. None: no limit. Each file is fitted in a process of its own
        beside the worker (:mod:`modal.batch.fitproc`), so a file that hangs or crashes fails alone.
    dashboard : bool or str
        Local cluster: serve Dask's dashboard (True: at :data:`~modal.batch.cluster.DEFAULT_DASHBOARD`,
        or at this ``HOST:PORT``); by default the local cluster starts no HTTP server at all.
    follow_symlinks : bool
        Follow every symbolic link found in the folders, wherever it leads.
    **fit_options
        The options of ``modal fit`` under their Python names (:class:`modal.fitting.FitOptions`):
        ``method``, ``bands_hz``, ``kind``, ``driving_point``, ``modes_hz``, ...

    Yields
    ------
    Outcome
        Reused files first, then fitted or failed files in the order they finish.

    Raises
    ------
    ParameterError
        Unknown or contradictory options, an input that does not exist, no file found, a missing
        output folder.
    """
    options = FitOptions.from_kwargs(**fit_options)
    file_timeout_s = _check_timeout(file_timeout_s)
    if dashboard and client is not None:
        raise ParameterError("dashboard applies to the local cluster; a running scheduler serves its own")
    dashboard = ("127.0.0.1:8787" if dashboard is True else str(dashboard)) if dashboard else None
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise ParameterError(f"workers must be a whole number >= 1, got {workers!r}")
    if out is not None:
        out = Path(out)
        table = Path(table) if table is not None else default_table(out)
        for target, name in ((out, "out"), (table, "table")):
            if not target.parent.is_dir() and str(target.parent):
                raise ParameterError(f"--{name} {target}: folder {target.parent} does not exist")
            if target.is_dir():
                raise ParameterError(f"--{name} {target}: is a folder; expected a file name")
    elif table is not None:
        raise ParameterError("table needs out (the archive that makes a run resumable)")
    exclude = [] if out is None else [out, table, parts_folder(out), lock_path(out)]
    files = find_files(paths, exclude=exclude, follow_symlinks=follow_symlinks)
    if not files:
        shown = paths if isinstance(paths, (str, os.PathLike)) else ", ".join(map(str, paths))
        raise ParameterError(f"no FRF file found in {shown}; expected folders, glob patterns or files "
                             "(UFF, CSV, MAT, HDF5)")
    return _run(files, options, client, out, table, workers, progress, file_timeout_s, dashboard)


def _check_timeout(value) -> float | None:
    if value is None:
        return None
    try:
        seconds = float(value)
    except (TypeError, ValueError):
        seconds = math.nan
    if isinstance(value, bool) or not (seconds > 0 and math.isfinite(seconds)):
        raise ParameterError(f"file timeout {value!r}: expected a time in seconds > 0 (or None for no limit)")
    return seconds


def _outcome(entry: Entry, status: str) -> Outcome:
    return Outcome(entry.source, status, entry.error, parse_table(entry.source, entry.table, entry.warnings),
                   entry.fit, entry.warnings, entry.take_setup, entry.sha256)


def _run(files: list[str], options: FitOptions, client, out, table, workers, progress,
         file_timeout_s, dashboard) -> Iterator[Outcome]:
    """The run, holding the output's lock from the first file hashed to the table written."""
    lock = RunLock(out) if out is not None else None
    if lock is not None:
        lock.acquire()  # before anything is read or written: a second run on the same output stops here
    try:
        yield from _locked_run(files, options, client, out, table, workers, progress, file_timeout_s, dashboard)
    finally:
        if lock is not None:
            lock.release()


def _locked_run(files: list[str], options: FitOptions, client, out, table, workers, progress,
                file_timeout_s, dashboard) -> Iterator[Outcome]:
    start = time.perf_counter()
    settings, settings_hash = options.settings_json(), options.settings_hash()
    store = PartStore(out) if out is not None else None
    hashes: dict[str, str] = {}
    done: dict[str, Entry] = {}
    statuses: dict[str, str] = {}
    pending: list[str] = []
    for path in files:
        try:
            hashes[path] = file_sha256(path)
        except OSError as exc:
            done[path] = entry_of(FileFit(source=path, sha256="", settings=settings, settings_hash=settings_hash,
                                          error=one_line(exc), retry=True))
            statuses[path] = "failed"
    known = store.index(settings_hash, set(hashes.values())) if store is not None else {}
    bar = _progress(len(files), progress)
    try:
        for path in files:
            if path in done:
                bar.update()
                yield _outcome(done[path], "failed")
            elif hashes[path] in known:
                entry = dataclasses.replace(known[hashes[path]], source=path)
                done[path], statuses[path] = entry, "failed" if entry.error else "reused"
                bar.update()
                yield _outcome(entry, statuses[path])
            else:
                pending.append(path)
        if pending:
            yield from _fit_pending(pending, options, hashes, client, workers, store, done, statuses, bar,
                                    file_timeout_s, dashboard)
    finally:
        bar.close()
    if out is not None:
        entries = [done[p] for p in files]
        failed = [e for e in entries if e.error]
        info = BatchInfo(settings=settings, settings_hash=settings_hash, n_files=len(files),
                         n_fitted=sum(s == "fitted" for s in statuses.values()),
                         n_reused=sum(s == "reused" for s in statuses.values()), n_failed=len(failed),
                         failed_files=tuple(e.source for e in failed), failed_errors=tuple(e.error for e in failed),
                         wall_time_s=time.perf_counter() - start)
        write_batch_archive(out, info, entries)
        write_table(table, entries)
        store.clear()


def chunk_size(n_files: int, n_workers: int) -> int:
    """Files per task: about four tasks per worker (load balance, and a crash loses at most the chunks in
    flight), at most 16 files (a chunk is one part file: its overhead is paid once)."""
    return max(1, min(16, -(-n_files // (4 * max(1, n_workers)))))


def _fit_pending(pending, options, hashes, client, workers, store, done, statuses, bar,
                 file_timeout_s, dashboard) -> Iterator[Outcome]:
    from distributed import as_completed

    from .._version import __version__
    from .cluster import open_client
    from .task import fit_and_store

    archive = None if store is None else str(store.archive.resolve())
    with open_client(client, workers, dashboard) as dask:
        size = chunk_size(len(pending), len(dask.scheduler_info().get("workers", {})))
        chunks = [pending[i:i + size] for i in range(0, len(pending), size)]
        futures = {dask.submit(fit_and_store, chunk, options, [hashes[p] for p in chunk], archive, __version__,
                               file_timeout_s, pure=False): chunk
                   for chunk in chunks}
        for future in as_completed(futures, loop=dask.loop):
            chunk = futures[future]
            try:
                entries = future.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker (KilledWorker) or a cancelled task: data
                entries = [entry_of(FileFit(source=path, sha256=hashes[path], settings=options.settings_json(),
                                            settings_hash=options.settings_hash(), error=one_line(exc), retry=True))
                           for path in chunk]
            future.release()
            unstored = [i for i, e in enumerate(entries) if e.location is None and not e.retry]
            if store is not None and unstored:  # the worker could not write the part: the client does
                for i, entry in zip(unstored, store.save([entries[i].fit for i in unstored])):
                    entries[i] = entry
            for path, entry in zip(chunk, entries):
                if entry.source != path:
                    entry = dataclasses.replace(entry, source=path)
                done[path], statuses[path] = entry, "failed" if entry.error else "fitted"
                bar.update()
                yield _outcome(entry, statuses[path])


def fit_files(paths: str | os.PathLike | Sequence[str | os.PathLike], *, client: Any = None,
              out: str | os.PathLike | None = None, table: str | os.PathLike | None = None,
              workers: int | None = None, progress: bool = False,
              file_timeout_s: float | None = DEFAULT_FILE_TIMEOUT_S, dashboard: bool | str = False,
              follow_symlinks: bool = False, **fit_options: Any) -> BatchResult:
    """Fit every FRF file and return all outcomes (the Python side of ``modal batch``).

    Parameters are those of :func:`iter_fit`.

    Returns
    -------
    BatchResult
        ``result.rows()`` is the table, ``result.failed`` the failures, ``result.summary()`` the
        ``--json`` document.

    Examples
    --------
    >>> result = fit_files("survey/", out="survey.h5", kind="accelerance")   # doctest: +SKIP
    >>> result.fitted, result.reused, result.failed                          # doctest: +SKIP
    """
    start = time.perf_counter()
    outcomes = {o.file: o for o in iter_fit(paths, client=client, out=out, table=table, workers=workers,
                                            progress=progress, file_timeout_s=file_timeout_s,
                                            dashboard=dashboard, follow_symlinks=follow_symlinks,
                                            **fit_options)}
    ordered = tuple(outcomes[p] for p in sorted(outcomes))
    table_path = None if out is None else str(Path(table) if table is not None else default_table(out))
    return BatchResult(outcomes=ordered, archive=None if out is None else str(out), table=table_path,
                       wall_time_s=time.perf_counter() - start)
