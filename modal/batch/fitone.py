"""Read and fit one file as ``modal fit`` does, never raising for a bad file: the unit of work of a
batch, run in a fitting process (:mod:`modal.batch.fitproc`) or in the caller's."""
from __future__ import annotations

import time
import warnings

from ..errors import ModalError
from ..fitting import FitOptions, fit_path
from .discover import file_sha256
from .records import FileFit, one_line
from .store import table_text

__all__ = ["fit_one", "take_setup"]


def fit_one(path: str, options: FitOptions, sha256: str | None = None) -> FileFit:
    """Fit one file as ``modal fit`` does; never raises for a bad file.

    Parameters
    ----------
    path : str
    options : FitOptions
    sha256 : str, optional
        The hash the caller computed when it found the file; the file is hashed again here, before and
        after the fit. A file whose bytes differ from the caller's hash, or change during the fit, is
        still being written (a recorder or a copy not finished) or was replaced: it fails, to be tried
        again by a rerun, rather than fitting a record cut short.

    Returns
    -------
    FileFit
        With ``error`` set (one line) when the file could not be read or fitted.
    """
    settings, settings_hash = options.settings_json(), options.settings_hash()
    start = time.perf_counter()
    found = sha256
    try:
        sha256 = file_sha256(path)
    except OSError as exc:
        return FileFit(source=path, sha256=sha256 or "", settings=settings, settings_hash=settings_hash,
                       error=one_line(exc), retry=True)
    if found and found != sha256:
        return _changed(path, sha256, settings, settings_hash, "since the batch found it")
    fitted = _fit(path, options, sha256, settings, settings_hash, start)
    try:
        after = file_sha256(path)
    except OSError as exc:
        return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                       error=one_line(exc), retry=True)
    return fitted if after == sha256 else _changed(path, sha256, settings, settings_hash, "while it was fitted")


def _changed(path, sha256, settings, settings_hash, when) -> FileFit:
    return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash, retry=True,
                   error=f"{path}: its bytes changed {when} (still being written, or replaced?); expected a "
                         "finished file: run the batch again once it is (the rerun fits it)")


def _fit(path: str, options: FitOptions, sha256: str, settings, settings_hash, start) -> FileFit:
    """The fit of a file of bytes ``sha256`` (see :func:`fit_one`)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            out = fit_path(path, options)
        except ModalError as exc:  # the file's verdict: kept for reruns of the same content
            return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                           error=one_line(exc), fit_time_s=time.perf_counter() - start)
        except MemoryError as exc:  # past the fitting process's memory budget (the worker's memory limit)
            return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                           error=f"{path}: out of memory ({one_line(exc)}); a file may use the worker's memory "
                                 "limit at most", retry=True, fit_time_s=time.perf_counter() - start)
        except Exception as exc:  # noqa: BLE001 - per-file failures are data; a rerun tries again
            return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash,
                           error=one_line(exc), retry=True, fit_time_s=time.perf_counter() - start)
    frf = out.frf
    texts = tuple(dict.fromkeys(" ".join(str(w.message).split()) for w in caught))
    if frf is None:  # operational analysis: no FRF, the band of interest and no lines
        first = out.results[0]
        shape = dict(kind=first.kind, n_channels=int(first.n_channels), n_lines=0,
                     frequency_range_hz=tuple(float(f) for f in first.settings["band_hz"]))
    else:
        shape = dict(kind=frf.kind, n_channels=int(frf.n_channels), n_lines=int(frf.n_freq),
                     frequency_range_hz=(float(frf.frequency_hz[0]), float(frf.frequency_hz[-1])))
    return FileFit(source=path, sha256=sha256, settings=settings, settings_hash=settings_hash, **shape,
                   results=tuple(out.results), warnings=texts, fit_time_s=time.perf_counter() - start,
                   table=table_text(out.results), take_setup=take_setup(out.time_data))


def take_setup(time_data) -> str:
    """A time record whose one excitation channel holds one hammer hit: its sample rate and channels as one line
    (files that agree on it look like takes of one test); empty for anything else (FRF files, several hits,
    continuous excitation)."""
    from ..estimate.hits import pulse_train

    if time_data is None or time_data[0] is None:  # an FRF file, or a roving test's joined estimates
        return ""
    record, inputs, _ = time_data
    if len(inputs) != 1 or len(record.take_lengths or ()) > 1:
        return ""
    train = pulse_train(record.signals[inputs[0]], record.sample_rate_hz)
    if not (train.impulsive and train.count == 1):
        return ""
    channels = "; ".join(f"{n} [{q or 'unknown'}, {u or 'no unit'}]"
                         for n, q, u in zip(record.names, record.quantities, record.units))
    return f"{float(record.sample_rate_hz)!r} Hz, excitation {inputs[0] + 1}: {channels}"
