"""Crash-safe writing: write a temporary file beside the target, then rename it.

Every writer in :mod:`modal.io` goes through :func:`atomic_path`, so a crash or
an exception never leaves a half-written file under the target's name.
"""
from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["atomic_path", "clean_stale_temporaries"]


def _default_mode() -> int:
    """0o666 minus the process umask (what ``open(path, "w")`` would give)."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _temp_prefix(target: Path) -> str:
    return f".{target.name}.pid"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists (another user's) or cannot tell: keep its file
    return True


def clean_stale_temporaries(target: str | os.PathLike) -> list[Path]:
    """Remove temporaries of ``target`` left by writers of this user that died (kill -9, power loss).

    Only files named ``.<target name>.pid<PID>-<random>.tmp`` (the names :func:`atomic_path`
    gives) whose process no longer exists and which belong to the current user are removed;
    a live writer's file (another process writing the same target right now) is left alone.

    Returns
    -------
    list of Path
        The files removed.
    """
    target = Path(target)
    folder = target.parent if str(target.parent) else Path(".")
    prefix = _temp_prefix(target)
    removed = []
    try:
        candidates = [p for p in folder.iterdir() if p.name.startswith(prefix) and p.name.endswith(".tmp")]
    except OSError:
        return removed
    uid = os.getuid() if hasattr(os, "getuid") else None
    for path in candidates:
        pid_text = path.name[len(prefix):].partition("-")[0]
        if not pid_text.isdigit() or int(pid_text) == os.getpid() or _pid_alive(int(pid_text)):
            continue
        try:
            if uid is not None and path.lstat().st_uid != uid:
                continue
            path.unlink()
            removed.append(path)
        except OSError:
            pass
    return removed


def _name_target(exc: BaseException, tmp: Path, target: Path) -> BaseException | None:
    """The same error naming the target instead of the temporary file (None when it does not name it)."""
    text = str(exc)
    if isinstance(exc, OSError) and exc.filename is not None and str(tmp) in str(exc.filename):
        return type(exc)(exc.errno, exc.strerror, str(target)) if exc.errno is not None else None
    if str(tmp) in text or tmp.name in text:
        try:
            return type(exc)(text.replace(str(tmp), str(target)).replace(tmp.name, target.name))
        except Exception:  # an exception class with another signature: leave it as it is
            return None
    return None


@contextmanager
def atomic_path(target: str | os.PathLike, verify: Callable[[Path], None] | None = None) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; rename it onto the target on success.

    Parameters
    ----------
    target : path-like
        Final file name. Its folder must exist.
    verify : callable, optional
        Called with the temporary path after the writer closed it and before the
        rename (for example: reopen and check the content). An exception from it
        aborts the write like any other.

    Yields
    ------
    Path
        An empty temporary file (``.<name>.pid<PID>-<random>.tmp``) the caller writes and closes.

    Raises
    ------
    OSError
        Naming the target (not the temporary) when its folder is missing or not writable.

    Notes
    -----
    On any exception the temporary file is removed and the target is left as it
    was; errors that named the temporary name the target instead. Temporaries of
    the same target left by dead writers (kill -9) are removed first
    (:func:`clean_stale_temporaries`). The rename is :func:`os.replace`, atomic on
    POSIX and Windows when both names are on the same file system (they are: same folder).
    """
    target = Path(target)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(2, "folder does not exist" if not folder.exists() else "not a folder",
                                str(target))
    clean_stale_temporaries(target)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f"{_temp_prefix(target)}{os.getpid()}-", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise type(exc)(exc.errno, exc.strerror, str(target)) from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:  # mkstemp makes the file private (0600); give it the target's or the usual mode
        os.chmod(tmp, target.stat().st_mode & 0o7777 if target.is_file() else _default_mode())
    except OSError:
        pass
    try:
        yield tmp
        if verify is not None:
            verify(tmp)
        os.replace(tmp, target)
    except BaseException as exc:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass
        renamed = _name_target(exc, tmp, target) if isinstance(exc, Exception) else None
        if renamed is not None:
            raise renamed from None
        raise
