"""Reading time records (force and responses) for FRF estimation.

:func:`read_time` returns a :class:`TimeRecord`: channels × samples on one
uniform time axis, with each channel's name (point id), what it measured and
its unit when the file says. Formats, picked from the file's bytes:

* UFF 58/58b with function type 1 (time response); record 8's ordinate
  specific data type gives the quantity (13 force, 8/11/12 displacement,
  velocity, acceleration); the point id is the response node and direction;
* CSV: a time column (header ``time``, ``t`` or ``time_s``, in s) and one
  column per channel; a header ``name [unit]`` gives the unit, from which the
  quantity follows (N → force, m → displacement, m/s → velocity, m/s^2 or g →
  acceleration);
* MAT (v5/v7 or v7.3) and HDF5: ``signals`` (channels × samples), and either
  ``sample_rate_hz`` (or ``fs``) or a ``time`` vector; optional ``names``,
  ``quantities`` and ``units`` (string arrays, or HDF5 attributes of ``signals``).
"""
from __future__ import annotations

import csv as _csv
import os
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import FormatError
from ._common import check_file, source_name

__all__ = ["TimeRecord", "read_time", "QUANTITY_FROM_DATA_TYPE"]

#: UFF specific data type → what a time channel measured
QUANTITY_FROM_DATA_TYPE = {13: "force", 9: "force", 8: "displacement", 11: "velocity", 12: "acceleration"}
_QUANTITY_FROM_UNIT = {
    "n": "force", "kn": "force", "lbf": "force",
    "m": "displacement", "mm": "displacement", "um": "displacement", "µm": "displacement",
    "m/s": "velocity", "mm/s": "velocity",
    "m/s^2": "acceleration", "m/s2": "acceleration", "m/s**2": "acceleration", "g": "acceleration",
}
#: factor from a channel's unit to SI (N, m, m/s, m/s²)
_SI_FACTOR = {"kn": 1e3, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "mm/s": 1e-3, "g": 9.80665, "lbf": 4.4482216152605}
_TIME_NAMES = ("time", "t", "time_s", "time [s]", "time (s)", "t [s]", "t (s)")


@dataclass(frozen=True)
class TimeRecord:
    """Channels sampled on one uniform time axis.

    Attributes
    ----------
    signals : ndarray, shape (n_channels, n_samples)
        In SI units where the unit was known (N, m, m/s, m/s²), else as stored.
    sample_rate_hz : float
    names : tuple of str
        Channel names or point ids (for example ``"1+Z"``).
    quantities : tuple of str or None
        ``"force"``, ``"displacement"``, ``"velocity"``, ``"acceleration"`` or None (unknown).
    units : tuple of str or None
        Each channel's unit after conversion to SI (None when unknown).
    source : str
    full_scale : tuple of float or None, or None
        Each channel's declared converter full scale in the channel's unit (SI where
        converted), None where the file does not say; None for no channel at all.
    """

    signals: np.ndarray
    sample_rate_hz: float
    names: tuple[str, ...]
    quantities: tuple[str | None, ...]
    units: tuple[str | None, ...]
    source: str = "<array>"
    full_scale: tuple[float | None, ...] | None = None

    @property
    def n_channels(self) -> int:
        return self.signals.shape[0]

    @property
    def n_samples(self) -> int:
        return self.signals.shape[1]

    def channel_index(self, spec: str | int) -> int:
        """0-based index of a channel given as its number (from 1, in file order) or its name."""
        text = str(spec).strip()
        if text in self.names:
            return self.names.index(text)
        if text.isdigit() and 1 <= int(text) <= self.n_channels:
            return int(text) - 1
        listing = ", ".join(f"{k + 1}={n}" for k, n in enumerate(self.names))
        raise FormatError(f"{self.source}: no channel {spec!r}; expected a number 1..{self.n_channels} or a name "
                          f"({listing})")

    def force_channels(self) -> list[int]:
        """Indices of the channels that measured force."""
        return [k for k, q in enumerate(self.quantities) if q == "force"]


def _normalise_unit(unit: str | None) -> str | None:
    if unit is None:
        return None
    u = unit.strip().replace(" ", "").replace("²", "^2").lower()
    return u or None


_SI_UNIT = {"force": "N", "displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}


def _channel(values, unit: str | None, quantity: str | None):
    """(values in SI, unit, quantity): a unit we know is converted to SI and names the quantity when
    the file does not; any other unit is kept as stored."""
    u = _normalise_unit(unit)
    if u in _QUANTITY_FROM_UNIT:
        quantity = quantity or _QUANTITY_FROM_UNIT[u]
        return np.asarray(values, float) * _SI_FACTOR.get(u, 1.0), _SI_UNIT[quantity], quantity
    return np.asarray(values, float), (unit.strip() if u else _SI_UNIT.get(quantity or "")), quantity


def _check(signals: np.ndarray, rate: float, src: str) -> None:
    if signals.ndim != 2 or signals.shape[1] < 2:
        raise FormatError(f"{src}: field 'signals' has shape {signals.shape}; expected (channels, samples >= 2)")
    if not (np.isfinite(rate) and rate > 0):
        raise FormatError(f"{src}: sample rate {rate!r}; expected a positive number of samples per second")
    bad = ~np.isfinite(signals)
    if bad.any():
        ch, i = (int(v) for v in np.argwhere(bad)[0])
        raise FormatError(f"{src}: channel {ch + 1}, sample {i}: not a finite number; expected finite samples")


def _rate_from_time(time: np.ndarray, src: str, field: str = "time") -> float:
    time = np.asarray(time, float).ravel()
    if time.size < 2 or not np.all(np.isfinite(time)):
        raise FormatError(f"{src}: field {field!r} holds {time.size} values or non-finite ones; expected a time axis in s")
    step = np.diff(time)
    mean = (time[-1] - time[0]) / (time.size - 1)
    if mean <= 0 or np.max(np.abs(step - mean)) > 1e-6 * mean + 1e-9 * abs(time[-1]):
        raise FormatError(f"{src}: field {field!r} is not uniformly increasing; expected samples at one rate "
                          "(resample first)")
    return 1.0 / mean


def _read_uff(path, src: str) -> TimeRecord:
    import pyuff

    from .uff import format_point

    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            uff = pyuff.UFF(os.fspath(path))
            types = [int(t) for t in uff.get_set_types()]
            sets = [uff.read_sets(k) if t == 58 else None for k, t in enumerate(types)]
    except Exception as exc:  # pyuff raises bare Exception
        raise FormatError(f"{src}: cannot be read as UFF ({exc}); expected datasets 58/58b") from None
    chosen = [(k, d) for k, d in enumerate(sets) if isinstance(d, dict) and int(d.get("func_type", -1)) == 1]
    if not chosen:
        found = sorted({int(d["func_type"]) for d in sets if isinstance(d, dict) and "func_type" in d})
        raise FormatError(f"{src}: no dataset 58 of function type 1 (time response) (function types found: "
                          f"{found or 'none'}); expected time data")
    k0, first = chosen[0]
    step = float(first["abscissa_inc"])
    n = int(first["num_pts"])
    signals, names, quantities, units = [], [], [], []
    for k, d in chosen:
        if int(d["num_pts"]) != n or not np.isclose(float(d["abscissa_inc"]), step, rtol=1e-9):
            raise FormatError(f"{src}: dataset {k + 1}: {d['num_pts']} samples every {d['abscissa_inc']} s; expected "
                              f"{n} every {step} s like dataset {k0 + 1} (one time axis for every channel)")
        data = np.asarray(d["data"])
        if np.iscomplexobj(data):
            raise FormatError(f"{src}: dataset {k + 1}: complex ordinates; expected real time samples")
        quantity = QUANTITY_FROM_DATA_TYPE.get(int(d.get("ordinate_spec_data_type", 0)))
        unit = d.get("ordinate_axis_units_lab")
        unit = None if unit in (None, "NONE", "") else str(unit)
        values, si, quantity = _channel(data, unit, quantity)
        signals.append(values)
        names.append(format_point(int(d.get("rsp_node", k + 1)), int(d.get("rsp_dir", 0))))
        quantities.append(quantity)
        units.append(si)
    if len(set(names)) < len(names):  # repeated point ids (a roving test stored twice): number them
        names = [f"{n}#{k + 1}" for k, n in enumerate(names)]
    signals = np.array(signals)
    rate = 1.0 / step
    # UFF keeps the time step to 6 significant digits (E13.5): 1/1024 s comes back as 9.76562e-4 s. A rate
    # within that rounding (5e-6 relative) of a whole number of samples per second is taken as that number
    if abs(rate - round(rate)) <= 5e-6 * rate:
        rate = float(round(rate))
    _check(signals, rate, src)
    return TimeRecord(signals, rate, tuple(names), tuple(quantities), tuple(units), src)


def _split_header(text: str) -> tuple[str, str | None]:
    for open_, close in (("[", "]"), ("(", ")")):
        if text.endswith(close) and open_ in text:
            name, unit = text[:-1].rsplit(open_, 1)
            return name.strip(), unit.strip()
    return text.strip(), None


def _read_csv(path, src: str) -> TimeRecord:
    with open(path, newline="", encoding="utf-8-sig") as fh:
        sample = fh.read(4096)
        fh.seek(0)
        try:
            dialect = _csv.Sniffer().sniff(sample, delimiters=",;\t ")
        except _csv.Error:
            dialect = _csv.excel
        rows = [r for r in _csv.reader(fh, dialect) if any(c.strip() for c in r)]
    if len(rows) < 3:
        raise FormatError(f"{src}: {len(rows)} rows; expected a header and at least 2 rows of samples")
    header = [c.strip() for c in rows[0]]
    if header[0].lower() not in _TIME_NAMES:
        raise FormatError(f"{src}: line 1, column 1 is {header[0]!r}; expected a time column named 'time' (s) "
                          "followed by one column per channel")
    try:
        table = np.array([[float(c) for c in r] for r in rows[1:]])
    except ValueError as exc:
        raise FormatError(f"{src}: a sample is not a number ({exc}); expected numbers below the header") from None
    if table.ndim != 2 or table.shape[1] != len(header) or table.shape[1] < 2:
        raise FormatError(f"{src}: rows have differing numbers of columns; expected {len(header)} in every row")
    rate = _rate_from_time(table[:, 0], src)
    signals, names, quantities, units = [], [], [], []
    for j, text in enumerate(header[1:], start=1):
        name, unit = _split_header(text)
        values, si, quantity = _channel(table[:, j], unit, None)
        signals.append(values)
        names.append(name or str(j))
        quantities.append(quantity)
        units.append(si)
    signals = np.array(signals)
    _check(signals, rate, src)
    return TimeRecord(signals, rate, tuple(names), tuple(quantities), tuple(units), src)


def _strings(value) -> list[str] | None:
    if value is None:
        return None
    arr = np.atleast_1d(np.asarray(value))
    out = []
    for v in arr.ravel():
        if isinstance(v, bytes):
            v = v.decode()
        out.append(str(v).strip())
    return out


def _from_mapping(get, src: str) -> TimeRecord:
    signals = get("signals")
    if signals is None:
        raise FormatError(f"{src}: no variable 'signals'; expected 'signals' (channels x samples) and "
                          "'sample_rate_hz' or 'time'")
    signals = np.atleast_2d(np.asarray(signals, float))
    rate = get("sample_rate_hz")
    if rate is None:
        rate = get("fs")
    if rate is not None:
        rate = float(np.asarray(rate, float).ravel()[0])
    else:
        time = get("time")
        if time is None:
            raise FormatError(f"{src}: neither 'sample_rate_hz' nor 'time'; expected one of them beside 'signals'")
        time = np.asarray(time, float).ravel()
        if signals.shape[1] != time.size and signals.shape[0] == time.size:
            signals = signals.T
        rate = _rate_from_time(time, src)
    names = _strings(get("names")) or [str(k + 1) for k in range(signals.shape[0])]
    quantities = _strings(get("quantities")) or [None] * signals.shape[0]
    stored_units = _strings(get("units")) or [None] * signals.shape[0]
    for field, values in (("names", names), ("quantities", quantities), ("units", stored_units)):
        if len(values) != signals.shape[0]:
            raise FormatError(f"{src}: field {field!r} has {len(values)} entries; expected one per channel "
                              f"({signals.shape[0]})")
    out, si_units, quants = [], [], []
    for k in range(signals.shape[0]):
        q = quantities[k] if quantities[k] in ("force", "displacement", "velocity", "acceleration") else None
        values, si, q = _channel(signals[k], stored_units[k], q)
        out.append(values)
        si_units.append(si)
        quants.append(q)
    signals = np.array(out)
    _check(signals, rate, src)
    return TimeRecord(signals, rate, tuple(names), tuple(quants), tuple(si_units), src)


def _read_mat(path, src: str) -> TimeRecord:
    from scipy.io import loadmat

    try:
        data = loadmat(os.fspath(path), squeeze_me=True)
    except NotImplementedError:  # v7.3: HDF5
        return _read_hdf5(path, src)
    except Exception as exc:
        raise FormatError(f"{src}: cannot be read as a MAT file ({exc})") from None
    return _from_mapping(data.get, src)


def _read_hdf5(path, src: str) -> TimeRecord:
    import h5py

    try:
        with h5py.File(path, "r") as fh:
            def get(name):
                if name in fh:
                    return fh[name][()]
                if "signals" in fh and name in fh["signals"].attrs:
                    return fh["signals"].attrs[name]
                return fh.attrs.get(name)
            return _from_mapping(get, src)
    except OSError as exc:
        raise FormatError(f"{src}: cannot be read as HDF5 ({exc})") from None


def read_time(path: str | os.PathLike, **hints: Any) -> TimeRecord:
    """Read a time record (force and response channels).

    Parameters
    ----------
    path : path-like
        UFF 58/58b (function type 1), CSV with a time column, MAT or HDF5.

    Returns
    -------
    TimeRecord

    Raises
    ------
    FormatError
        The file holds no time data, or the time axis is not uniform; the message
        names the file and the field.
    """
    from . import sniff_format

    if hints:
        raise TypeError(f"read_time() takes no hints, got {', '.join(sorted(hints))}")
    src = source_name(path)
    check_file(path)
    kind = sniff_format(path)
    if kind == "uff":
        return _read_uff(path, src)
    if kind in ("mat5", "mat73"):
        return _read_mat(path, src)
    if kind == "hdf5":
        return _read_hdf5(path, src)
    if kind == "binary":
        raise FormatError(f"{src}: binary content of no known kind; expected UFF 58/58b, MAT, HDF5 or CSV")
    return _read_csv(path, src)


def is_time_file(path: str | os.PathLike) -> bool:
    """Whether a file holds time data rather than an FRF (cheap: UFF function type, CSV header, variable names)."""
    from . import sniff_format

    try:
        kind = sniff_format(path)
        if kind == "uff":
            import pyuff
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore")
                uff = pyuff.UFF(os.fspath(path))
                types = [int(t) for t in uff.get_set_types()]
                for k, t in enumerate(types):
                    if t == 58:
                        return int(uff.read_sets(k, header_only=True).get("func_type", -1)) == 1
            return False
        if kind == "text":
            with open(path, encoding="utf-8-sig", errors="replace") as fh:
                first = fh.readline()
            head = first.replace(";", ",").replace("\t", ",").split(",")[0].strip().lower()
            return head in _TIME_NAMES
        if kind in ("hdf5", "mat73"):
            import h5py
            with h5py.File(path, "r") as fh:
                return "signals" in fh
        if kind == "mat5":
            from scipy.io import whosmat
            return any(name == "signals" for name, *_ in whosmat(os.fspath(path)))
    except Exception:  # noqa: BLE001 - a file we cannot even peek into is left to the FRF reader's message
        return False
    return False
