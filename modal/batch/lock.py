"""One batch run per output: a lock on ``<archive>.lock``, held for the whole run.

The lock is the operating system's (``flock``): it ends with the process that holds it, however
that process ends (kill -9 included), so a run that was killed never blocks the next one. The
file also says who holds it (process id, host, start time, command), so that a second run on the
same output refuses at once naming the running one, and a run that finds the words of a holder
that no longer holds the lock (killed before it could remove the file) says it takes over.
The file is removed when the run ends.
"""
from __future__ import annotations

import json
import os
import socket
import sys
import warnings
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

from ..errors import ModalError, ModalWarning

__all__ = ["RunLock", "LockHolder", "OutputInUseError", "lock_path"]


class OutputInUseError(ModalError, RuntimeError):
    """Another batch run holds the output's lock (the message names it)."""


def lock_path(archive: str | os.PathLike) -> Path:
    """The lock file beside the archive: ``RESULTS.h5`` → ``RESULTS.h5.lock``."""
    archive = Path(archive)
    return archive.with_name(archive.name + ".lock")


@dataclass(frozen=True)
class LockHolder:
    """Who holds (or held) a lock.

    Attributes
    ----------
    pid : int
    host : str
    started : str
        Start time of the run, ISO 8601 with the UTC offset.
    command : str
    """

    pid: int
    host: str
    started: str
    command: str = ""

    @classmethod
    def here(cls) -> "LockHolder":
        """This process, now."""
        program = sys.argv[0] if sys.argv else ""
        program = "python -m modal" if program.endswith("__main__.py") else os.path.basename(program) or "python"
        return cls(pid=os.getpid(), host=socket.gethostname(),
                   started=datetime.now().astimezone().isoformat(timespec="seconds"),
                   command=" ".join([program, *sys.argv[1:]])[:300])

    @classmethod
    def parse(cls, text: str) -> "LockHolder | None":
        try:
            doc = json.loads(text)
            return cls(pid=int(doc["pid"]), host=str(doc["host"]), started=str(doc["started"]),
                       command=str(doc.get("command", "")))
        except (ValueError, KeyError, TypeError):
            return None

    def describe(self) -> str:
        return f"pid {self.pid} on {self.host}, started {self.started}" + (f": {self.command}" if self.command else "")


class RunLock:
    """The lock of one output (see the module's description).

    Parameters
    ----------
    archive : path-like
        The batch archive the lock guards.
    """

    def __init__(self, archive: str | os.PathLike):
        self.archive = Path(archive)
        self.path = lock_path(archive)
        self._fd: int | None = None

    def acquire(self) -> None:
        """Take the lock, or raise :class:`OutputInUseError` at once.

        Warns
        -----
        ModalWarning
            A run that ended without releasing the lock left its words in the file (it is taken over),
            or the file system offers no locks (the run goes on unguarded).
        """
        import fcntl

        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = LockHolder.parse(_read(fd))
                os.close(fd)
                who = holder.describe() if holder is not None else "a process that has not yet said who it is"
                raise OutputInUseError(f"{self.archive}: another modal batch run is writing it ({who}); wait for "
                                       f"it to finish or choose another --out (lock {self.path})") from None
            except OSError as exc:  # a file system without locks (some network mounts)
                os.close(fd)
                warnings.warn(f"{self.path}: cannot lock the output ({exc.strerror or exc}); a second run on "
                              f"{self.archive} would not be stopped", ModalWarning, stacklevel=3)
                return
            try:
                same = os.fstat(fd).st_ino == os.stat(self.path).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)  # locked a file its holder removed as it finished: take the new one
        previous = LockHolder.parse(_read(fd))
        if previous is not None:
            warnings.warn(f"{self.archive}: taking over from a run that ended without releasing its lock "
                          f"({previous.describe()}); its saved results are reused", ModalWarning, stacklevel=3)
        os.ftruncate(fd, 0)
        os.pwrite(fd, json.dumps(vars(LockHolder.here())).encode(), 0)
        os.fsync(fd)
        self._fd = fd

    def release(self) -> None:
        """Remove the lock file and let the lock go."""
        if self._fd is None:
            return
        try:
            os.unlink(self.path)
        except OSError:
            pass
        os.close(self._fd)
        self._fd = None

    def __enter__(self) -> "RunLock":
        self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def _read(fd: int) -> str:
    try:
        return os.pread(fd, 4096, 0).decode("utf-8", "replace")
    except OSError:
        return ""
