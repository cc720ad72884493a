"""Batches of FRF files: one fit per file (the same as ``modal fit``), locally or on a Dask cluster,
resumable, into one archive and one table (``python -m modal batch``).

>>> from modal.batch import fit_files                                  # doctest: +SKIP
>>> result = fit_files("survey/", out="survey.h5", method="nls")       # doctest: +SKIP
>>> result.summary()                                                   # doctest: +SKIP
{'files': 120, 'fitted': 118, 'reused': 0, 'failed': [...], 'archive': 'survey.h5', ...}
"""
from __future__ import annotations

import importlib

__all__ = ["fit_files", "iter_fit", "find_files", "file_sha256", "BatchResult", "FileFit", "BatchInfo", "Outcome",
           "TABLE_COLUMNS", "FRF_EXTENSIONS", "OutputInUseError"]

#: the module of each public name, imported when the name is first used: every ``modal`` command builds
#: the batch command's parser (modal.batch.cli), and importing the package for it loaded the batch
#: runner, its archive store and h5py, which ``modal fit`` without an archive never uses
_HOME = {"FRF_EXTENSIONS": "discover", "file_sha256": "discover", "find_files": "discover",
         "OutputInUseError": "lock", "BatchInfo": "records", "FileFit": "records", "Outcome": "records",
         "BatchResult": "run", "fit_files": "run", "iter_fit": "run", "TABLE_COLUMNS": "store"}


def __getattr__(name: str):
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *_HOME})
