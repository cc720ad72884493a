"""Run a file reader in a forked child process, so that a damaged file that crashes or
hangs compiled library code (SciPy's MAT reader, libhdf5) ends in a FormatError instead
of killing or freezing the caller. Fuzzing found both (docs/stress.md).

The child is made with ``os.fork`` itself, not with :mod:`multiprocessing`, which refuses
to start children from daemonic processes (the worker processes of a ``multiprocessing.Pool``
or of Dask's nanny). Where the OS cannot fork the reader runs in-process. Warnings raised in
the child are re-issued in the parent; the toolkit's own errors and a MemoryError (the file was too large
for the memory the process may use, not damaged) come back as they were raised.
"""
from __future__ import annotations

import math
import os
import pickle
import select
import signal
import time
import warnings
from typing import Any, Callable

from ..errors import FormatError, ModalError

__all__ = ["call_isolated"]

_IN_CHILD = False
#: bytes read from the child at a time
_CHUNK = 1 << 20


def _child(func: Callable, args: tuple, fd: int, timeout_s: float) -> None:  # pragma: no cover - runs in the child
    global _IN_CHILD
    _IN_CHILD = True
    if hasattr(signal, "alarm"):
        # end on our own shortly after the parent's deadline: if the parent is killed
        # meanwhile (Ctrl-C, a harness timeout), a reader hung in compiled code would
        # otherwise live on as an orphan, spinning for ever (the stress fuzzer left dozens).
        # The default action of SIGALRM ends the process even inside C code.
        signal.signal(signal.SIGALRM, signal.SIG_DFL)
        signal.alarm(int(math.ceil(timeout_s)) + 2)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle (it ends this child)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result: tuple = ("ok", func(*args))
        except ModalError as exc:
            result = ("error", exc)
        except MemoryError as exc:  # the file is not damaged: the process ran out of memory reading it
            result = ("error", MemoryError(f"{exc}"))
        except BaseException as exc:  # noqa: BLE001 - anything else is a damaged file too
            result = ("error", FormatError(f"{type(exc).__name__}: {exc}"))
    try:
        data = pickle.dumps(result + ([(str(w.message), w.category) for w in caught],), pickle.HIGHEST_PROTOCOL)
    except Exception as exc:  # noqa: BLE001 - an unpicklable result: say so rather than crash
        data = pickle.dumps(("error", FormatError(f"the reader's result cannot be passed back ({exc})"), []))
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def _read_all(fd: int, deadline: float) -> bytes | None:
    """Everything the child writes until it closes its end; None when the deadline passes first."""
    chunks = []
    while True:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            return None
        block = os.read(fd, _CHUNK)
        if not block:
            return b"".join(chunks)
        chunks.append(block)


def call_isolated(func: Callable[..., Any], args: tuple, src: str, what: str, timeout_s: float = 120.0) -> Any:
    """``func(*args)`` in a forked child; its result, or a FormatError naming ``src``.

    Parameters
    ----------
    func : callable
        The reader (its result and exceptions must pickle).
    args : tuple
    src : str
        The file's name, for messages.
    what : str
        What the file is (``"HDF5 file"``), for messages.
    timeout_s : float
        The reader's deadline, s: after it the child is killed and a FormatError says so.
    """
    if _IN_CHILD or not hasattr(os, "fork"):
        return func(*args)
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            os.close(read_fd)
            _child(func, args, write_fd, timeout_s)
        finally:
            os._exit(0)
    os.close(write_fd)
    data = None
    try:
        data = _read_all(read_fd, time.monotonic() + timeout_s)
    finally:
        os.close(read_fd)
        if data is None:  # past the deadline, or the caller interrupted (Ctrl-C): the child goes too
            os.kill(pid, signal.SIGKILL)
        status = os.waitpid(pid, 0)[1]
    if data is None:
        raise FormatError(f"{src}: reading the {what} did not finish in {timeout_s:g} s; the file is probably "
                          "damaged (the library reading it loops)")
    if not data:
        raise FormatError(f"{src}: damaged {what}: the library reading it crashed (exit code "
                          f"{os.waitstatus_to_exitcode(status)})")
    outcome, payload, caught = pickle.loads(data)
    for message, category in caught:
        warnings.warn(message, category, stacklevel=3)
    if outcome == "ok":
        return payload
    raise payload
