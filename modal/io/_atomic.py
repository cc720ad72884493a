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

__all__ = ["atomic_path"]


def _default_mode() -> int:
    """0o666 minus the process umask (what ``open(path, "w")`` would give)."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


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
        An empty temporary file (``.<name>.<random>.tmp``) the caller writes and closes.

    Notes
    -----
    On any exception the temporary file is removed and the target is left as it
    was. The rename is :func:`os.replace`, atomic on POSIX and Windows when both
    names are on the same file system (they are: same folder).
    """
    target = Path(target)
    folder = target.parent if str(target.parent) else Path(".")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
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
    except BaseException:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass
        raise
