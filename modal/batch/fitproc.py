"""Each file's fit in a process of its own beside the Dask worker: a file that hangs, crashes
or takes too long costs that process, never the worker.

The fitting process is a fresh interpreter (``python -c``), started by the worker on its first
file and kept for the next ones; one request at a time (a file's path, options and hash), one
:class:`~modal.batch.records.FileFit` back. A fresh interpreter rather than a fork of the worker:
a Dask worker process is daemonic (:mod:`multiprocessing` refuses it children) and
multithreaded (its event loop beside the task threads; a fork copies locks that another
thread may hold, and Python 3.12 warns of it). The fitting process itself is single-threaded
and not daemonic, so the readers' own protection (:mod:`modal.io._isolate`: MAT and HDF5 files
read in a forked child, a crash or a loop in the library ending in a FormatError) works in it as
it does under ``modal fit``.

A file still fitting after its time limit is listed as failed (``timed out after N s``): its
process and whatever it forked are killed (a session of their own) and the next file gets a
new process. A process that dies (a crash outside the readers, the kernel's OOM killer) fails
that file only. Its memory is its own: a file that needs a lot of it never grows the worker, and
the process may grow by the worker's memory limit at most (Dask's budget for the worker: the
machine's memory shared among the workers), past which the file fails with a MemoryError.
"""
from __future__ import annotations

import atexit
import math
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import threading
import time
from typing import Any

from .records import FileFit

__all__ = ["fit_in_process", "FitProcess", "ProcessEnded", "DEFAULT_FILE_TIMEOUT_S", "shutdown",
           "worker_memory_limit"]

#: Default time limit of one file's fit, s. The toolkit's slowest ordinary case, a 100 000-line FRF,
#: identifies in 0.5-1 s on an idle core and in under 60 s on a loaded one (benchmarks/REPORT.md):
#: five times that leaves a large, legitimate file room on a busy machine, while a file that loops
#: or explodes in work frees its worker within five minutes.
DEFAULT_FILE_TIMEOUT_S = 300.0
#: Time a new fitting process may take to start (imports of numpy, scipy, h5py and the toolkit), s.
STARTUP_TIMEOUT_S = 120.0
#: The process ends itself (SIGALRM, default action) this long after a file's deadline, so that it
#: cannot outlive a worker killed in the meantime, s.
_ORPHAN_MARGIN_S = 5.0
_HEADER = struct.Struct("!Q")
_CHUNK = 1 << 20


class ProcessEnded(Exception):
    """The fitting process ended, or was ended, before it answered (the message says how).

    Attributes
    ----------
    timed_out : bool
        Ended at the file's time limit.
    """

    def __init__(self, message: str, timed_out: bool = False):
        super().__init__(message)
        self.timed_out = timed_out


def _write(fd: int, obj: Any) -> None:
    data = pickle.dumps(obj, pickle.HIGHEST_PROTOCOL)
    view = memoryview(_HEADER.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _read_exact(fd: int, n: int, deadline: float | None) -> bytes | None:
    """``n`` bytes from ``fd``; None at end of file; TimeoutError past ``deadline`` (monotonic, s)."""
    chunks, size = [], 0
    while size < n:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise TimeoutError
        block = os.read(fd, min(_CHUNK, n - size))
        if not block:
            return None
        chunks.append(block)
        size += len(block)
    return b"".join(chunks)


def _read(fd: int, deadline: float | None = None) -> Any:
    """One message; EOFError when the other end has closed; TimeoutError past ``deadline``."""
    head = _read_exact(fd, _HEADER.size, deadline)
    if head is None:
        raise EOFError
    body = _read_exact(fd, _HEADER.unpack(head)[0], deadline)
    if body is None:
        raise EOFError
    return pickle.loads(body)


def _limit_memory(budget_bytes: int) -> None:
    """Let this process grow by at most ``budget_bytes`` of address space beyond what it has now (its
    interpreter and libraries): past it an allocation fails (numpy's MemoryError) instead of taking
    the machine's memory."""
    import resource

    with open("/proc/self/statm") as fh:
        now = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = now + int(budget_bytes)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def serve(memory_budget_bytes: int | None = None) -> None:  # pragma: no cover - runs in the fitting process
    """The fitting process: answer requests ``(path, options, sha256, timeout_s)`` on stdin with a
    :class:`FileFit` on stdout until stdin closes. Whatever the libraries print goes to /dev/null
    (stdout is the channel of the answers). With ``memory_budget_bytes`` the process may grow by
    that much at most (:func:`_limit_memory`)."""
    requests, answers = os.dup(0), os.dup(1)
    devnull = os.open(os.devnull, os.O_RDWR)
    os.dup2(devnull, 0)
    os.dup2(devnull, 1)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the worker decides when this process ends
    from .fitone import fit_one
    # identification's checks import their quantiles when they first run: loaded here, before the budget, so
    # that the budget is the fits' own and a fit after an out-of-memory one does not fail importing them
    from .. import quantiles  # noqa: F401

    if memory_budget_bytes and sys.platform == "linux":
        _limit_memory(memory_budget_bytes)
    _write(answers, ("ready", os.getpid()))
    while True:
        try:
            path, options, sha256, timeout_s = _read(requests)
        except EOFError:  # the worker has gone (or let this process go)
            return
        if timeout_s is not None:
            signal.signal(signal.SIGALRM, signal.SIG_DFL)
            signal.alarm(int(math.ceil(timeout_s + _ORPHAN_MARGIN_S)))
        fit = fit_one(path, options, sha256)
        signal.alarm(0)
        try:
            _write(answers, fit)
        except BrokenPipeError:
            return


class FitProcess:
    """One fitting process (see the module's description).

    Parameters
    ----------
    memory_budget_bytes : int, optional
        Memory the process may take beyond its interpreter and libraries (the worker's memory limit);
        past it, a file fails with a MemoryError and the process serves the next one.

    Raises
    ------
    ProcessEnded
        The process could not be started.
    """

    def __init__(self, memory_budget_bytes: int | None = None) -> None:
        self.memory_budget_bytes = int(memory_budget_bytes) if memory_budget_bytes else None
        try:
            self._proc = subprocess.Popen(
                [sys.executable, "-c",
                 f"from modal.batch.fitproc import serve; serve({self.memory_budget_bytes!r})"],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, start_new_session=True)
        except OSError as exc:
            raise ProcessEnded(f"cannot start a fitting process ({exc.strerror or exc})") from None
        try:
            self._answer(time.monotonic() + STARTUP_TIMEOUT_S, f"did not start in {STARTUP_TIMEOUT_S:g} s")
        except ProcessEnded as exc:
            raise ProcessEnded(f"cannot start a fitting process: {exc}") from None

    @property
    def pid(self) -> int:
        return self._proc.pid

    def alive(self) -> bool:
        return self._proc.poll() is None

    def _answer(self, deadline: float | None, late: str, timed_out: bool = False) -> Any:
        try:
            return _read(self._proc.stdout.fileno(), deadline)
        except TimeoutError:
            self.kill()
            raise ProcessEnded(late, timed_out) from None
        except (EOFError, OSError, pickle.UnpicklingError):
            self.kill()
            code = self._proc.returncode
            how = f"signal {-code}" if code is not None and code < 0 else f"exit code {code}"
            raise ProcessEnded(f"the fitting process ended ({how}) before it answered") from None

    def fit(self, path: str, options, sha256: str | None, timeout_s: float | None) -> FileFit:
        """The file's :class:`FileFit`; :class:`ProcessEnded` when the process ended or was ended
        (``timeout_s`` passed) before it answered."""
        try:
            _write(self._proc.stdin.fileno(), (path, options, sha256, timeout_s))
        except OSError:
            self.kill()
            raise ProcessEnded("the fitting process had ended") from None
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        return self._answer(deadline, f"timed out after {timeout_s:g} s", timed_out=True)

    def kill(self) -> None:
        """End the process and anything it forked (a reader's child): its whole session."""
        if self._proc.poll() is None:
            try:
                os.killpg(self._proc.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        self._proc.wait()
        for pipe in (self._proc.stdin, self._proc.stdout):
            try:
                pipe.close()
            except OSError:
                pass

    def close(self) -> None:
        """Let the process end (it sees the end of its requests), killing it if it lingers."""
        try:
            self._proc.stdin.close()
            self._proc.wait(5)
        except (OSError, subprocess.TimeoutExpired):
            pass
        self.kill()


_IDLE: list[FitProcess] = []
_LOCK = threading.Lock()


def worker_memory_limit() -> int | None:
    """The memory limit of the Dask worker running this code, bytes (None: none, or not in a worker)."""
    try:
        from distributed import get_worker

        limit = get_worker().memory_manager.memory_limit
    except (ImportError, ValueError, AttributeError):
        return None
    return int(limit) if limit else None


def fit_in_process(path: str, options, sha256: str | None, timeout_s: float | None,
                   memory_budget_bytes: int | None = None) -> FileFit:
    """Fit one file in a fitting process of this process (an idle one, or a new one); never raises
    for a bad file.

    Parameters
    ----------
    path : str
    options : FitOptions
    sha256 : str, optional
        The hash the caller computed (the file is hashed again by :func:`modal.batch.fitone.fit_one`).
    timeout_s : float or None
        The file's time limit, s; None for none.
    memory_budget_bytes : int, optional
        The memory a fit may take (see :class:`FitProcess`); the Dask worker's memory limit by default
        when one runs this code.

    Returns
    -------
    FileFit
        With ``error`` set when the file could not be read or fitted; a file that timed out or
        whose process died is marked ``retry`` (a rerun tries it again).
    """
    if os.name != "posix":  # pragma: no cover - no sessions or pipes to select on: fitted here, without a limit
        from .fitone import fit_one

        return fit_one(path, options, sha256)
    budget = worker_memory_limit() if memory_budget_bytes is None else memory_budget_bytes
    budget = int(budget) if budget else None
    with _LOCK:
        fitting = [p for p in _IDLE if p.memory_budget_bytes == budget]
        proc = fitting[-1] if fitting else None
        if proc is not None:
            _IDLE.remove(proc)
    try:
        if proc is not None and not proc.alive():
            proc.kill()  # ended while idle: reap it
            proc = None
        if proc is None:
            proc = FitProcess(budget)
        fit = proc.fit(path, options, sha256, timeout_s)
    except ProcessEnded as exc:
        return FileFit(source=path, sha256=sha256 or "", settings=options.settings_json(),
                       settings_hash=options.settings_hash(), error=f"{path}: {exc}", retry=True,
                       fit_time_s=timeout_s if exc.timed_out else float("nan"))
    with _LOCK:
        _IDLE.append(proc)
    return fit


def shutdown() -> None:
    """End the idle fitting processes of this process (at its exit, or when a caller is done)."""
    with _LOCK:
        idle = list(_IDLE)
        _IDLE.clear()
    for proc in idle:
        proc.close()


atexit.register(shutdown)
