"""What a batch produces per file and as a whole: plain frozen dataclasses the archive layer stores."""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["FileFit", "BatchInfo", "Entry", "Outcome", "one_line"]


def one_line(exc: BaseException) -> str:
    """An exception as one line: its message with whitespace collapsed (the type's name when the
    error is not one of the toolkit's own, which already name file, field and expectation)."""
    from ..errors import ModalError

    text = " ".join(str(exc).split())
    if isinstance(exc, OSError) and exc.filename is not None:
        text = f"{exc.filename}: {exc.strerror or text}"
    if not isinstance(exc, (ModalError, OSError)):
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text[:500]


@dataclass(frozen=True)
class FileFit:
    """The fit of one file (one group ``/files/<i>`` of a batch archive).

    Attributes
    ----------
    source : str
        The file's path as found by the batch.
    sha256 : str
        SHA-256 (hex) of the file's bytes.
    settings : str
        The fit options and toolkit version, canonical JSON (:meth:`modal.fitting.FitOptions.settings_json`).
    settings_hash : str
        SHA-256 (hex) of ``settings``; with ``sha256`` the key under which a rerun reuses this fit.
    error : str
        One line naming what went wrong; empty when the file was fitted.
    retry : bool
        The failure did not come from the file's content (a lost worker, an unexpected exception,
        an unreadable file): a rerun tries the file again. Failures with the toolkit's own
        errors (unreadable format, failed identification) are kept and reported again.
    kind : str
        FRF kind (``receptance``, ``mobility``, ``accelerance``).
    n_channels, n_lines : int
        Channels and frequency lines of the FRF.
    frequency_range_hz : tuple of float
        First and last line, Hz.
    results : tuple of IdentificationResult
        One per method that ran (modes with standard errors and flags).
    warnings : tuple of str
        Warnings the fit raised (their content is also in the modes' flags).
    fit_time_s : float
        Wall time of reading and fitting on the worker, s.
    table : str
        This file's rows of the batch table as CSV lines, without the ``file`` column
        (kept so that a rerun writes the table without reading every result back).
    take_setup : str
        A time file whose excitation holds one hammer hit: its sample rate and channels (names,
        quantities, units) as one line, the key by which files that look like takes of one test are
        found (:meth:`modal.batch.BatchResult.takes`); empty for every other file.
    """

    source: str
    sha256: str
    settings: str
    settings_hash: str
    error: str = ""
    retry: bool = False
    kind: str = ""
    n_channels: int = 0
    n_lines: int = 0
    frequency_range_hz: tuple[float, float] = (float("nan"), float("nan"))
    results: tuple = ()
    warnings: tuple[str, ...] = ()
    fit_time_s: float = float("nan")
    table: str = ""
    take_setup: str = ""

    @property
    def ok(self) -> bool:
        """True when the file was fitted."""
        return not self.error


@dataclass(frozen=True)
class Entry:
    """What the client of a batch keeps of one file: the outcome, the table rows and where the
    full :class:`FileFit` is stored (a part file or the previous archive), or the fit itself.

    Attributes
    ----------
    source, sha256, error, retry, table, warnings, take_setup
        As in :class:`FileFit`.
    location : tuple of (str, str) or None
        HDF5 file and group holding the :class:`FileFit`.
    fit : FileFit or None
        The fit itself when it is not stored (no archive, or a failure a rerun tries again).
    """

    source: str
    sha256: str
    error: str
    retry: bool
    table: str
    location: tuple[str, str] | None = None
    fit: FileFit | None = None
    warnings: tuple[str, ...] = ()
    take_setup: str = ""


@dataclass(frozen=True)
class BatchInfo:
    """The batch as a whole (group ``/batch`` of a batch archive).

    Attributes
    ----------
    settings : str
        Fit options and toolkit version, canonical JSON.
    settings_hash : str
    n_files, n_fitted, n_reused, n_failed : int
        Files found; fitted in this run; read back from an earlier run; failed
        (``n_files = n_fitted + n_reused + n_failed``).
    failed_files, failed_errors : tuple of str
        The failed files and their one-line errors, in the same order.
    wall_time_s : float
        Wall time of the run, s.
    """

    settings: str
    settings_hash: str
    n_files: int
    n_fitted: int
    n_reused: int
    n_failed: int
    failed_files: tuple[str, ...] = ()
    failed_errors: tuple[str, ...] = ()
    wall_time_s: float = float("nan")


@dataclass(frozen=True)
class Outcome:
    """One file's outcome, as :func:`modal.batch.iter_fit` yields it.

    Attributes
    ----------
    file : str
    status : str
        ``"fitted"`` (in this run), ``"reused"`` (from an earlier run) or ``"failed"``.
    error : str
        One line; empty unless failed.
    rows : tuple of dict
        This file's rows of the batch table (:data:`modal.batch.TABLE_COLUMNS`; NaN where not defined).
    fit : FileFit or None
        The whole result (modes with all fields) when the batch writes no archive (``out=None``);
        with an archive, read it from there: ``read_archive(out)["files"]``.
    warnings : tuple of str
        The warnings the file's fit raised (one line each), as ``modal fit`` prints them.
    take_setup : str
        As in :class:`FileFit`: set for a time file of one hammer hit.
    sha256 : str
        SHA-256 (hex) of the file's bytes (empty when it could not be read).
    """

    file: str
    status: str
    error: str
    rows: tuple[dict, ...] = field(default=(), repr=False)
    fit: FileFit | None = field(default=None, repr=False)
    warnings: tuple[str, ...] = field(default=(), repr=False)
    take_setup: str = field(default="", repr=False)
    sha256: str = field(default="", repr=False)
