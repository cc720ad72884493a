"""Reading and writing measured FRFs: UFF 58/58b, CSV, MATLAB .mat and HDF5.

:func:`read_frf` looks at a file's bytes (not only its name) to pick the reader;
:func:`write_frf` picks the writer from the extension or ``format=``. Every
reader turns a bad file into one :class:`~modal.errors.FormatError` whose
message names the file, the field or line, and what was expected; every writer
writes a temporary file beside the target and renames it (no half-written files).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FormatError
from ..frf import FRF
from ._common import check_file, check_hints, refuse_copies, source_name

__all__ = ["read_frf", "write_frf", "sniff_format", "WRITE_FORMATS"]

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
#: Formats :func:`write_frf` knows, and the extensions that select them.
WRITE_FORMATS = ("uff58", "uff58b", "csv", "mat", "mat73", "hdf5")
_EXTENSIONS = {
    ".uff": "uff58", ".unv": "uff58", ".csv": "csv", ".txt": "csv", ".mat": "mat",
    ".h5": "hdf5", ".hdf5": "hdf5",
}
_FORMAT_ALIASES = {
    "uff": "uff58", "unv": "uff58", "uff58": "uff58", "58": "uff58", "uff58a": "uff58",
    "uff58b": "uff58b", "58b": "uff58b", "csv": "csv", "mat": "mat", "mat5": "mat", "mat7": "mat",
    "mat73": "mat73", "mat7.3": "mat73", "hdf5": "hdf5", "h5": "hdf5",
}


def sniff_format(path: str | os.PathLike) -> str:
    """What a file holds, from its first bytes.

    Returns
    -------
    str
        ``"mat73"`` (HDF5 with a MATLAB user block), ``"hdf5"``, ``"mat5"``
        (MATLAB 5.0/7 header), ``"uff"`` (first non-blank line is ``-1``),
        ``"binary"`` (NUL bytes, none of the above) or ``"text"``.
    """
    with open(path, "rb") as fh:
        head = fh.read(2056)
    hdf5_at = next((off for off in (0, 512, 1024, 2048) if head[off:off + 8] == HDF5_SIGNATURE), None)
    if hdf5_at is not None:
        return "mat73" if head.startswith(b"MATLAB") and hdf5_at > 0 else "hdf5"
    if head.startswith(b"MATLAB 5.0 MAT-file"):
        return "mat5"
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):  # UTF-16 text (some Windows exporters)
        return "text"
    first = next((ln.strip() for ln in head.split(b"\n") if ln.strip()), b"")
    if first == b"-1":
        return "uff"
    if b"\x00" in head:
        return "binary"
    return "text"


def _read_one(path: str | os.PathLike, hints: dict[str, Any]) -> FRF:
    src = source_name(path)
    check_file(path)
    kind = sniff_format(path)
    if kind in ("hdf5",):
        from .hdf5 import read_frf_hdf5
        return read_frf_hdf5(path, **hints)
    if kind in ("mat5", "mat73"):
        from .mat import read_frf_mat
        return read_frf_mat(path, **hints)
    if kind == "uff":
        from .uff import read_frf_uff
        return read_frf_uff(path, **hints)
    if kind == "binary":
        if Path(path).suffix.lower() == ".mat":  # MATLAB v4 has no header: let scipy try
            from .mat import read_frf_mat
            return read_frf_mat(path, **hints)
        raise FormatError(
            f"{src}: byte 0: binary content of no known kind; expected UFF 58/58b (first line '    -1'), "
            "MATLAB .mat, HDF5 or CSV/text"
        )
    from .csv import read_frf_csv
    return read_frf_csv(path, **hints)


def read_frf(path: str | os.PathLike | Sequence[str | os.PathLike], **hints: Any) -> FRF:
    """Read an FRF file, choosing the reader from the file's content.

    Parameters
    ----------
    path : path-like, or a sequence of them
        One file, or several files on the same frequency axis whose channels are
        combined (in the given order) into one multi-channel FRF.
    **hints
        What the file cannot say, used where they apply:

        ``kind``
            ``"receptance"``, ``"mobility"`` or ``"accelerance"``; required when
            the file does not state it (never guessed); an error if it contradicts the file.
        ``frequency_axis``
            Unit of a text frequency column (``"hz"``, ``"khz"``, ``"rad/s"``, ``"cpm"``, ``"rpm"``).
        ``frequency_hz`` / ``frequency_step``, ``frequency_start``
            The lines of a file that stores none (e.g. one complex column).
        ``variables``
            MAT variable names, ``{"frequency": ..., "response": ...}``.
        ``layout``, ``delimiter``, ``decimal``
            Text layout (``"re_im"``, ``"mag_deg"``, ``"db_deg"``, ``"complex"``...), column
            delimiter and decimal mark (``","`` for a decimal comma).
        ``dataset``
            UFF: the dataset number(s) to read, 1-based over all datasets of the file as
            in the error messages (an int or a list); HDF5: the group name under ``/frf``.
        ``response_points``, ``reference_points``, ``units``
            Override or supply point ids and the response unit.

    Returns
    -------
    FRF
        ``source`` is the path as given. One channel gives a 1-D ``response``.

    Raises
    ------
    FormatError
        The file cannot be read as an FRF; the message names the file, the field
        or line, and what was expected.
    FRFValidationError
        The data are not a valid FRF (e.g. duplicate frequency lines).
    TypeError
        An unknown hint name.
    """
    check_hints(hints)
    if isinstance(path, (str, os.PathLike)):
        return _read_one(path, hints)
    paths = list(path)
    if not paths:
        raise FormatError("read_frf: an empty list of files; expected at least one path")
    refuse_copies(paths, "files combined on one axis", "a file given twice gives its channels twice")
    per_file = {k: v for k, v in hints.items() if k not in ("response_points", "reference_points", "units")}
    frfs = [_read_one(p, per_file) for p in paths]
    return _combine(frfs, paths, hints)


def _combine(frfs: list[FRF], paths: list, hints: dict[str, Any]) -> FRF:
    """Channels of several files on one frequency axis, as one FRF."""
    from ._common import build_frf

    first = frfs[0]
    for p, f in zip(paths[1:], frfs[1:]):
        src = source_name(p)
        if f.kind != first.kind:
            raise FormatError(f"{src}: kind {f.kind}; expected {first.kind} like {source_name(paths[0])}")
        if f.units != first.units:
            raise FormatError(f"{src}: units {f.units!r}; expected {first.units!r} like {source_name(paths[0])}")
        if f.n_freq != first.n_freq or not np.array_equal(f.frequency_hz, first.frequency_hz):
            raise FormatError(
                f"{src}: frequency axis ({f.n_freq} lines, {f.frequency_hz[0]}–{f.frequency_hz[-1]} Hz) differs "
                f"from {source_name(paths[0])} ({first.n_freq} lines, {first.frequency_hz[0]}–"
                f"{first.frequency_hz[-1]} Hz); expected one shared axis to combine the files"
            )
        if (f.exponential_decay_s or 0.0) != (first.exponential_decay_s or 0.0):
            def window(frf):
                return (f"an exponential window of {frf.exponential_decay_s:g} s" if frf.exponential_decay_s
                        else "no exponential window")
            raise FormatError(f"{src}: estimated with {window(f)} where {source_name(paths[0])} has {window(first)}; "
                              "expected one window for FRFs fitted together (its damping is taken out of every pole)")
    resp = np.concatenate([f.channels for f in frfs], axis=0)

    def joined(attr):
        ids = [getattr(f, attr) for f in frfs]
        return None if any(i is None for i in ids) else tuple(x for i in ids for x in i)

    frf = build_frf(first.frequency_hz, resp, first.kind, " + ".join(source_name(p) for p in paths),
                    response_points=joined("response_points"), reference_points=joined("reference_points"),
                    units=first.units, hints=hints)
    return _with_estimates(frf, frfs)


def _with_estimates(frf: FRF, frfs: list[FRF]) -> FRF:
    """The combined FRF with what the files' estimates knew of their errors: the exponential window (one for all,
    checked by the caller), each line's noise (where every file has it) and the noise model (where every file has
    one of the same lag window: the first file's line correlation for all, the fewest averages, no variance model,
    which is fitted per channel)."""
    from dataclasses import replace

    from ..noise_model import NoiseModel

    noise = [f.noise_std for f in frfs]
    noise_std = None
    if all(n is not None for n in noise):
        noise_std = np.concatenate([np.atleast_2d(n) for n in noise], axis=0)  # each already in the SI unit
    models = [f.noise_model for f in frfs]
    model = None
    if all(m is not None for m in models):
        lag = [None if m.lag_window is None else m.lag_window.shape for m in models]
        if len(set(lag)) == 1 and len({m.sample_interval_s for m in models}) == 1:
            first = models[0]
            correlation = first.line_correlation if all(m.line_correlation is not None for m in models) else None
            model = NoiseModel(averages=min(m.averages for m in models),
                               degrees_of_freedom=min(m.degrees_of_freedom for m in models),
                               line_correlation=correlation, lag_window=first.lag_window,
                               sample_interval_s=first.sample_interval_s)
    return replace(frf, noise_std=noise_std, exponential_decay_s=frfs[0].exponential_decay_s, noise_model=model)


def write_frf(frf: FRF, path: str | os.PathLike, format: str | None = None) -> None:
    """Write an FRF, atomically (temporary file beside the target, then rename).

    Parameters
    ----------
    frf : FRF
    path : path-like
    format : str, optional
        One of :data:`WRITE_FORMATS`: ``"uff58"`` (ASCII dataset 58), ``"uff58b"``
        (binary), ``"csv"`` (canonical CSV), ``"mat"`` (MATLAB v5/v7), ``"mat73"``
        (MATLAB v7.3, HDF5), ``"hdf5"`` (archive layout). Default: from the
        extension (.uff/.unv → uff58, .csv/.txt → csv, .mat → mat, .h5/.hdf5 → hdf5).

    Raises
    ------
    FormatError
        Unknown format or extension.
    """
    if not isinstance(frf, FRF):
        raise TypeError(f"write_frf() expects an FRF, got {type(frf).__name__}")
    if format is None:
        ext = Path(path).suffix.lower()
        if ext not in _EXTENSIONS:
            raise FormatError(
                f"{source_name(path)}: extension {ext or '(none)'!r} does not name a format; expected one of "
                f"{', '.join(sorted(_EXTENSIONS))} or format= one of {', '.join(WRITE_FORMATS)}"
            )
        fmt = _EXTENSIONS[ext]
    else:
        fmt = _FORMAT_ALIASES.get(str(format).lower())
        if fmt is None:
            raise FormatError(
                f"{source_name(path)}: format={format!r} is unknown; expected one of {', '.join(WRITE_FORMATS)}"
            )
    if fmt == "csv":
        from .csv import write_frf_csv
        write_frf_csv(frf, path)
    elif fmt in ("uff58", "uff58b"):
        from .uff import write_frf_uff
        write_frf_uff(frf, path, binary=fmt == "uff58b")
    elif fmt in ("mat", "mat73"):
        from .mat import write_frf_mat
        write_frf_mat(frf, path, version="7.3" if fmt == "mat73" else "5")
    else:
        from .hdf5 import write_frf_hdf5
        write_frf_hdf5(frf, path)
