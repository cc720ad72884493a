"""A command line's ``main`` run in the test's own process, with what a subprocess would give back.

A subprocess pays Python, numpy and the package's imports again (0.3-1.5 CPU-s a call); where a test's
point is the exit code and the messages, ``main(argv)`` in-process gives the same: the console scripts
and ``python -m`` call that function. Each entry point keeps real subprocess tests of its own
(tests/modal/test_cli.py, tests/test_first_use.py, tests/test_readme_walkthrough.py,
tests/balancer/influence/test_cli.py).
"""
from __future__ import annotations

import contextlib
import io
import os
import subprocess
import warnings
from collections.abc import Callable, Sequence


def run_main(main: Callable[[list[str]], int], args: Sequence[object], cwd: str | os.PathLike | None = None,
             program: str = "modal") -> subprocess.CompletedProcess:
    """Call ``main([str(a) for a in args])`` as ``python -m PROGRAM ARGS`` would run it.

    Parameters
    ----------
    main : callable
        The command line's entry function (``modal.cli.main``): takes the arguments, returns the exit code.
    args : sequence
        The arguments, each passed as ``str(arg)``.
    cwd : path-like, optional
        The working directory during the call (restored afterwards).
    program : str
        The module name recorded in the returned ``args``.

    Returns
    -------
    subprocess.CompletedProcess
        ``returncode`` (argparse's exit code on a usage error), ``stdout`` and ``stderr`` as text.

    Notes
    -----
    Warnings are shown as in a fresh interpreter (the suite's ``filterwarnings = error`` would turn the
    command's printed warnings into exceptions); the filters and ``warnings.showwarning``, which ``main``
    replaces, are restored afterwards.
    """
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.ExitStack() as stack:
        stack.enter_context(warnings.catch_warnings())
        warnings.resetwarnings()
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
            warnings.simplefilter("ignore", category)  # the interpreter's default filters
        if cwd is not None:
            stack.enter_context(contextlib.chdir(cwd))
        stack.enter_context(contextlib.redirect_stdout(out))
        stack.enter_context(contextlib.redirect_stderr(err))
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's usage errors and --help
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if not isinstance(exc.code, (int, type(None))):
                print(exc.code, file=err)
    return subprocess.CompletedProcess(["python", "-m", program, *argv], int(code), out.getvalue(), err.getvalue())


def run_module(program: str, *args: object, cwd: str | os.PathLike | None = None) -> subprocess.CompletedProcess:
    """``python -m PROGRAM ARGS`` in this process: :func:`run_main` with that program's ``main``.

    Parameters
    ----------
    program : {"modal", "balancer"}
        The package whose command line runs (``modal.cli.main`` or ``balancer.cli.main``).
    *args : object
        The arguments, each passed as ``str(arg)``.
    cwd : path-like, optional
        The working directory during the call.

    Returns
    -------
    subprocess.CompletedProcess
        As :func:`run_main` returns it.
    """
    import balancer.cli
    import modal.cli

    main = {"modal": modal.cli.main, "balancer": balancer.cli.main}[program]
    return run_main(main, args, cwd=cwd, program=program)
