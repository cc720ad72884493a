"""Run a file reader in a forked child process, so that a damaged file that crashes or
hangs compiled library code (SciPy's MAT reader, libhdf5) ends in a FormatError instead
of killing or freezing the caller. Fuzzing found both (docs/stress.md).

Where the OS cannot fork the reader runs in-process. Warnings raised in the child are
re-issued in the parent; the toolkit's own errors come back as they were raised.
"""
from __future__ import annotations

import math
import multiprocessing
import signal
import warnings
from typing import Any, Callable

from ..errors import FormatError, ModalError

__all__ = ["call_isolated"]

_IN_CHILD = False


def _child(func: Callable, args: tuple, conn, timeout_s: float) -> None:  # pragma: no cover - runs in the child
    global _IN_CHILD
    _IN_CHILD = True
    if hasattr(signal, "alarm"):
        # end on our own shortly after the parent's deadline: if the parent is killed
        # meanwhile (Ctrl-C, a harness timeout), a reader hung in compiled code would
        # otherwise live on as an orphan, spinning for ever (the stress fuzzer left dozens).
        # The default action of SIGALRM ends the process even inside C code.
        signal.signal(signal.SIGALRM, signal.SIG_DFL)
        signal.alarm(int(math.ceil(timeout_s)) + 2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result: tuple = ("ok", func(*args))
        except ModalError as exc:
            result = ("error", exc)
        except BaseException as exc:  # noqa: BLE001 - anything else is a damaged file too
            result = ("error", FormatError(f"{type(exc).__name__}: {exc}"))
    conn.send(result + ([(str(w.message), w.category) for w in caught],))
    conn.close()


def call_isolated(func: Callable[..., Any], args: tuple, src: str, what: str, timeout_s: float = 120.0) -> Any:
    """``func(*args)`` in a forked child; its result, or a FormatError naming ``src``."""
    if _IN_CHILD or "fork" not in multiprocessing.get_all_start_methods():
        return func(*args)
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(func, args, child, timeout_s), daemon=True)
    proc.start()
    child.close()
    try:
        if not parent.poll(timeout_s):
            proc.kill()
            raise FormatError(f"{src}: reading the {what} did not finish in {timeout_s:g} s; the file is probably "
                              "damaged (the library reading it loops)")
        status, payload, caught = parent.recv()
    except EOFError:
        status, payload, caught = "crashed", None, []
    finally:
        parent.close()
        proc.join(5)
    for message, category in caught:
        warnings.warn(message, category, stacklevel=3)
    if status == "ok":
        return payload
    if status == "error":
        raise payload
    raise FormatError(f"{src}: damaged {what}: the library reading it crashed (exit code {proc.exitcode})")
