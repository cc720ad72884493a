"""Bytecode caching for a test run whose environment forbids writing it (PYTHONDONTWRITEBYTECODE).

The variable keeps ``__pycache__`` folders out of the sources, but it also makes every CLI subprocess,
plotting process and xdist worker of the run compile the toolkit's sources again: ``import modal.cli``
costs 0.37 CPU-s compiling against 0.20 s cached, and a worker's collection (with the assertion rewriting
of every test file) 10-11 against 5 CPU-s. The run caches bytecode under a folder of its own in the
temporary directory instead (PYTHONPYCACHEPREFIX): the checkout stays as clean as the variable keeps it.
"""
from __future__ import annotations

import os
from collections.abc import MutableMapping

__all__ = ["cache_outside_the_checkout"]


def cache_outside_the_checkout(environ: MutableMapping[str, str], temporary: str) -> str | None:
    """Swap PYTHONDONTWRITEBYTECODE in ``environ`` for a bytecode cache folder under ``temporary``.

    Returns the folder (for the running process's ``sys.pycache_prefix``), or None where nothing changes:
    the variable is not set, or PYTHONPYCACHEPREFIX already names a cache folder (kept as given).
    """
    if not environ.get("PYTHONDONTWRITEBYTECODE") or environ.get("PYTHONPYCACHEPREFIX"):
        return None
    prefix = os.path.join(temporary, f"modalbal-pycache-{os.getuid()}")
    del environ["PYTHONDONTWRITEBYTECODE"]
    environ["PYTHONPYCACHEPREFIX"] = prefix
    return prefix
