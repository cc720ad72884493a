"""Batches of FRF files: one fit per file (the same as ``modal fit``), locally or on a Dask cluster,
resumable, into one archive and one table (``python -m modal batch``).

>>> from modal.batch import fit_files                                  # doctest: +SKIP
>>> result = fit_files("survey/", out="survey.h5", method="nls")       # doctest: +SKIP
>>> result.summary()                                                   # doctest: +SKIP
{'files': 120, 'fitted': 118, 'reused': 0, 'failed': [...], 'archive': 'survey.h5', ...}
"""
from .discover import FRF_EXTENSIONS, file_sha256, find_files
from .lock import OutputInUseError
from .records import BatchInfo, FileFit, Outcome
from .run import BatchResult, fit_files, iter_fit
from .store import TABLE_COLUMNS

__all__ = ["fit_files", "iter_fit", "find_files", "file_sha256", "BatchResult", "FileFit", "BatchInfo", "Outcome",
           "TABLE_COLUMNS", "FRF_EXTENSIONS", "OutputInUseError"]
