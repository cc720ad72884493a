"""Several time files of one test as one record of takes (hammer hits saved one file per hit).

The files must hold the same channels (names, quantities, units, full scale) at one sample
rate; the record joins their samples end to end and says where each take ends, so that the
estimator never cuts a segment or a hit record across two of them
(:mod:`modal.estimate.takes`).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import FormatError
from .timedata import TimeRecord

__all__ = ["join_takes"]

#: sample rates of two takes that differ by less than this fraction are one rate (a file's time step
#: is often kept to 6–9 digits)
RATE_TOLERANCE = 1e-6
#: two takes whose samples agree to this fraction of each channel's peak are one take saved twice (a
#: re-export at another precision: 6 significant digits round by 5e-7 of the value); two hits never agree
#: so, their noise alone differing by far more, and their hits falling at other samples
SAME_SAMPLES_TOLERANCE = 1e-6


def join_takes(records: Sequence[TimeRecord]) -> TimeRecord:
    """One record of the takes ``records``, in order; a single record is returned as it is.

    Raises
    ------
    FormatError
        A take whose channels or sample rate differ from the first's (the message names the file,
        the channel and both values).
    """
    records = list(records)
    if len(records) == 1:
        return records[0]
    first = records[0]
    for record in records[1:]:
        src = record.source
        if record.n_channels != first.n_channels:
            raise FormatError(f"{src}: {record.n_channels} channel(s) where {first.source} has {first.n_channels}; "
                              "expected the same channels in every take of one test")
        if abs(record.sample_rate_hz - first.sample_rate_hz) > RATE_TOLERANCE * first.sample_rate_hz:
            raise FormatError(f"{src}: sample rate {record.sample_rate_hz:.9g} Hz where {first.source} has "
                              f"{first.sample_rate_hz:.9g} Hz; expected one rate in every take (resample first)")
        for field in ("names", "quantities", "units"):
            mine, theirs = getattr(record, field), getattr(first, field)
            for k, (a, b) in enumerate(zip(mine, theirs)):
                if a != b:
                    roving = field == "names" and record.quantities == first.quantities and record.units == first.units
                    hint = ("; files measured at different points (a roving hammer or sensor) are not takes: estimate "
                            "each file's FRFs on its own (python -m modal frf FILE --out FILE.h5) and fit the FRF "
                            "files together (python -m modal fit A.h5 B.h5, or a scene's [frf] file = [...])"
                            if roving else "")
                    raise FormatError(f"{src}: channel {k + 1} ({field}) is {a!r} where {first.source} has {b!r}; "
                                      f"expected the same channels in every take of one test{hint}")
        if record.full_scale != first.full_scale:
            raise FormatError(f"{src}: full scale {record.full_scale!r} where {first.source} has "
                              f"{first.full_scale!r}; expected one recorder setting in every take")
    _refuse_same_samples(records)
    sources = tuple(record.source for record in records)
    return TimeRecord(
        signals=np.concatenate([record.signals for record in records], axis=1),
        sample_rate_hz=first.sample_rate_hz, names=first.names, quantities=first.quantities, units=first.units,
        source=f"{sources[0]} (+{len(sources) - 1} file{'s' if len(sources) > 2 else ''})",
        full_scale=first.full_scale, take_lengths=tuple(record.n_samples for record in records),
        take_sources=sources)


def _refuse_same_samples(records: Sequence[TimeRecord]) -> None:
    """Refuse two takes holding the same samples (:data:`SAME_SAMPLES_TOLERANCE`) in different bytes: one take
    exported twice (as CSV and again at another precision, or in two formats) would be averaged with itself,
    its noise looking smaller than it is. Byte-identical copies are refused before reading
    (:func:`modal.io._common.refuse_copies`)."""
    signals = [np.asarray(record.signals, float) for record in records]
    peaks = [np.abs(x).max(axis=1) if x.size else np.zeros(x.shape[0]) for x in signals]
    for j, later in enumerate(records):
        for i, earlier in enumerate(records[:j]):
            a, b = signals[i], signals[j]
            if a.shape != b.shape or a.shape[1] == 0:
                continue
            peak = np.maximum(peaks[i], peaks[j])
            head = slice(0, min(64, a.shape[1]))  # most pairs differ at once
            if np.any(np.abs(a[:, head] - b[:, head]).max(axis=1) > SAME_SAMPLES_TOLERANCE * peak):
                continue
            if np.all(np.abs(a - b).max(axis=1) <= SAME_SAMPLES_TOLERANCE * peak):
                raise FormatError(f"{later.source}: holds the same samples as {earlier.source} (to "
                                  f"{SAME_SAMPLES_TOLERANCE:g} of each channel's peak); expected each take once (one "
                                  "take saved twice is averaged with itself: its noise looks smaller than it is)")
