"""Reading time records (force and responses) for FRF estimation.

:func:`read_time` returns a :class:`TimeRecord`: channels × samples on one
uniform time axis, with each channel's name (point id), what it measured, its
unit and its converter full scale when the file says. Formats, picked from the
file's bytes (docs/estimate.md has the full specification):

* UFF 58/58b with function type 1 (time response); record 8's ordinate
  specific data type gives the quantity (13 force, 8/11/12 displacement,
  velocity, acceleration); the point id is the response node and direction;
  the time step is record 7's increment, or an explicit abscissa (spacing 0)
  when it is uniform;
* CSV: a time column (header ``time``, ``t`` or ``time_s``, in s) and one
  column per channel; a header ``name [unit]`` gives the unit, from which the
  quantity follows (N → force, m → displacement, m/s → velocity, m/s^2 or g →
  acceleration); ``#`` lines are comments, ``# full_scale: v1, v2, ...`` declares
  each channel's full scale in its unit;
* MAT (v5/v7 or v7.3) and HDF5: ``signals`` (channels × samples, or a cell of
  equal-length channels), and either ``sample_rate_hz`` (or ``fs``) or a ``time``
  vector; optional ``names``, ``quantities``, ``units`` (strings, or HDF5
  attributes of ``signals``) and ``full_scale`` (NaN where unknown).

A damaged or hostile file (cut short, a zero or uneven time step, channels of
different lengths, samples that are not finite, sizes beyond what the file can
hold) ends in one :class:`~modal.errors.FormatError` naming the file, the dataset
or column, and what is wrong.
"""
from __future__ import annotations

import csv as _csv
import os
import re
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import FormatError, QualityWarning, warn
from ._common import check_file, refuse_cut_last_value, source_name
from .csv import choose_delimiter
from .mat import _MAX_ELEMENTS_PER_BYTE

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
#: a time column's header: ``time`` or ``t``, optionally with its unit (``time [ms]``, ``t (s)``, ``time_us``)
_TIME_HEADER = re.compile(r"^(?:time|t)(?:\s*\[\s*(s|ms|us|µs|μs)\s*\]|\s*\(\s*(s|ms|us|µs|μs)\s*\)|_(s|ms|us))?$",
                          re.IGNORECASE)
_TIME_FACTOR = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6}
#: a sample rate below this (Hz) from a time column that gives no unit is named: it is what a column in
#: milliseconds read as seconds gives at rates up to 20 kHz, and below what vibration tests sample at
LOW_RATE_HZ = 20.0
#: a hammer hit lasts from about 0.1 ms (a steel tip) to 20 ms (a soft tip on a heavy structure): force pulses
#: longer than this at the rate a file states are no hits at that rate, the rate is off by its unit (a rate in
#: kHz written as Hz makes a 2 ms hit last 2 s), s
MAX_HIT_DURATION_S = 0.1
#: force pulses shorter than this (s) at the rate a time column in ms or µs gives are no hammer hits either (a steel
#: tip's 0.1 ms, with a margin of 5): the column holds seconds (a 1 ms hit read from 'time [ms]' lasts 1 µs)
MIN_HIT_DURATION_S = 2e-5


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
    take_lengths : tuple of int, or None
        Samples of each take when the record joins several (:func:`modal.io.timejoin.join_takes`);
        None for one recording.
    take_sources : tuple of str, or None
        The file of each take.
    """

    signals: np.ndarray
    sample_rate_hz: float
    names: tuple[str, ...]
    quantities: tuple[str | None, ...]
    units: tuple[str | None, ...]
    source: str = "<array>"
    full_scale: tuple[float | None, ...] | None = None
    take_lengths: tuple[int, ...] | None = None
    take_sources: tuple[str, ...] | None = None

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

    def describe(self, index: int) -> str:
        """``channel 2 (1+Z, acceleration in m/s^2)``: a channel as messages name it."""
        quantity = self.quantities[index]
        unit = self.units[index]
        what = (f"{quantity} in {unit}" if quantity and unit else quantity or
                (f"unknown quantity in {unit}" if unit else "unknown quantity"))
        return f"channel {index + 1} ({self.names[index]}, {what})"

    def check_roles(self, inputs, outputs) -> str | None:
        """Check that the excitation channels measured force and the responses motion.

        Parameters
        ----------
        inputs, outputs : sequence of int
            0-based indices of the excitation and response channels.

        Returns
        -------
        str or None
            What every response measured (``"displacement"``, ``"velocity"`` or
            ``"acceleration"``), None when the file does not say.

        Raises
        ------
        FormatError
            An excitation whose quantity or unit says it is not a force, a response that
            measured force, a channel in both roles, responses of different quantities.

        Warns
        -----
        ModalWarning
            An excitation channel of unknown quantity (accepted as the force).
        """
        from ..errors import ModalWarning

        both = sorted(set(inputs) & set(outputs))
        if both:
            raise FormatError(f"{self.source}: {self.describe(both[0])} is both the excitation and a response; "
                              "expected separate force and response channels")
        for k in inputs:
            if self.quantities[k] is None:
                warn(f"{self.source}: {self.describe(k)} is taken as the excitation, but the file does not say "
                     "it measured force; check that it is the hammer's or shaker's force in N", ModalWarning)
            elif self.quantities[k] != "force":
                raise FormatError(f"{self.source}: {self.describe(k)} is named as the excitation but measured "
                                  f"{self.quantities[k]}; expected a force channel (N) as the excitation")
        for k in outputs:
            if self.quantities[k] == "force":
                raise FormatError(f"{self.source}: {self.describe(k)} is a response but measured force; expected "
                                  "responses of displacement, velocity or acceleration")
        known = {self.quantities[k] for k in outputs if self.quantities[k] is not None}
        unknown = [k for k in outputs if self.quantities[k] is None]
        if len(known) > 1 or (known and unknown):
            listing = ", ".join(self.describe(k) for k in outputs)
            raise FormatError(f"{self.source}: the responses measured different quantities ({listing}); expected "
                              "one kind (choose them with --response)")
        return known.pop() if known else None


def _normalise_unit(unit: str | None) -> str | None:
    if unit is None:
        return None
    u = unit.strip().replace(" ", "").replace("²", "^2").lower()
    return u or None


_SI_UNIT = {"force": "N", "displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}


def _channel(values, unit: str | None, quantity: str | None, src: str = "<array>", where: str = "channel"):
    """(values in SI, unit, quantity): a unit we know is converted to SI and names the quantity when
    the file does not; any other unit is kept as stored. A unit of another quantity than the file
    states is refused (which of the two is wrong cannot be told)."""
    u = _normalise_unit(unit)
    if u in _QUANTITY_FROM_UNIT:
        if quantity is not None and quantity != _QUANTITY_FROM_UNIT[u]:
            raise FormatError(f"{src}: {where}: the unit {unit.strip()!r} is of {_QUANTITY_FROM_UNIT[u]} but the file "
                              f"says the channel measured {quantity}; expected a unit of {quantity} "
                              f"({_SI_UNIT[quantity]})")
        quantity = quantity or _QUANTITY_FROM_UNIT[u]
        return np.asarray(values, float) * _SI_FACTOR.get(u, 1.0), _SI_UNIT[quantity], quantity
    return np.asarray(values, float), (unit.strip() if u else _SI_UNIT.get(quantity or "")), quantity


#: no measurement reaches this magnitude in any unit; writers put the largest double (1.8e308) for ±Inf,
#: and squaring such a sample overflows the spectra
LARGEST_SAMPLE = 1e100


def _check_samples(values: np.ndarray, src: str, where: str) -> None:
    """Every sample finite and of a magnitude a measurement can have; the message names the first bad one."""
    values = np.asarray(values)
    if values.dtype.kind not in "fiu":
        raise FormatError(f"{src}: {where}: samples of type {values.dtype}; expected real numbers")
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(values) < LARGEST_SAMPLE)
    if bad.any():
        i = np.unravel_index(int(np.argmax(bad)), values.shape)
        ch, sample = (int(i[0]) + 1, int(i[1])) if values.ndim == 2 else (None, int(i[0]))
        value = values[i]
        what = "not a number" if np.isnan(value) else ("infinite" if np.isinf(value) else
                                                        f"{value:.4g} (a writer's stand-in for infinity?)")
        at = f"channel {ch}, sample {sample + 1}" if ch is not None else f"sample {sample + 1}"
        raise FormatError(f"{src}: {where}, {at}: {what}; expected finite samples (|value| < {LARGEST_SAMPLE:g})")


def _check(signals: np.ndarray, rate: float, src: str, quantities=(), field: str = "sample rate",
           time_unit: str = "") -> None:
    """Shape, rate and samples; and the rate against the hammer hits of the channels that say they measured force
    (``field`` names where the rate came from; ``time_unit`` the unit a time column's name gave)."""
    if signals.ndim != 2 or signals.shape[1] < 2:
        raise FormatError(f"{src}: field 'signals' has shape {signals.shape}; expected (channels, samples >= 2)")
    if not (np.isfinite(rate) and rate > 0):
        raise FormatError(f"{src}: sample rate {rate!r}; expected a positive number of samples per second")
    _check_samples(signals, src, "field 'signals'")
    _check_hit_durations(signals, rate, src, quantities, field, time_unit)


def _check_hit_durations(signals: np.ndarray, rate: float, src: str, quantities, field: str,
                         time_unit: str = "") -> None:
    """Refuse a rate at which a force channel's hits (short pulses holding its energy) last longer than any hammer
    hit does (:data:`MAX_HIT_DURATION_S`): the rate, or the time axis it came from, is in the wrong unit."""
    timed = field.startswith("column") or field == "field 'time'"
    hint = ("is the time in ms? say so in its name: 'time [ms]'" if timed else "is it in kHz?")
    from ..estimate.hits import pulse_train

    for k, quantity in enumerate(quantities):
        if quantity != "force":
            continue
        train = pulse_train(signals[k], rate)
        if not train.impulsive:
            continue
        duration = train.duty * signals.shape[1] / train.count / rate
        if duration > MAX_HIT_DURATION_S:
            raise FormatError(f"{src}: {field} gives {rate:.6g} samples/s, at which the {train.count} hit(s) of force "
                              f"channel {k + 1} last {duration:.3g} s each; expected a rate in Hz at which hammer "
                              f"hits last at most {MAX_HIT_DURATION_S:g} s ({hint})")
        if _TIME_FACTOR.get(time_unit.lower(), 1.0) < 1.0 and duration < MIN_HIT_DURATION_S:
            raise FormatError(f"{src}: {field} gives {rate:.6g} samples/s, at which the {train.count} hit(s) of force "
                              f"channel {k + 1} last {duration:.3g} s each; expected hammer hits of at least "
                              f"{MIN_HIT_DURATION_S:g} s (does the time column hold seconds? name it 'time [s]')")


def _time_column(header: str) -> str | None:
    """The unit a time column's header gives (``""`` for none, then s), or None when it is not a time column."""
    match = _TIME_HEADER.match(header.strip())
    if match is None:
        return None
    return next((unit for unit in match.groups() if unit), "")


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


def _warn_low_rate(rate: float, src: str, field: str, time_axis: bool) -> None:
    """Name a sample rate below :data:`LOW_RATE_HZ` that a time axis without a unit (read in s) or a rate field
    gave: what milliseconds read as seconds, or kHz as Hz, give. After the record's checks, which refuse it
    outright where its hammer hits contradict it."""
    if rate >= LOW_RATE_HZ:
        return
    if time_axis:
        warn(f"{src}: field {field!r} gives no unit and is read in s: a sample rate of {rate:.6g} Hz; if it "
             "holds milliseconds, say so in its name ('time [ms]')", QualityWarning)
    else:
        warn(f"{src}: field {field!r} gives a sample rate of {rate:.6g} Hz, below what vibration tests sample "
             "at; if it holds kHz, write it in Hz", QualityWarning)


def _uff_time_step(block, d: dict, src: str) -> float:
    """The time step of one dataset 58 of time data, s: record 7's increment, or its explicit abscissa."""
    if int(d.get("abscissa_spacing", 1)) == 1:
        step = float(d.get("abscissa_inc", float("nan")))
        if not (np.isfinite(step) and step > 0):
            raise FormatError(f"{src}: {block.where(7, 'abscissa_inc')}: time step {step!r} s; expected a positive "
                              "step between samples")
        return step
    # spacing 0: the abscissa is stored with every sample (pyuff writes it so when given x): accept it when uniform
    x = np.asarray(d.get("x", ()), dtype=float)
    # ASCII keeps each abscissa to 6 significant digits (E13.5): 5e-6 of |x|; binary stores them as written
    head = block.raw.split(b"\n", 2)
    binary = len(head) > 1 and head[1][6:7].lower() == b"b"
    rounding = 1e-12 if binary else 5e-6
    where = f"{block.where()} (record 7 abscissa_spacing 0: an abscissa for every sample)"
    if x.size < 2 or not np.all(np.isfinite(x)):
        raise FormatError(f"{src}: {where}: {x.size} abscissa values or non-finite ones; expected a time axis in s")
    step = (x[-1] - x[0]) / (x.size - 1)
    offset = np.abs(x - (x[0] + step * np.arange(x.size)))
    # each value off by its own rounding, and the axis through the end points by theirs
    bad = offset > rounding * (np.abs(x) + abs(x[0]) + abs(x[-1])) + 1e-9 * abs(step)
    if not step > 0 or bad.any():
        steps = np.diff(x)
        usual = float(np.median(steps))
        jumps = np.flatnonzero(np.abs(steps - usual) > 2 * rounding * (np.abs(x[1:]) + abs(usual)))
        if usual > 0 and jumps.size:
            j = int(jumps[0])
            what = (f"the step from sample {j + 1} to {j + 2} is {steps[j]:.6g} s against {usual:.6g} s "
                    "elsewhere")
        else:
            what = f"the times run from {x[0]:.6g} to {x[-1]:.6g} s unevenly"
        raise FormatError(f"{src}: {where}: {what}; expected samples at one rate (resample first)")
    return float(step)


def _read_uff(path, src: str) -> TimeRecord:
    from .uff import FUNCTION_TYPES, check_header, format_point, read_dataset, scan_datasets

    uff, blocks = scan_datasets(path, src)
    uff58 = [b for b in blocks if b.type == 58]
    if not uff58:
        kinds = ", ".join(sorted({str(b.type) for b in blocks}))
        raise FormatError(f"{src}: no dataset 58 (the file holds dataset types {kinds}); expected a time file: "
                          "datasets 58/58b of function type 1 (time response)")
    headers = {b.number: read_dataset(uff, b, src, header_only=True) for b in uff58}
    chosen = [b for b in uff58 if int(headers[b.number].get("func_type", -1)) == 1]
    if not chosen:
        found = sorted({int(h.get("func_type", -1)) for h in headers.values()})
        names = ", ".join(f"{t} ({FUNCTION_TYPES.get(t, 'unknown')})" for t in found)
        frf = " (FRFs: fit them with 'modal fit')" if 4 in found else ""
        raise FormatError(f"{src}: no time data: its datasets 58 are of function type {names}{frf}; expected a time "
                          "file: datasets 58/58b of function type 1 (time response)")
    signals, names, quantities, units = [], [], [], []
    b0, n0, step0 = None, 0, 0.0
    for b in chosen:
        problem = check_header(b, src)
        if problem:
            raise FormatError(problem)
        d = read_dataset(uff, b, src, header_only=False)
        data = np.asarray(d.get("data", ()))
        n_pts = int(d.get("num_pts", -1))
        if data.size != n_pts:
            raise FormatError(f"{src}: {b.where(7, 'num_pts')}: says {n_pts} samples but its data hold {data.size}: "
                              "the dataset ends early; expected a complete dataset (truncated or damaged file?)")
        if np.iscomplexobj(data):
            raise FormatError(f"{src}: {b.where(7, 'ord_data_type')}: complex ordinates; expected real time samples")
        step = _uff_time_step(b, d, src)
        if b0 is None:
            b0, n0, step0 = b, n_pts, step
        elif n_pts != n0 or not np.isclose(step, step0, rtol=1e-9):
            raise FormatError(f"{src}: {b.where(7)}: {n_pts} samples every {step:.9g} s; expected {n0} every "
                              f"{step0:.9g} s like dataset {b0.number} (one time axis for every channel)")
        _check_samples(data, src, b.where())
        quantity = QUANTITY_FROM_DATA_TYPE.get(int(d.get("ordinate_spec_data_type", 0)))
        unit = d.get("ordinate_axis_units_lab")
        unit = None if unit in (None, "NONE", "") else str(unit)
        values, si, quantity = _channel(data, unit, quantity, src, b.where(9, 'ordinate_axis_units_lab'))
        signals.append(values)
        names.append(format_point(int(d.get("rsp_node", b.number)), int(d.get("rsp_dir", 0))))
        quantities.append(quantity)
        units.append(si)
    if len(set(names)) < len(names):  # repeated point ids (a roving test stored twice): number them
        names = [f"{n}#{k + 1}" for k, n in enumerate(names)]
    signals = np.array(signals)
    rate = 1.0 / step0
    # UFF keeps the time step to 6 significant digits (E13.5): 1/1024 s comes back as 9.76562e-4 s. A rate
    # within that rounding (5e-6 relative) of a whole number of samples per second is taken as that number
    if abs(rate - round(rate)) <= 5e-6 * rate:
        rate = float(round(rate))
    _check(signals, rate, src, quantities, "the time step (record 7, abscissa_inc)")
    return TimeRecord(signals, rate, tuple(names), tuple(quantities), tuple(units), src)


def _split_header(text: str) -> tuple[str, str | None]:
    for open_, close in (("[", "]"), ("(", ")")):
        if text.endswith(close) and open_ in text:
            name, unit = text[:-1].rsplit(open_, 1)
            return name.strip(), unit.strip()
    return text.strip(), None


_TIME_CSV = ("expected a time file: a 'time' column (s, or 'time [ms]', 'time [us]') followed by one column per "
             "channel, 'name [unit]'")


def _csv_full_scale(comments: list[tuple[int, str]], n_channels: int, src: str) -> list[float | None] | None:
    """The ``# full_scale: v1, v2, ...`` comment line (one level per channel, in its unit; nan when unknown)."""
    for line_no, text in comments:
        key, _, value = text.lstrip("#").partition(":")
        if key.strip().lower() != "full_scale":
            continue
        parts = [v.strip() for v in value.replace(";", ",").split(",")]
        try:
            levels = [float(v) if v else float("nan") for v in parts]
        except ValueError:
            raise FormatError(f"{src}: line {line_no}, full_scale: {value.strip()!r}; expected one number per "
                              "channel (nan where unknown)") from None
        if len(levels) != n_channels or any(v <= 0 for v in levels):
            raise FormatError(f"{src}: line {line_no}, full_scale: {len(levels)} value(s) {value.strip()!r}; "
                              f"expected {n_channels} positive levels, one per channel (nan where unknown)")
        return [v if np.isfinite(v) else None for v in levels]
    return None


def _read_csv(path, src: str) -> TimeRecord:
    with open(path, newline="", encoding="utf-8-sig") as fh:
        text = fh.read()
    lines = text.splitlines()
    comments = [(k + 1, ln) for k, ln in enumerate(lines) if ln.lstrip().startswith("#")]
    body = [(k + 1, ln) for k, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")]
    if any("modalbal-frf-csv" in ln for _, ln in comments[:1]):
        raise FormatError(f"{src}: line 1: an FRF file (modalbal-frf-csv), not a time record; {_TIME_CSV} "
                          "(fit FRF files with 'modal fit')")
    delimiter = choose_delimiter({}, body, ".", src)  # as the FRF CSV reader chooses it
    if delimiter is None:  # whitespace
        rows = [(k, ln.split()) for k, ln in body]
    else:
        parsed = _csv.reader([ln for _, ln in body], delimiter=delimiter)
        rows = [(k, [c.strip() for c in row]) for (k, _), row in zip(body, parsed)]
    if rows and len(rows[0][1]) > 1 and all(row and not row[-1] for _, row in rows):
        rows = [(k, row[:-1]) for k, row in rows]  # every line ends with the delimiter (a spreadsheet's export)
    if delimiter in (";", "\t", None) and any("," in c for _, row in rows[1:51] for c in row) and not any(
            "." in c for _, row in rows[1:] for c in row):
        rows = rows[:1] + [(k, [c.replace(",", ".") for c in row]) for k, row in rows[1:]]  # a decimal comma
    if len(rows) < 3:
        raise FormatError(f"{src}: {len(rows)} rows; {_TIME_CSV}, and at least 2 rows of samples")
    header_line, header = rows[0]
    time_unit = _time_column(header[0])
    if time_unit is None:
        frf = header[0].lower().startswith(("freq", "f [", "f_hz", "f (", "omega"))
        what = "a frequency column: an FRF, not a time record" if frf else "not a time column"
        raise FormatError(f"{src}: line {header_line}, column 1 is {header[0]!r} ({what}); {_TIME_CSV}"
                          + (" (fit FRF files with 'modal fit')" if frf else ""))
    if len(header) < 2:
        raise FormatError(f"{src}: line {header_line}: only the time column; {_TIME_CSV}")
    for line_no, row in rows[1:]:
        if len(row) != len(header):
            last = " (the last line: is the file cut short?)" if line_no == rows[-1][0] and len(row) < len(header) \
                else ""
            raise FormatError(f"{src}: line {line_no}: {len(row)} columns{last}; expected {len(header)} like the "
                              f"header (line {header_line}) in every row")
    refuse_cut_last_value(text, rows[1:], header[-1], src)
    try:
        table = np.array([row for _, row in rows[1:]], dtype=float)
    except ValueError:
        for line_no, row in rows[1:]:  # find the cell
            for j, cell in enumerate(row):
                try:
                    float(cell)
                except ValueError:
                    column = header[j] or f"column {j + 1}"
                    raise FormatError(f"{src}: line {line_no}, column {column!r}: {cell!r} is not a number; "
                                      "expected numbers below the header") from None
        raise
    factor = _TIME_FACTOR[time_unit.lower()] if time_unit else 1.0
    rate = _rate_from_time(table[:, 0] * factor, src, field=header[0])
    scale = _csv_full_scale(comments, len(header) - 1, src)
    signals, names, quantities, units, scales = [], [], [], [], []
    for j, text in enumerate(header[1:], start=1):
        name, unit = _split_header(text)
        values, si, quantity = _channel(table[:, j], unit, None)
        signals.append(values)
        names.append(name or str(j))
        quantities.append(quantity)
        units.append(si)
        level = None if scale is None else scale[j - 1]
        scales.append(None if level is None else level * _SI_FACTOR.get(_normalise_unit(unit) or "", 1.0))
    signals = np.array(signals)
    _check(signals, rate, src, quantities, f"column {header[0]!r}", time_unit or "")
    if not time_unit:
        _warn_low_rate(rate, src, header[0], time_axis=True)
    declared = tuple(scales) if any(v is not None for v in scales) else None
    return TimeRecord(signals, rate, tuple(names), tuple(quantities), tuple(units), src, declared)


def _strings(value, field: str, src: str) -> list[str] | None:
    """A list of strings from a char array, cellstr or HDF5 string attribute (None when absent)."""
    if value is None:
        return None
    if isinstance(value, str):
        return [value.strip()]
    out = []
    for v in (value if isinstance(value, list) else np.atleast_1d(np.asarray(value)).ravel()):
        if isinstance(v, bytes):
            v = v.decode("utf-8", "replace")
        if isinstance(v, np.ndarray) and v.dtype.kind in "US" and v.size <= 1:
            v = "".join(str(c) for c in v.ravel())
        if not isinstance(v, (str, np.str_)):
            raise FormatError(f"{src}: field {field!r} holds {type(v).__name__} values; expected text, one per channel")
        out.append(str(v).strip())
    return out


def _signals(value, src: str) -> np.ndarray:
    """The ``signals`` variable as a float array (channels, samples); a cell of channels is stacked."""
    if isinstance(value, (list, tuple)) or (isinstance(value, np.ndarray) and value.dtype.kind == "O"):
        channels = [np.asarray(v).squeeze() for v in (value if isinstance(value, (list, tuple)) else value.ravel())]
        for k, ch in enumerate(channels):
            if ch.ndim != 1 or ch.dtype.kind not in "fiub":
                raise FormatError(f"{src}: field 'signals', channel {k + 1}: {ch.dtype} of shape {ch.shape}; "
                                  "expected a vector of numbers")
            if ch.size != channels[0].size:
                raise FormatError(f"{src}: field 'signals', channel {k + 1}: {ch.size} samples, channel 1 has "
                                  f"{channels[0].size}; expected one length for every channel")
        if not channels:
            raise FormatError(f"{src}: field 'signals' is empty; expected (channels, samples)")
        return np.array(channels, dtype=float)
    arr = np.asarray(value)
    if arr.dtype.kind not in "fiub":
        what = "complex numbers" if arr.dtype.kind == "c" else f"values of type {arr.dtype}"
        raise FormatError(f"{src}: field 'signals' holds {what}; expected real samples (channels x samples)")
    if arr.ndim > 2:
        raise FormatError(f"{src}: field 'signals' has shape {arr.shape}; expected (channels, samples)")
    return np.atleast_2d(arr.astype(float))


def _number(value, field: str, src: str) -> float | None:
    if value is None:
        return None
    arr = np.asarray(value)
    if arr.dtype.kind not in "fiu" or arr.size != 1:
        raise FormatError(f"{src}: field {field!r} holds {arr.size} value(s) of type {arr.dtype}; expected one number")
    return float(arr.ravel()[0])


def _from_mapping(get, src: str) -> TimeRecord:
    signals = get("signals")
    if signals is None:
        raise FormatError(f"{src}: no variable 'signals'; expected a time file: 'signals' (channels x samples) and "
                          "'sample_rate_hz' or 'time'")
    signals = _signals(signals, src)
    rate_field = "sample_rate_hz"
    rate = _number(get("sample_rate_hz"), "sample_rate_hz", src)
    if rate is None:
        rate_field, rate = "fs", _number(get("fs"), "fs", src)
    time = get("time")
    if rate is not None and time is not None:  # a time for every sample beside the rate: the two must agree
        time = np.asarray(time, float).ravel()
        step = (time[-1] - time[0]) / (time.size - 1) if time.size == signals.shape[1] >= 2 else np.nan
        # 1e-4: far above a single-precision time vector's rounding, far below a unit's factor of 1000
        if np.isfinite(step) and step > 0 and abs(1 / step - rate) > 1e-4 * rate:
            raise FormatError(f"{src}: field {rate_field!r} is {rate:.6g} but field 'time' steps {step:.6g} s "
                              f"({1 / step:.6g} Hz); expected the same sample rate in Hz (is {rate_field!r} in kHz?)")
    if rate is None:
        if time is None:
            raise FormatError(f"{src}: neither 'sample_rate_hz' nor 'time'; expected one of them beside 'signals'")
        time = np.asarray(time, float).ravel()
        if signals.shape[1] != time.size and signals.shape[0] == time.size:
            signals = signals.T
        if signals.shape[1] != time.size:
            raise FormatError(f"{src}: field 'time' has {time.size} values and 'signals' {signals.shape[1]} samples "
                              "per channel; expected one time per sample")
        rate_field, rate = "time", _rate_from_time(time, src)
    n_ch = signals.shape[0]
    names = _strings(get("names"), "names", src) or [str(k + 1) for k in range(n_ch)]
    quantities = _strings(get("quantities"), "quantities", src) or [""] * n_ch
    stored_units = _strings(get("units"), "units", src) or [None] * n_ch
    scale = get("full_scale")
    full_scale = None if scale is None else np.atleast_1d(np.asarray(scale, dtype=float)).ravel()
    for field, values in (("names", names), ("quantities", quantities), ("units", stored_units),
                          ("full_scale", full_scale)):
        if values is not None and len(values) != n_ch:
            raise FormatError(f"{src}: field {field!r} has {len(values)} entries; expected one per channel ({n_ch})")
    if full_scale is not None and np.any(full_scale <= 0):
        k = int(np.flatnonzero(full_scale <= 0)[0])
        raise FormatError(f"{src}: field 'full_scale', channel {k + 1}: {full_scale[k]:g}; expected a positive level "
                          "(NaN where unknown)")
    out, si_units, quants, scales = [], [], [], []
    for k in range(n_ch):
        q = quantities[k].lower() if quantities[k] else None
        if q is not None and q not in _SI_UNIT:
            raise FormatError(f"{src}: field 'quantities', channel {k + 1}: {quantities[k]!r}; expected one of "
                              f"{', '.join(_SI_UNIT)} (or empty when unknown)")
        values, si, q = _channel(signals[k], stored_units[k], q, src, f"channel {k + 1} ('units', 'quantities')")
        out.append(values)
        si_units.append(si)
        quants.append(q)
        level = None if full_scale is None or not np.isfinite(full_scale[k]) else float(full_scale[k])
        factor = _SI_FACTOR.get(_normalise_unit(stored_units[k]) or "", 1.0)
        scales.append(None if level is None else level * factor)
    signals = np.array(out)
    _check(signals, rate, src, quants, f"field {rate_field!r}")
    _warn_low_rate(rate, src, rate_field, time_axis=rate_field == "time")
    declared = tuple(scales) if any(v is not None for v in scales) else None
    return TimeRecord(signals, rate, tuple(names), tuple(quants), tuple(si_units), src, declared)


def _read_mat(path, src: str) -> TimeRecord:
    """MAT v4/v5/v7 through the FRF reader's guarded loader (class and size checks, in a child process)."""
    from .mat import _load_v5, _load_v73, _HDF5_SIGNATURE

    with open(path, "rb") as fh:
        head = fh.read(520)
    if head[512:520] == _HDF5_SIGNATURE:
        variables = _load_v73(path, src)  # arrays back in MATLAB's shape, cells as lists
    else:
        variables = _load_v5(path, src)
    return _from_mapping(variables.get, src)


def _read_hdf5(path, src: str) -> TimeRecord:
    import h5py

    size = os.path.getsize(path)
    try:
        with h5py.File(path, "r") as fh:
            def get(name):
                if name in fh:
                    obj = fh[name]
                    if not isinstance(obj, h5py.Dataset):
                        raise FormatError(f"{src}: {obj.name} is a group; expected a dataset {name!r}")
                    # a damaged header can claim any shape: no dataset holds more than zlib's best ratio allows
                    if obj.size > _MAX_ELEMENTS_PER_BYTE * size:
                        raise FormatError(f"{src}: dataset {obj.name} claims shape {obj.shape}, more than a "
                                          f"{size}-byte file can hold; expected an undamaged file")
                    return obj[()]
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
            return _time_column(head) is not None
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
