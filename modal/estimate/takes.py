"""Several takes of one test estimated as one: hammer hits saved one file per hit, a shaker run recorded in parts.

The takes are joined end to end (excitation and response of every take, in order) and
:func:`~modal.estimate.estimate_frf` is told where each ends (``take_lengths``). No record
straddles two takes: segments are cut within each take, and hits are found, cut and screened
take by take (a take's last hit is never completed by the next take's first samples). The
spectral sums then run over the records of every take, so the estimate is the one a single
recording of all of them would give, without the joins.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import ParameterError
from .hits import Hits, find_hits

__all__ = ["hit_labels", "take_bounds", "take_names", "segment_starts", "find_hits_in_takes"]


def take_bounds(take_lengths: Sequence[int] | None, n_samples: int, source: str) -> np.ndarray:
    """The first sample of each take and the end of the last, shape (n_takes + 1,).

    Raises
    ------
    ParameterError
        Lengths that are not positive whole numbers or do not add up to the samples given.
    """
    if take_lengths is None:
        return np.array([0, n_samples], dtype=np.int64)
    lengths = np.asarray(take_lengths)
    if lengths.ndim != 1 or lengths.size == 0 or lengths.dtype.kind not in "iu" or np.any(lengths < 2):
        raise ParameterError(f"{source}: field 'take_lengths' is {list(np.ravel(take_lengths))!r}; expected the "
                             "samples of each take, at least 2 each")
    if int(lengths.sum()) != n_samples:
        raise ParameterError(f"{source}: field 'take_lengths' adds up to {int(lengths.sum())} samples; expected "
                             f"the {n_samples} samples of the joined takes")
    return np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)


def take_names(names: Sequence[str] | None, n_takes: int, source: str) -> list[str]:
    """How messages name each take (``"take 1"``, … unless named)."""
    if names is None:
        return [f"take {k + 1}" for k in range(n_takes)]
    names = [str(name) for name in names]
    if len(names) != n_takes:
        raise ParameterError(f"{source}: field 'take_names' has {len(names)} names; expected one per take "
                             f"({n_takes})")
    return names


def segment_starts(bounds: np.ndarray, length: int, step: int) -> np.ndarray:
    """First sample of every segment of ``length`` samples, ``step`` apart, that lies within one take."""
    return np.concatenate([first + np.arange(0, last - first - length + 1, step)
                           for first, last in zip(bounds[:-1], bounds[1:])]).astype(np.int64)


def find_hits_in_takes(force: np.ndarray, response: np.ndarray, sample_rate_hz: float, bounds: np.ndarray,
                       names: Sequence[str], *, record_length: int | None = None, **options) -> Hits:
    """:func:`~modal.estimate.hits.find_hits` take by take, as one :class:`Hits` on the joined samples.

    Every take is searched on its own (its own threshold unless one is given, its own cuts at its
    start and end). The record length, unless given, is the shortest that any take's hit spacing
    allows, so that every take's records have one length. Rejections carry ``take`` (counted from 1)
    and ``take_name``; their ``hit`` and ``time_s`` count within the take; ``trigger_index`` and
    ``record_start`` index the joined samples.
    """
    takes = list(zip(bounds[:-1], bounds[1:]))

    def search(first, last, name, length):  # a take without any hit raises, naming the take
        return find_hits(force[first:last], response[:, first:last], sample_rate_hz, record_length=length,
                         **{**options, "source": name})

    if record_length is None:
        record_length = min(search(first, last, name, None).record_length
                            for (first, last), name in zip(takes, names))
    found = [search(first, last, name, record_length) for (first, last), name in zip(takes, names)]
    rejected = [{**item, "take": k + 1, "take_name": names[k]} for k, hits in enumerate(found) for item in hits.rejected]
    return Hits(
        trigger_index=np.concatenate([hits.trigger_index + first for hits, (first, _) in zip(found, takes)]),
        accepted=np.concatenate([hits.accepted for hits in found]),
        record_start=np.concatenate([hits.record_start + first for hits, (first, _) in zip(found, takes)]),
        record_length=int(record_length),
        pulse_samples=max(hits.pulse_samples for hits in found),
        threshold=min(hits.threshold for hits in found),
        rejected=rejected,
        overloads=[item for hits in found for item in hits.overloads],
    )


def hit_labels(hits: Hits, bounds: np.ndarray | None, names: Sequence[str], sample_rate_hz: float) -> list[dict]:
    """Per hit of ``hits``: how its rejection names it, ``hit`` and ``time_s`` counted within its take, with
    ``take`` (from 1) and ``take_name`` when ``bounds`` (the takes' first samples and the end) is given, as
    :func:`find_hits_in_takes` names them; on the whole record without."""
    trigger = np.asarray(hits.trigger_index)
    if bounds is None:
        return [{"hit": k + 1, "time_s": float(t / sample_rate_hz)} for k, t in enumerate(trigger)]
    take = np.searchsorted(bounds, trigger, side="right") - 1
    first_of_take = np.searchsorted(take, take, side="left")  # triggers are in time order
    return [{"hit": int(k - first_of_take[k] + 1), "time_s": float((t - bounds[take[k]]) / sample_rate_hz),
             "take": int(take[k] + 1), "take_name": names[take[k]]} for k, t in enumerate(trigger)]
