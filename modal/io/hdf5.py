"""FRFs in HDF5, in the project's archive layout (NeXus-style ``NXdata`` groups).

Layout of a file written by :func:`write_frf_hdf5`::

    /                  @schema="modalbal-archive" @schema_version="1.0"
                       @software_version=modal.__version__ @created="2026-01-31T12:00:00Z"
    /frf/<name>/       @NX_class="NXdata" @signal="response" @axes="frequency_hz"
                       @kind @response_points @reference_points (string arrays, optional)
        frequency_hz   float64 (n_freq,)               @units="Hz"
        response       complex128 (n_freq,) or (n_channels, n_freq)   @units="m/s^2/N"

A multi-channel group has ``@axes=[".", "frequency_hz"]`` (NeXus: one entry per
dimension, "." for none). h5py stores complex as a compound of ``r`` and ``i``.

:func:`write_frf_group` and :func:`read_frf_group` work on any h5py group, so the
result archive (``modal.archive``) can hold FRFs next to its other groups;
:func:`write_root_attrs` and :func:`check_schema` handle the file-level attributes.
"""
from __future__ import annotations

import os
from dataclasses import replace
from datetime import datetime, timezone
from typing import Any

import numpy as np

from ..errors import FormatError, ModalError
from ..frf import FRF
from ..frf_units import frf_in_si
from ._atomic import atomic_path
from ._common import build_frf, check_file, normalise_kind, resolve_kind, source_name

__all__ = [
    "SCHEMA", "SCHEMA_VERSION", "FRF_GROUP", "write_frf_group", "read_frf_group", "write_root_attrs",
    "check_schema", "write_frf_hdf5", "read_frf_hdf5",
]

SCHEMA = "modalbal-archive"
SCHEMA_VERSION = "1.0"
#: Group under the root that holds one subgroup per FRF.
FRF_GROUP = "frf"
#: seconds a read may take before the file counts as damaged (libhdf5 looping on it)
READ_TIMEOUT_S = 20.0


def _h5py():
    import h5py

    return h5py


def _str_attr(value: Any) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.shape == ():
        return _str_attr(value[()])
    return str(value)


def _str_list(value: Any) -> tuple[str, ...]:
    return tuple(_str_attr(v) for v in np.atleast_1d(value).ravel())


# ------------------------------------------------------------------ groups
def write_frf_group(group, frf: FRF) -> None:
    """Store ``frf`` in an (empty) h5py group as an NXdata group.

    Parameters
    ----------
    group : h5py.Group
        Group to fill: datasets ``frequency_hz`` and ``response`` and the
        attributes listed in the module docstring.
    frf : FRF
    """
    h5py = _h5py()
    single = frf.response.ndim == 1
    fd = group.create_dataset("frequency_hz", data=np.asarray(frf.frequency_hz, dtype=np.float64))
    fd.attrs["units"] = "Hz"
    rd = group.create_dataset("response", data=np.asarray(frf.response, dtype=np.complex128))
    rd.attrs["units"] = frf.units
    group.attrs["NX_class"] = "NXdata"
    group.attrs["signal"] = "response"
    if single:
        group.attrs["axes"] = "frequency_hz"
    else:
        group.attrs["axes"] = np.array([".", "frequency_hz"], dtype=h5py.string_dtype())
    group.attrs["frequency_hz_indices"] = np.int64(0 if single else 1)
    group.attrs["kind"] = frf.kind
    for name in ("response_points", "reference_points"):
        ids = getattr(frf, name)
        if ids is not None:
            group.attrs[name] = np.array(list(ids), dtype=h5py.string_dtype())
    from ..estimate.core import EstimatedFRF

    if isinstance(frf, EstimatedFRF):  # an estimate from time data (modal.estimate_frf)
        _write_estimate(group, frf)
    else:
        _write_known(group, frf, {"noise_std": None}, {"exponential_decay_s": "s"})


#: per-line arrays of an estimate from time data, and their units (None: the FRF's own unit)
_ESTIMATE_ARRAYS = {"coherence": "1", "multiple_coherence": "1", "noise_std": None, "hit_times_s": "s"}
#: numbers of an estimate, and their units
_ESTIMATE_NUMBERS = {"averages": "1", "sample_rate_hz": "Hz", "segment_length": "1", "overlap": "1",
                     "n_inputs": "1", "exponential_decay_s": "s"}


def _write_known(group, frf, arrays: dict, numbers: dict) -> None:
    """The FRF's fields named in ``arrays`` (float64, unit None: the FRF's own) and ``numbers`` that are known."""
    for name, unit in arrays.items():
        value = getattr(frf, name)
        if value is not None and not (name == "hit_times_s" and len(value) == 0):
            ds = group.create_dataset(name, data=np.asarray(value, dtype=np.float64))
            ds.attrs["units"] = frf.units if unit is None else unit
    for name, unit in numbers.items():
        value = getattr(frf, name)
        if value is not None:
            ds = group.create_dataset(name, data=value)
            ds.attrs["units"] = unit


def _write_estimate(group, frf) -> None:
    """Coherence, noise per line and the estimate's settings beside an estimated FRF's response."""
    import json

    _write_known(group, frf, _ESTIMATE_ARRAYS, _ESTIMATE_NUMBERS)
    group.attrs["estimator"] = frf.estimator
    group.attrs["window"] = frf.window
    group.attrs["rejected"] = json.dumps(frf.rejected)
    group.attrs["overloads"] = json.dumps(frf.overloads)
    group.attrs["unrelated"] = json.dumps(frf.unrelated)


def _read_estimate(group, frf: FRF, source: str) -> FRF:
    """An :class:`~modal.estimate.EstimatedFRF` when the group holds an estimate's extras, else ``frf`` with
    its noise per line and window time constant when the group holds them."""
    if "averages" not in group:
        known = {}
        try:
            if "noise_std" in group:
                known["noise_std"] = np.asarray(group["noise_std"][()], float).reshape(np.shape(frf.response))
            if "exponential_decay_s" in group:
                known["exponential_decay_s"] = float(group["exponential_decay_s"][()])
        except (ValueError, TypeError) as exc:
            raise FormatError(f"{source}: group {group.name}: the noise per line cannot be read ({exc}); "
                              "expected an array shaped like 'response'") from None
        return replace(frf, **known) if known else frf
    import json

    from ..estimate import EstimatedFRF

    extras: dict[str, Any] = {}
    try:
        for name in _ESTIMATE_ARRAYS:
            if name in group:
                arr = np.asarray(group[name][()], float)
                if name == "hit_times_s":
                    extras[name] = tuple(float(t) for t in arr.ravel())
                else:
                    extras[name] = arr if name == "multiple_coherence" else arr.reshape(np.shape(frf.response))
        for name in _ESTIMATE_NUMBERS:
            if name in group:
                value = group[name][()]
                extras[name] = int(value) if name in ("averages", "segment_length", "n_inputs") else float(value)
        extras["estimator"] = _str_attr(group.attrs.get("estimator", "H1"))
        extras["window"] = _str_attr(group.attrs.get("window", "rect"))
        extras["rejected"] = json.loads(_str_attr(group.attrs.get("rejected", "[]")))
        extras["overloads"] = json.loads(_str_attr(group.attrs.get("overloads", "[]")))
        extras["unrelated"] = json.loads(_str_attr(group.attrs.get("unrelated", "[]")))
    except (ValueError, TypeError) as exc:
        raise FormatError(f"{source}: group {group.name}: the estimate's coherence or noise cannot be read ({exc}); "
                          "expected arrays shaped like 'response'") from None
    return EstimatedFRF(frequency_hz=frf.frequency_hz, response=frf.response, kind=frf.kind,
                        response_points=frf.response_points, reference_points=frf.reference_points,
                        units=frf.units, source=frf.source, **extras)


def read_frf_group(group, source: str, hints: dict[str, Any] | None = None) -> FRF:
    """Read an FRF written by :func:`write_frf_group`.

    Parameters
    ----------
    group : h5py.Group
    source : str
        File name for messages and ``FRF.source``.
    hints : dict, optional
        ``kind`` (checked against the group's), ``response_points``, ``reference_points``, ``units``.

    Raises
    ------
    FormatError
        A missing dataset or attribute, or a dataset of the wrong type or shape.
    """
    hints = hints or {}
    h5py = _h5py()
    where = f"group {group.name}"
    for name in ("frequency_hz", "response"):
        if name not in group or not isinstance(group[name], h5py.Dataset):
            have = ", ".join(sorted(group.keys())) or "nothing"
            raise FormatError(f"{source}: {where}: no dataset {name!r} (it holds {have}); expected "
                              "datasets 'frequency_hz' and 'response'")
    fds, rds = group["frequency_hz"], group["response"]
    if fds.dtype.kind not in "fiu" or fds.ndim != 1:
        raise FormatError(f"{source}: {where}/frequency_hz: dtype {fds.dtype}, shape {fds.shape}; "
                          "expected a 1-D float64 array")
    if rds.dtype.kind != "c":
        raise FormatError(f"{source}: {where}/response: dtype {rds.dtype}; expected complex128")
    if rds.ndim not in (1, 2) or rds.shape[-1] != fds.shape[0]:
        raise FormatError(f"{source}: {where}/response: shape {rds.shape}; expected ({fds.shape[0]},) or "
                          f"(n_channels, {fds.shape[0]}) to match frequency_hz")
    unit = _str_attr(fds.attrs.get("units", "Hz"))
    if unit.strip().lower() != "hz":
        raise FormatError(f"{source}: {where}/frequency_hz (attribute units): {unit!r}; expected 'Hz'")
    freq = fds[()]
    resp = rds[()]
    if "kind" in group.attrs:
        file_kind = normalise_kind(_str_attr(group.attrs["kind"]), source, f"{where} (attribute kind)")
    else:
        file_kind = None
    kind = resolve_kind(file_kind, hints, source, f"{where} (attribute kind)",
                        why_unknown="the group has no 'kind' attribute")
    points = [(_str_list(group.attrs[n]) if n in group.attrs else None)
              for n in ("response_points", "reference_points")]
    units = _str_attr(rds.attrs["units"]) if "units" in rds.attrs else None
    frf = build_frf(freq, resp, kind, source, response_points=points[0], reference_points=points[1],
                    units=units, hints=hints, squeeze=False)
    return _read_estimate(group, frf, source)


# ------------------------------------------------------------------ files
def write_root_attrs(h5file, created: str | None = None) -> None:
    """Set the archive's root attributes: schema, schema_version, software_version, created.

    ``created`` defaults to now, UTC, as ``YYYY-MM-DDTHH:MM:SSZ``. It is written
    once: a variable-length string overwritten leaves its old bytes in the file's
    global heap, so two archives written a second apart would differ there.
    """
    from .._version import __version__

    h5file.attrs["schema"] = SCHEMA
    h5file.attrs["schema_version"] = SCHEMA_VERSION
    h5file.attrs["software_version"] = __version__
    h5file.attrs["created"] = created or datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def check_schema(h5file, source: str, error: type[Exception] = FormatError) -> str:
    """Check the root attributes; return the schema version.

    Parameters
    ----------
    h5file : h5py.File
    source : str
        File name for messages.
    error : exception class
        Raised on a problem (``FormatError`` for FRF reading; the archive layer
        may pass ``ArchiveError``).

    Raises
    ------
    error
        No or another ``schema``, or a ``schema_version`` whose major number is
        not this program's.
    """
    schema = _str_attr(h5file.attrs["schema"]) if "schema" in h5file.attrs else None
    if schema != SCHEMA:
        raise error(f"{source}: root attribute schema is {schema!r}; expected {SCHEMA!r} "
                    "(not an archive of this toolkit)")
    version = _str_attr(h5file.attrs.get("schema_version", "?"))
    major = version.split(".")[0]
    if major != SCHEMA_VERSION.split(".")[0]:
        raise error(f"{source}: root attribute schema_version is {version!r}, which this program cannot read; "
                    f"expected major version {SCHEMA_VERSION.split('.')[0]} ({SCHEMA_VERSION}); "
                    "a newer modalbal may read it")
    return version


def write_frf_hdf5(frf: FRF, path: str | os.PathLike, name: str = "0") -> None:
    """Write ``frf`` as an archive file with one group ``/frf/<name>``, atomically.

    The file is written under a temporary name beside ``path``, closed,
    reopened and compared with ``frf``, then renamed onto ``path``.
    """
    h5py = _h5py()
    src = source_name(path)

    def verify(tmp) -> None:
        with h5py.File(tmp, "r") as fh:
            check_schema(fh, src)
            back = read_frf_group(fh[FRF_GROUP][name], src)
        expected = frf_in_si(frf)  # as the reader gives it: a unit it knows in SI
        if not (back == expected and back.response.shape == frf.response.shape):
            raise OSError(f"{src}: verification after writing failed; the file was not replaced")

    with atomic_path(path, verify=verify) as tmp:
        with h5py.File(tmp, "w") as fh:
            write_root_attrs(fh)
            write_frf_group(fh.create_group(FRF_GROUP).create_group(name), frf)


def read_frf_hdf5(path: str | os.PathLike, **hints: Any) -> FRF:
    """Read the FRF of an archive file (``dataset=`` names the group if there are several).

    The file is read in a forked child process: libhdf5 can loop forever on a damaged
    file (found by fuzzing), which then ends in a FormatError after ``READ_TIMEOUT_S``
    (a sound file of 1000 channels reads in 0.05 s).
    """
    from ._isolate import call_isolated

    return call_isolated(_read_frf_hdf5_here, (path, hints), source_name(path), "HDF5 file",
                         timeout_s=READ_TIMEOUT_S)


def _read_frf_hdf5_here(path: str | os.PathLike, hints: dict[str, Any]) -> FRF:
    h5py = _h5py()
    src = source_name(path)
    check_file(path)
    try:
        fh = h5py.File(path, "r")
    except OSError as exc:
        raise FormatError(f"{src}: not a readable HDF5 file ({exc}); expected an archive written by modalbal") from None
    with fh:
        try:
            check_schema(fh, src)
            stored = _archive_frfs(fh, h5py)
            if stored is not None:  # a result archive (modal fit --archive, balancer run): FRF items by name
                return _pick_archive_frf(fh, stored, src, hints)
            if FRF_GROUP not in fh or not isinstance(fh[FRF_GROUP], h5py.Group):
                have = ", ".join(sorted(fh.keys())) or "nothing"
                raise FormatError(f"{src}: no group /{FRF_GROUP} (the file holds {have}); expected /{FRF_GROUP}/<name>")
            names = sorted(fh[FRF_GROUP].keys())
            choice = hints.get("dataset")
            if choice is not None:
                if str(choice) not in names:
                    raise FormatError(f"{src}: group /{FRF_GROUP}/{choice} not found; expected one of "
                                      f"{', '.join(names) or '(none)'}")
                name = str(choice)
            elif len(names) == 1:
                name = names[0]
            else:
                raise FormatError(f"{src}: group /{FRF_GROUP} holds {len(names)} FRFs "
                                  f"({', '.join(names) or 'none'}); expected one, or dataset= naming it")
            return read_frf_group(fh[FRF_GROUP][name], src, hints)
        except ModalError:
            raise
        except (OSError, KeyError, RuntimeError, TypeError, ValueError) as exc:  # damaged file or object
            raise FormatError(f"{src}: damaged HDF5 content ({exc}); expected an archive written by modalbal") from None


def _archive_frfs(fh, h5py) -> list[str] | None:
    """Names of the top-level FRF items of a result archive (``@__type__ = "frf"``), or None
    when the file is not a result archive (then it holds ``/frf/<name>`` groups)."""
    def kind(node) -> str:
        value = node.attrs.get("__type__", "")
        return value.decode() if isinstance(value, bytes) else str(value)

    typed = [name for name in fh.keys() if name != "scene" and kind(fh[name])]
    if not typed and "scene" not in fh:
        return None
    return [name for name in typed if kind(fh[name]) == "frf"]


def _pick_archive_frf(fh, names: list[str], src: str, hints: dict[str, Any]) -> FRF:
    if not names:
        held = ", ".join(f"{k} ({_describe(fh[k])})" for k in fh.keys()) or "nothing"
        raise FormatError(f"{src}: this archive holds no FRF (it holds {held}); expected an archive written by "
                          f"'modal fit --archive', 'modal frf --out' or a scene with an [frf] stage")
    choice = hints.get("dataset")
    if choice is not None:
        if str(choice) not in names:
            raise FormatError(f"{src}: archive item {choice!r} is not an FRF; its FRFs are {', '.join(names)}")
        name = str(choice)
    elif len(names) == 1:
        name = names[0]
    else:
        raise FormatError(f"{src}: the archive holds {len(names)} FRFs ({', '.join(names)}); expected one, "
                          f"or dataset= naming it")
    return read_frf_group(fh[name], src, hints)


def _describe(node) -> str:
    value = node.attrs.get("__type__", "")
    value = value.decode() if isinstance(value, bytes) else str(value)
    if value == "dataclass":
        return str(node.attrs.get("__class__", "result")).rpartition(":")[2]
    return value or "data"
