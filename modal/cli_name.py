"""The name a command line goes by in its usage and help: ``python -m modal`` when started so, the console
script's own name (``modalbal``, ``modalbal-scene``) when started by it."""
from __future__ import annotations

import os
import sys

__all__ = ["program_name"]


def program_name(module: str, argv: list[str] | None = None) -> str:
    """The program's name as the user typed it.

    Parameters
    ----------
    module : str
        The package run by ``python -m`` (``"modal"``, ``"balancer"``).
    argv : list of str, optional
        The arguments ``main`` was given: a caller passing them (tests, scripts) gets ``python -m MODULE``;
        only the process's own command line (None) is read from ``sys.argv[0]``.

    Returns
    -------
    str
        ``python -m MODULE``, or the basename of the console script that started the process.
    """
    default = f"python -m {module}"
    if argv is not None or not sys.argv or not sys.argv[0]:
        return default
    name = os.path.basename(sys.argv[0])
    if name.endswith(".py") or name.startswith("-"):  # python -m (argv[0] is __main__.py) or python -c
        return default
    return name
