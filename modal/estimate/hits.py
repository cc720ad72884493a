"""Hit detection in a continuous impact-hammer record.

A *hit* is one impact event: the force rises above a threshold and the pulses
that follow it within ``double_hit_window_s`` belong to the same event (a
bounce of the hammer, i.e. a double hit). Hits are numbered from 1 in time
order. Each hit is accepted or rejected with a reason a user can act on:

* ``"double hit"``: a second force pulse follows within the double-hit window;
* ``"overload (clipped)"``: the force or a response sits at a flat maximum (the
  converter clipped) for several samples;
* ``"response not decayed before the next hit"``: the (windowed) response at
  the end of the hit's record is still above ``decay_fraction`` of its peak, so
  the record is truncated (leakage) and the next hit's record starts with it;
* ``"record cut by the start or end of the data"``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError

__all__ = ["Hits", "find_hits"]


@dataclass(frozen=True)
class Hits:
    """Hits found in a force record.

    Attributes
    ----------
    trigger_index : ndarray of int
        Sample where each hit's force first exceeds the threshold, for every hit.
    accepted : ndarray of bool
        Per hit: used for the estimate.
    record_start : ndarray of int
        First sample of each hit's record (trigger minus pre-trigger).
    record_length : int
        Samples per record.
    pulse_samples : int
        Longest accepted force pulse, samples (sizes the force window).
    rejected : list of dict
        One dict per rejected hit: ``hit`` (number from 1), ``time_s`` (trigger time
        in the record, s) and ``reason``.
    threshold : float
        Force level used for detection, in the force channel's unit.
    """

    trigger_index: np.ndarray
    accepted: np.ndarray
    record_start: np.ndarray
    record_length: int
    pulse_samples: int
    threshold: float
    rejected: list = field(default_factory=list)


def _pulses(above: np.ndarray, merge_gap: int) -> list[tuple[int, int]]:
    """(first, last) sample of each run of True, runs closer than ``merge_gap`` merged."""
    edges = np.diff(above.astype(np.int8), prepend=0, append=0)
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1) - 1
    pulses: list[tuple[int, int]] = []
    for s, e in zip(starts, stops):
        if pulses and s - pulses[-1][1] <= merge_gap:
            pulses[-1] = (pulses[-1][0], int(e))
        else:
            pulses.append((int(s), int(e)))
    return pulses


def _clipped(signal: np.ndarray, min_run: int = 3) -> bool:
    """True when the signal holds its largest |value| for ``min_run`` or more consecutive samples."""
    peak = np.max(np.abs(signal))
    if peak == 0:
        return False
    at_peak = np.abs(signal) >= peak * (1 - 1e-12)
    run = np.convolve(at_peak.astype(np.int32), np.ones(min_run, np.int32), mode="valid")
    return bool(np.any(run >= min_run))


def find_hits(force, response, sample_rate_hz: float, *, threshold: float | None = None,
              pretrigger_s: float | None = None, record_length: int | None = None,
              double_hit_window_s: float = 0.05, decay_fraction: float = 0.05,
              decay_window: np.ndarray | None = None, full_scale: float | None = None) -> Hits:
    """Find, cut and screen the hits of a continuous impact record.

    Parameters
    ----------
    force : array_like, shape (n_samples,)
        The hammer's force channel.
    response : array_like, shape (n_outputs, n_samples)
        Response channels (screened for clipping and decay).
    sample_rate_hz : float
        Samples per second, Hz.
    threshold : float, optional
        Trigger level in the force's unit. Default: the larger of 5 % of the
        largest |force| and 8 robust standard deviations of the force's noise
        (median absolute deviation / 0.6745).
    pretrigger_s : float, optional
        Time kept before each trigger, s. Default: 1/64 of the record, at least 2 samples.
    record_length : int, optional
        Samples per hit record. Default: the largest power of two not above the
        shortest spacing between separate hits (or the data after the last hit).
    double_hit_window_s : float
        A pulse starting this soon after the previous pulse's end makes a double hit, s.
    decay_fraction : float
        Largest |response| allowed in the last 1/16 of a record, as a fraction of the
        record's peak, after ``decay_window`` (the leakage the record can tolerate).
    decay_window : ndarray, optional
        Window applied to the response record before the decay check (the exponential window).
    full_scale : float, optional
        The converter's full scale in the force's and responses' units: |values| at
        or above 99.9 % of it count as overloads as well.
    """
    force = np.asarray(force, dtype=float)
    response = np.atleast_2d(np.asarray(response, dtype=float))
    n = force.size
    fs = float(sample_rate_hz)
    peak = float(np.max(np.abs(force))) if n else 0.0
    if peak == 0:
        raise ParameterError("field 'excitation' is zero everywhere: no hit to find (is it the force channel?)")
    if threshold is None:
        noise = float(np.median(np.abs(force - np.median(force)))) / 0.6745
        threshold = max(0.05 * peak, 8.0 * noise)
    threshold = float(threshold)
    above = np.abs(force) > threshold
    merge_gap = max(2, int(round(0.0005 * fs)))
    pulses = _pulses(above, merge_gap)
    if not pulses:
        raise ParameterError(f"field 'excitation': no sample exceeds the trigger threshold {threshold:g}")
    bounce = max(1, int(round(double_hit_window_s * fs)))
    events: list[list[tuple[int, int]]] = []
    for p in pulses:
        if events and p[0] - events[-1][-1][1] <= bounce:
            events[-1].append(p)
        else:
            events.append([p])
    trigger = np.array([ev[0][0] for ev in events], dtype=np.int64)
    if record_length is None:
        spacing = np.diff(np.append(trigger, n))
        shortest = int(spacing.min()) if spacing.size else n
        record_length = 1 << max(4, int(np.floor(np.log2(max(shortest, 16)))))
        if record_length > shortest and trigger.size > 1:
            record_length >>= 1
    record_length = int(record_length)
    pre = max(2, record_length // 64) if pretrigger_s is None else int(round(pretrigger_s * fs))
    start = trigger - pre
    tail = max(1, record_length // 16)
    accepted = np.ones(trigger.size, bool)
    rejected: list[dict] = []
    pulse_len = 1
    for k, ev in enumerate(events):
        reason = None
        s = int(start[k])
        if s < 0 or s + record_length > n:
            reason = "record cut by the start or end of the data"
        elif len(ev) > 1:
            reason = "double hit"
        else:
            seg_f = force[s:s + record_length]
            seg_y = response[:, s:s + record_length]
            over = _clipped(seg_f) or any(_clipped(ch) for ch in seg_y)
            if full_scale is not None:
                over = over or bool(np.any(np.abs(seg_f) >= 0.999 * full_scale)
                                    or np.any(np.abs(seg_y) >= 0.999 * full_scale))
            if over:
                reason = "overload (clipped)"
            else:
                weighted = seg_y * (1.0 if decay_window is None else decay_window)
                top = np.max(np.abs(weighted), axis=1)
                end = np.max(np.abs(weighted[:, -tail:]), axis=1)
                if np.any(end > decay_fraction * np.maximum(top, np.finfo(float).tiny)):
                    reason = "response not decayed before the next hit"
                elif k + 1 < trigger.size and trigger[k + 1] - pre < s + record_length:
                    reason = "response not decayed before the next hit"
        if reason is not None:
            accepted[k] = False
            rejected.append({"hit": k + 1, "time_s": float(trigger[k] / fs), "reason": reason})
        else:
            pulse_len = max(pulse_len, ev[0][1] - ev[0][0] + 1)
    return Hits(trigger, accepted, start, record_length, int(pulse_len), threshold, rejected)
