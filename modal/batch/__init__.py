"""Batches of FRF files: one fit per file (the same as ``modal fit``), locally or on a Dask cluster,
resumable, into one archive and one table (``python -m modal batch``).

>>> from modal.batch import fit_files                                  # doctest: +SKIP
>>> result = fit_files("survey/", out="survey.h5", method="nls")       # doctest: +SKIP
>>> result.summary()                                                   # doctest: +SKIP
{'files': 120, 'fitted': 118, 'reused': 0, 'failed': [...], 'archive': 'survey.h5', ...}
"""
from __future__ import annotations

from ..lazy import lazy_names

__all__ = ["fit_files", "iter_fit", "find_files", "file_sha256", "BatchResult", "FileFit", "BatchInfo", "Outcome",
           "TABLE_COLUMNS", "FRF_EXTENSIONS", "OutputInUseError"]

#: the module of each public name, imported when the name is first used: every ``modal`` command builds
#: the batch command's parser (modal.batch.cli), and importing the package for it loaded the batch
#: runner, its archive store and h5py, which ``modal fit`` without an archive never uses
_HOME = {"FRF_EXTENSIONS": "discover", "file_sha256": "discover", "find_files": "discover",
         "OutputInUseError": "lock", "BatchInfo": "records", "FileFit": "records", "Outcome": "records",
         "BatchResult": "run", "fit_files": "run", "iter_fit": "run", "TABLE_COLUMNS": "store"}


__getattr__, __dir__ = lazy_names(__name__, _HOME)
