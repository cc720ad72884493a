"""Fit one FRF file (or several files on one axis) with the options of ``modal fit``.

The one place where a path and the command line's fit options become FRF + identification
results: :mod:`modal.cli` (``modal fit``) and :mod:`modal.batch` (``modal batch``, on Dask
workers) both call :func:`fit_path`, so a file gives the same numbers either way.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

from .errors import ModalError, ParameterError
from .validate import one_of

__all__ = ["FitOptions", "FitOutput", "fit_path", "READ_HINTS", "GLOBAL_OPTIONS"]

#: read_frf hints that the command line exposes (same names as options)
READ_HINTS = ("kind", "frequency_axis", "frequency_step", "frequency_start", "layout", "delimiter", "decimal", "dataset")
#: options of method "global" only
GLOBAL_OPTIONS = ("modes_hz", "order", "max_order")
_METHODS = ("auto", "nls", "circle", "halfpower", "global", "all")


@dataclass(frozen=True)
class FitOptions:
    """What ``modal fit`` does with a file, as plain values (picklable, hashable into a settings key).

    Attributes
    ----------
    method : str
        ``"auto"`` (default), ``"nls"``, ``"circle"``, ``"halfpower"``, ``"global"`` or ``"all"``
        (the three band-wise methods).
    bands_hz : tuple of (float, float), optional
        One fitting band per mode, Hz (``--band``).
    modes_hz, order, max_order
        Options of method ``"global"`` (choosing it under ``"auto"``).
    max_evaluations : int, optional
        Model evaluations the least-squares refinement may take (each method's: ``"circle"`` and ``"halfpower"``
        the refinement that checks them; ``"all"``: each of its fits); default scaled to the problem
        (:mod:`modal.work_budget`).
    driving_point : tuple of str, optional
        Driving-point channels: numbers counted from 1 or response point ids (:func:`driving_channels`).
    kind, frequency_axis, frequency_step, frequency_start, layout, delimiter, decimal, dataset
        Read hints (:func:`modal.read_frf`); ``frequency_step`` and ``frequency_start`` in Hz.
    excitation, response, impact, estimator, window, exponential_decay_s, segment_length, overlap
        Time-data options: a time file is turned into FRFs first (:mod:`modal.time_frf`).
    oma : OMAOptions, optional
        Records of responses only (``modal batch --oma``): each file's modes by operational analysis
        (:func:`modal.operational.files.oma_file`) with these options instead of a fit of FRFs.
    """

    method: str = "auto"
    bands_hz: tuple[tuple[float, float], ...] | None = None
    modes_hz: tuple[float, ...] | None = None
    order: int | None = None
    max_order: int | None = None
    max_evaluations: int | None = None
    driving_point: tuple[str, ...] | None = None
    kind: str | None = None
    frequency_axis: str | None = None
    frequency_step: float | None = None
    frequency_start: float | None = None
    layout: str | None = None
    delimiter: str | None = None
    decimal: str | None = None
    dataset: int | None = None
    excitation: str | None = None
    response: tuple[str, ...] | None = None
    impact: bool = False
    estimator: str | None = None
    window: str | None = None
    exponential_decay_s: float | None = None
    segment_length: int | None = None
    overlap: float | None = None
    oma: Any = None

    def __post_init__(self) -> None:
        one_of("method", self.method, _METHODS)
        if self.oma is not None:
            from .operational.files import OMAOptions

            if not isinstance(self.oma, OMAOptions):
                raise ParameterError(f"'oma' is {self.oma!r}; expected modal.operational.files.OMAOptions")
        budget = self.max_evaluations
        if budget is not None and (isinstance(budget, bool) or not isinstance(budget, int) or budget < 1):
            raise ParameterError(f"--max-evaluations {budget}: expected a whole number of model evaluations >= 1")
        given = [name for name in GLOBAL_OPTIONS if getattr(self, name) is not None]
        if given and self.method not in ("auto", "global"):
            raise ParameterError(f"--{given[0].replace('_', '-')} applies to --method global only")
        for name in ("bands_hz", "modes_hz", "driving_point", "response"):  # lists in, tuples kept (hashable)
            value = getattr(self, name)
            if value is not None and not isinstance(value, tuple):
                object.__setattr__(self, name, tuple(tuple(v) if name == "bands_hz" else v for v in value))
        if self.bands_hz is not None:
            object.__setattr__(self, "bands_hz", tuple((float(a), float(b)) for a, b in self.bands_hz))

    @classmethod
    def from_args(cls, args: Any) -> "FitOptions":
        """From an ``argparse`` namespace of ``modal fit`` / ``modal batch`` (``--band`` → ``bands_hz``)."""
        values = {f.name: getattr(args, f.name, None) for f in dataclasses.fields(cls) if f.name != "bands_hz"}
        values["bands_hz"] = getattr(args, "band", None)
        values["impact"] = bool(values["impact"])
        values["method"] = values["method"] or "auto"
        values["oma"] = _oma_from_args(args) if getattr(args, "oma", False) else None
        if values["oma"] is not None:  # the fit options that became the operational ones
            values.update(bands_hz=None, max_order=None)
        return cls(**values)

    @classmethod
    def from_kwargs(cls, **options: Any) -> "FitOptions":
        """From keyword arguments named as the attributes; an unknown name is a :class:`ParameterError`."""
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(options) - names)
        if unknown:
            raise ParameterError(f"unknown fit option(s) {', '.join(unknown)}; expected some of {', '.join(sorted(names))}")
        return cls(**options)

    def settings(self) -> dict[str, Any]:
        """The options that were given (not None / False), JSON-ready."""
        out = {}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None or value is False:
                continue
            if f.name == "oma":
                out["oma"] = value.settings()
                continue
            out[f.name] = [list(v) if isinstance(v, tuple) else v for v in value] if isinstance(value, tuple) else value
        return out

    def settings_json(self) -> str:
        """Canonical JSON of :meth:`settings` with the toolkit version (what a result depends on)."""
        from ._version import __version__

        return json.dumps({"options": self.settings(), "modalbal": __version__}, sort_keys=True)

    def settings_hash(self) -> str:
        """SHA-256 (hex) of :meth:`settings_json`."""
        return hashlib.sha256(self.settings_json().encode()).hexdigest()

    def hints(self) -> dict[str, Any]:
        """The read hints that were given."""
        return {k: getattr(self, k) for k in READ_HINTS if getattr(self, k) is not None}

    def namespace(self) -> SimpleNamespace:
        """The options as the attribute names of the command line (for :func:`modal.time_frf.frf_from_time`)."""
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        values["response"] = list(self.response) if self.response is not None else None
        values["band"] = self.bands_hz
        return SimpleNamespace(**values)


@dataclass(frozen=True)
class FitOutput:
    """What :func:`fit_path` returns.

    Attributes
    ----------
    frf : FRF or None
        The FRF that was fitted (an :class:`~modal.estimate.EstimatedFRF` from time data); None for
        operational analysis (``options.oma``), which identifies from the responses directly.
    results : tuple of IdentificationResult
        One per method that ran (``result.method`` says which ``"auto"`` chose).
    time_data : tuple or None
        ``(record, inputs, outputs)`` when the file held time data, for plots.
    """

    frf: Any
    results: tuple
    time_data: tuple | None = None


def fit_path(path: str | os.PathLike | Sequence[str | os.PathLike], options: FitOptions,
             report_estimate=None, report=None) -> FitOutput:
    """Read an FRF (or time) file and identify its modes, as ``modal fit`` does.

    Parameters
    ----------
    path : path-like or sequence of path-likes
        One file, or several FRF files on one frequency axis (one multi-channel FRF), or several
        time files: takes of one test (the same channels), estimated as one, or a roving-hammer test
        (one hit point per file), each point estimated and the FRFs joined (``settings["roving_hammer"]``
        says what their errors share).
    options : FitOptions
    report_estimate : callable, optional
        Called with the estimate when the file held time data (the command line prints a line).
    report : callable, optional
        Called with a one-line note on how a time file was read (the command line prints it).

    Returns
    -------
    FitOutput

    Raises
    ------
    ModalError
        Unreadable file or failed identification (the message names the file).
    """
    from .time_frf import frf_from_time, wants_time
    from .identify import identify
    from .io import read_frf

    paths = [path] if isinstance(path, (str, os.PathLike)) else list(path)
    if options.oma is not None:
        from .operational.files import oma_file

        if len(paths) != 1:
            raise ParameterError(f"operational analysis takes one time file at a time; got {len(paths)}")
        return FitOutput(frf=None, results=(oma_file(paths[0], options.oma),))
    args = options.namespace()
    time_data = None
    if any(wants_time(args, p) for p in paths):  # several time files are takes of one test
        frf, *record = frf_from_time(paths[0] if len(paths) == 1 else paths, args, report)
        time_data = tuple(record)
        if record[0] is not None:  # a roving-hammer test hands its points' estimates, no one record
            _check_bands_below_nyquist(options.bands_hz, record[0])
        if report_estimate is not None:
            report_estimate(frf)
    else:
        frf = read_frf(paths[0] if len(paths) == 1 else paths, **options.hints())
    methods = ["nls", "circle", "halfpower"] if options.method == "all" else [options.method]
    global_options = {k: getattr(options, k) for k in GLOBAL_OPTIONS if getattr(options, k) is not None}
    if global_options and methods == ["auto"]:
        methods = ["global"]  # options of the global method choose it
    if global_options:
        global_options = {k: list(v) if isinstance(v, tuple) else v for k, v in global_options.items()}
    driving = driving_channels(frf, options.driving_point) if options.driving_point else None
    bands = [list(b) for b in options.bands_hz] if options.bands_hz is not None else None
    budget = {} if options.max_evaluations is None else {"max_evaluations": options.max_evaluations}
    results = tuple(identify(frf, method, bands_hz=bands, driving_point=driving,
                             **(global_options if method == "global" else {}),
                             **budget)
                    for method in methods)
    from .roving import RovingEstimate

    if isinstance(frf, RovingEstimate):  # what the hit points' estimates shared, and what they could not
        results = tuple(dataclasses.replace(r, settings={**r.settings, "roving_hammer": frf.join_note})
                        for r in results)
    return FitOutput(frf=frf, results=results, time_data=time_data)


def _check_bands_below_nyquist(bands_hz, record) -> None:
    """A band wholly above half a time record's sample rate: the rate (or the band) is in the wrong unit."""
    nyquist = record.sample_rate_hz / 2
    for low, high in bands_hz or ():
        if low >= nyquist:
            raise ParameterError(f"{record.source}: --band {low:g} {high:g} Hz lies above the Nyquist frequency "
                                 f"{nyquist:.6g} Hz of the file's sample rate {record.sample_rate_hz:.6g} Hz; expected "
                                 "bands below it (is the file's sample rate in kHz?)")


def _oma_from_args(args: Any):
    """The operational options of ``modal batch --oma``: its ``--band`` (once) and ``--max-order`` with
    ``--rotor-speed-hz`` and ``--reference-channels``; ``--method`` stays ``auto`` (the default, ssi)."""
    from .operational.files import OMAOptions

    bands = getattr(args, "band", None) or []
    if len(bands) > 1:
        raise ParameterError(f"--oma takes one --band FMIN FMAX (the band of interest); got {len(bands)}")
    if (getattr(args, "method", None) or "auto") != "auto":
        raise ParameterError(f"--method {args.method} fits FRFs; --oma identifies from responses with ssi")
    return OMAOptions(band_hz=bands[0] if bands else None, reference_channels=getattr(args, "reference_channels", None),
                      rotor_speed_hz=getattr(args, "rotor_speed_hz", None), max_order=getattr(args, "max_order", None))


def driving_channels(frf, names: Sequence[str], option: str = "--driving-point", where: str | None = None):
    """Boolean mask over the FRF's channels from ``--driving-point`` values: channel numbers counted from 1
    (as the results table numbers them) or response point ids (for an FRF from a time file: the response
    channels' names). ``option`` names the setting and ``where`` (default the FRF's source) starts the
    messages."""
    import numpy as np

    where = f"{frf.source}: " if where is None else where
    n = frf.n_channels
    mask = np.zeros(n, bool)
    points = list(frf.response_points or [])
    listing = f" or a response point id ({', '.join(dict.fromkeys(points))})" if points else ""
    for name in names:
        text = str(name).strip()
        by_point = [k for k, p in enumerate(points) if p == text]
        by_number = int(text) - 1 if text.isdigit() and 1 <= int(text) <= n else None
        if by_number is not None and by_point and by_point != [by_number]:
            raise ModalError(f"{where}{option} {text} is ambiguous: channel {text} is "
                             f"{points[by_number]}, and response point {text} is channel "
                             f"{', '.join(str(k + 1) for k in by_point)}; name the channel by another of its ids")
        if by_point:
            mask[by_point] = True
        elif by_number is not None:
            mask[by_number] = True
        else:
            raise ModalError(f"{where}{option} {text}: no such channel; expected a channel number 1..{n}"
                             f"{listing}")
    return mask
