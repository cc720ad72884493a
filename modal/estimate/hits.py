"""Hit detection in a continuous impact-hammer record.

A *hit* is one impact event: the force rises above a threshold, and every pulse
that follows while the hit is not over belongs to it: a pulse within
``double_hit_window_s`` of the previous one (a bounce of the hammer), or a pulse
that arrives while the hit's response is still ringing (above ``decay_fraction``
of its peak and above its noise floor: a rebound, or a second hit given too
soon). Hits are numbered from 1 in time order. Each hit is accepted or rejected
with a reason a user can act on (and a ``detail`` saying what was seen):

* ``"double hit"``: more than one force pulse in the hit; under a force window also a pulse below the
  trigger threshold that the window cuts while the record keeps its response
  (:func:`reject_pulses_the_window_cuts`);
* ``"overload (clipped)"``: the force or a response reached the recorder's rail
  (flat tops at its extreme) or 99.9 % of a declared full scale within the hit's
  record (:mod:`modal.estimate.overload`);
* ``"response of an earlier hit still ringing"``: the hit began before the
  previous response had decayed relative to this hit's own peak (a weak hit after
  a strong one), so its record would start inside another hit's response;
* ``"response not decayed within the record"``: the (windowed) response in the
  last 1/16 of the record is still above ``decay_fraction`` of its peak and above
  the noise (leakage);
* ``"next hit within the record"``: the record is longer than the gap to the next hit;
* ``"record cut by the start or end of the data"``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ParameterError
from .overload import find_overloads

__all__ = ["Hits", "find_hits", "PulseTrain", "pulse_train", "trigger_threshold", "reject_pulses_the_window_cuts",
           "DECAY_LOOK_S", "NOISE_FACTOR", "PULSE_DUTY_LIMIT", "PULSE_ENERGY_SHARE", "CUT_PULSE_SIGMAS",
           "BASELINE_PULSES"]

#: how far back the response is looked at before a pulse to judge whether it has decayed, s
#: (a whole period of any mode above 10 Hz; half the gap to the previous pulse when that is shorter)
DECAY_LOOK_S = 0.1
#: a response within this many times its noise floor (RMS of its quietest parts) counts as decayed
NOISE_FACTOR = 6.0
#: 64-sample blocks whose RMS is within this factor of the quietest block's hold noise alone: the RMS of 64
#: samples of white noise scatters by 9 %, so the quietest of thousands of noise blocks lies near 0.7 of the
#: noise's RMS and every noise block within 1.5 of it but the loudest few; a decaying response above it
#: is not noise
QUIET_BLOCK_RATIO = 1.5
#: a force whose pulses above the trigger threshold fill at most this fraction of the record is a train of
#: hits: hammer pulses of 1–10 ms, a few per second, fill well under 1 %; a shaker's continuous force has no
#: sample above 8 robust standard deviations (Gaussian: probability 1e-15), a burst random one fills 10–90 %
PULSE_DUTY_LIMIT = 0.02
#: ... and those pulses hold at least this share of the force's energy (a few outliers of a heavy-tailed
#: random force hold far less; the hits of a hammer record hold nearly all of it)
PULSE_ENERGY_SHARE = 0.5
#: hits that peak at exactly one value this many times were clipped, each in a sample or two (hits not clipped
#: scatter in amplitude by several per cent; :func:`modal.estimate.overload.find_overloads`)
REPEATED_PEAKS = 3
#: a force beyond the force window whose matched filter (:func:`reject_pulses_the_window_cuts`) lies this many robust
#: standard deviations of its noise from the force's local level in two samples running or more is a pulse (white
#: noise: probability 1e-15 a sample; a lone spike must reach twice the level)
CUT_PULSE_SIGMAS = 8.0
#: the force's local level there: a straight line fitted over this many pulse widths (the slow recovery of an
#: AC-coupled channel after a hit is no pulse; a pulse moves the line by about 2/(π·8) ≈ 8 % of its peak)
BASELINE_PULSES = 8


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
    overloads : list of ChannelOverload
        Channels clipped or overloaded anywhere in the record (channel 0 is the force).
    """

    trigger_index: np.ndarray
    accepted: np.ndarray
    record_start: np.ndarray
    record_length: int
    pulse_samples: int
    threshold: float
    rejected: list = field(default_factory=list)
    overloads: list = field(default_factory=list)


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


def _noise_floor(centred: np.ndarray) -> np.ndarray:
    """Per channel, the RMS of the quiet parts: of the 64-sample blocks whose RMS is within
    :data:`QUIET_BLOCK_RATIO` of the quietest block's, however few they are (a take cut short while
    it rings is quiet only before its hit: a fixed share of the blocks, such as the quietest tenth,
    would then be ringing and put the floor near the response's peak)."""
    block = 64
    m = centred.shape[1] // block
    if m < 10:
        return 1.4826 * np.median(np.abs(centred), axis=1)
    blocks = centred[:, :m * block].reshape(centred.shape[0], m, block)
    power = np.mean(blocks**2, axis=2)
    quiet = power <= QUIET_BLOCK_RATIO**2 * power.min(axis=1, keepdims=True)
    return np.sqrt(np.sum(np.where(quiet, power, 0.0), axis=1) / quiet.sum(axis=1))


def trigger_threshold(force: np.ndarray) -> float:
    """The default trigger level of a force record, in its unit, above its median (the channel's offset): the
    larger of 5 % of the largest |force − median| and 8 robust standard deviations of its noise (median
    absolute deviation / 0.6745)."""
    centre, noise = _centre_and_noise(force)
    return _threshold(force - centre, noise)


def _centre_and_noise(force: np.ndarray) -> tuple[float, float]:
    """The force's median and its noise's robust standard deviation (median absolute deviation / 0.6745)."""
    centre = float(np.median(force))
    return centre, float(np.median(np.abs(force - centre))) / 0.6745


def _threshold(force: np.ndarray, noise: float) -> float:
    return max(0.05 * float(np.max(np.abs(force))), 8.0 * noise)


@dataclass(frozen=True)
class PulseTrain:
    """How much of a force record is short pulses above the trigger threshold.

    Attributes
    ----------
    count : int
        Pulses above the threshold (bounces within 0.5 ms merged).
    duty : float
        Fraction of the record's samples inside those pulses.
    energy_share : float
        Fraction of the force's energy above its noise (about its median) inside them.
    """

    count: int
    duty: float
    energy_share: float

    @property
    def impulsive(self) -> bool:
        """Whether the force is a train of hits (an impact record) rather than a continuous excitation."""
        return self.count >= 1 and self.duty <= PULSE_DUTY_LIMIT and self.energy_share >= PULSE_ENERGY_SHARE


def pulse_train(force, sample_rate_hz: float) -> PulseTrain:
    """Measure how much of ``force`` is pulses above :func:`trigger_threshold` (hammer hits), Hz for the rate."""
    force = np.asarray(force, dtype=float)
    if force.size == 0 or not np.any(force):
        return PulseTrain(0, 0.0, 0.0)
    centre, noise = _centre_and_noise(force)
    centred = force - centre  # a force channel's offset (an amplifier's, a drift) is no pulse
    above = np.abs(centred) > _threshold(centred, noise)
    pulses = _pulses(above, max(2, int(round(0.0005 * float(sample_rate_hz)))))
    inside = np.zeros(force.size, bool)
    for first, last in pulses:
        inside[first:last + 1] = True
    noise_variance = noise**2
    # energies above the noise's (the noise's expected energy taken off both), so that a noisy force
    # channel still shows its hits
    energy = float(np.sum(centred**2)) - noise_variance * force.size
    pulse_energy = float(np.sum(centred[inside] ** 2)) - noise_variance * np.count_nonzero(inside)
    share = float(np.clip(pulse_energy / energy, 0.0, 1.0)) if energy > 0 else 0.0
    return PulseTrain(len(pulses), float(np.mean(inside)), share)


def _names(channel_names, n_outputs: int) -> list[str]:
    if channel_names is None:
        return ["force"] + [f"response {k + 1}" for k in range(n_outputs)]
    names = [str(v) for v in channel_names]
    if len(names) != n_outputs + 1:
        raise ParameterError(f"field 'channel_names' has {len(names)} names; expected {n_outputs + 1} (force first)")
    return names


def find_hits(force, response, sample_rate_hz: float, *, threshold: float | None = None,
              pretrigger_s: float | None = None, record_length: int | None = None,
              double_hit_window_s: float = 0.05, decay_fraction: float = 0.05,
              decay_window: np.ndarray | None = None, full_scale=None, channel_names=None,
              channel_units=None, source: str = "<array>") -> Hits:
    """Find, cut and screen the hits of a continuous impact record.

    A pulse belongs to the hit before it when it starts within ``double_hit_window_s``
    of that hit's last pulse (a bounce) or while the hit's response is still ringing
    (above ``decay_fraction`` of its peak and above the noise): such a hit is rejected
    as a double hit, so that no record ever starts inside another hit's response.

    Parameters
    ----------
    force : array_like, shape (n_samples,)
        The hammer's force channel.
    response : array_like, shape (n_outputs, n_samples)
        Response channels (screened for clipping and decay).
    sample_rate_hz : float
        Samples per second, Hz.
    threshold : float, optional
        Trigger level in the force's unit, above the force's median (its offset). Default: the
        larger of 5 % of the largest |force − median| and 8 robust standard deviations of the
        force's noise (median absolute deviation / 0.6745).
    pretrigger_s : float, optional
        Time kept before each trigger, s. Default: 1/64 of the record, at least 2 samples.
    record_length : int, optional
        Samples per hit record. Default: the largest power of two not above the
        shortest spacing between separate hits, or half of it when the data after the
        last hit holds no more (for a single hit, the data after it).
    double_hit_window_s : float
        A pulse starting this soon after the previous pulse's end makes a double hit, s.
    decay_fraction : float
        A response is decayed when its |value| is below this fraction of its peak
        (or at its noise floor): in the last 1/16 of a record, after ``decay_window``
        (the leakage the record can tolerate), and when the next pulse arrives.
    decay_window : ndarray, optional
        Window applied to the response record before the decay check (the exponential window).
    full_scale : float or sequence of (float or None), optional
        The converter's full scale: one value for every channel, or one per channel
        (force first, then the responses), in the channels' units; |values| at or above
        99.9 % of it are overloads, as are flat tops (:mod:`modal.estimate.overload`).
    channel_names, channel_units : sequence of str, optional
        Force first, then the responses: how the reasons name the channels.
    source : str
        The record's name in messages (the file).

    Raises
    ------
    ParameterError
        A force that is zero everywhere, or one with no pulse above the threshold (a continuous force).
    """
    force = np.asarray(force, dtype=float)
    response = np.atleast_2d(np.asarray(response, dtype=float))
    n = force.size
    fs = float(sample_rate_hz)
    names = _names(channel_names, response.shape[0])
    units = [None] * len(names) if channel_units is None else list(channel_units)
    peak = float(np.max(np.abs(force))) if n else 0.0
    if peak == 0:
        raise ParameterError(f"{source}: field 'excitation' is zero everywhere: no hit to find (is it the force "
                             "channel?)")
    # the trigger counts from the force's median: an amplifier's offset is no hit
    if threshold is None:
        centre, noise = _centre_and_noise(force)
        centred = force - centre
        threshold = _threshold(centred, noise)  # trigger_threshold's, the median taken once
    else:
        centred, threshold = force - np.median(force), float(threshold)
    above = np.abs(centred) > threshold
    merge_gap = max(2, int(round(0.0005 * fs)))
    pulses = _pulses(above, merge_gap)
    if not pulses:
        unit = f" {units[0]}" if units[0] else ""
        raise ParameterError(f"{source}: impact record expected, but {names[0]} has no hit: no sample rises above "
                             f"the trigger threshold {threshold:g}{unit} (5 % of its peak or 8 times its noise, "
                             "whichever is larger), as with a shaker's continuous force; expected hammer hits, or "
                             "estimate it as a continuous record (without impact)")
    centred = response - np.median(response, axis=1, keepdims=True)
    floor = NOISE_FACTOR * _noise_floor(centred)
    bounce = max(1, int(round(double_hit_window_s * fs)))
    look = max(2, int(round(DECAY_LOOK_S * fs)))

    def ringing(first: int, stop: int, gap_start: int, reference: np.ndarray):
        """(channel, level / reference) of the most undecayed response just before the pulse at ``stop``, or None.

        The look ends ``merge_gap`` samples before the trigger: the force rises below the threshold first, and
        an acceleration answers it at once."""
        stop = max(first, stop - merge_gap)
        span = max(1, min(look, (stop - gap_start) // 2 if stop > gap_start else look))
        level = np.max(np.abs(centred[:, max(first, stop - span):stop]), axis=1) if stop > first else 0 * reference
        undecayed = level > np.maximum(decay_fraction * reference, floor)
        if not undecayed.any():
            return None
        ratio = np.where(undecayed, level / np.maximum(reference, np.finfo(float).tiny), 0.0)
        j = int(np.argmax(ratio))
        return j, float(ratio[j])

    events: list[list[tuple[int, int]]] = []
    details: list[str | None] = []
    for p in pulses:
        if events:
            first, last_end = events[-1][0][0], events[-1][-1][1]
            after_ms = 1e3 * (p[0] - first) / fs
            if p[0] - last_end <= bounce:
                events[-1].append(p)
                details[-1] = details[-1] or f"a second pulse {after_ms:.0f} ms after the first"
                continue
            still = ringing(first, p[0], last_end, np.max(np.abs(centred[:, first:p[0]]), axis=1))
            if still is not None:
                events[-1].append(p)
                details[-1] = details[-1] or (f"a second pulse {after_ms:.0f} ms after the first, while "
                                              f"{names[still[0] + 1]} was at {100 * still[1]:.0f} % of its peak")
                continue
        events.append([p])
        details.append(None)
    trigger = np.array([ev[0][0] for ev in events], dtype=np.int64)
    if record_length is None:
        def power_of_two(samples: int) -> int:
            return 1 << max(4, int(np.floor(np.log2(max(samples, 16)))))

        # the spacing between hits sizes the records; the data after the last hit shortens them at most to
        # half (every hit kept, at half the resolution): a shorter tail leaves its hit to be rejected as cut
        # rather than cutting every other hit's response short
        tail = power_of_two(n - int(trigger[-1]))
        record_length = power_of_two(int(np.diff(trigger).min())) if trigger.size > 1 else tail
        if tail < record_length and 2 * tail >= record_length:
            record_length = tail
    record_length = int(record_length)
    pre = max(2, record_length // 64) if pretrigger_s is None else int(round(pretrigger_s * fs))
    start = trigger - pre
    tail = max(1, record_length // 16)
    window = np.ones(record_length) if decay_window is None else np.asarray(decay_window, float)
    # three hits peaking at the very same value are clipped (hits scatter by several per cent in amplitude)
    overloads = find_overloads(np.vstack([force[None, :], response]), full_scale,
                               repeated_peaks=REPEATED_PEAKS if trigger.size >= REPEATED_PEAKS else None)
    accepted = np.ones(trigger.size, bool)
    rejected: list[dict] = []
    pulse_len = 1
    for k, ev in enumerate(events):
        reason, detail = None, None
        s = int(start[k])
        t = int(trigger[k])
        nxt = int(trigger[k + 1]) if k + 1 < trigger.size else n
        if s < 0 or s + record_length > n:
            reason = "record cut by the start or end of the data"
        elif len(ev) > 1:
            reason, detail = "double hit", details[k]
        elif any(o.mask[s:s + record_length].any() for o in overloads):
            reason = "overload (clipped)"
            detail = "; ".join(o.describe(names[o.channel], units[o.channel]) for o in overloads
                               if o.mask[s:s + record_length].any())
        else:
            previous_end = events[k - 1][-1][1] if k else 0
            own_peak = np.max(np.abs(centred[:, t:min(nxt, s + record_length)]), axis=1)
            before = ringing(previous_end, t, previous_end, own_peak)
            weighted = centred[:, s:s + record_length] * window
            top = np.max(np.abs(weighted), axis=1)
            end = np.max(np.abs(weighted[:, -tail:]), axis=1)
            end_floor = floor * np.max(np.abs(window[-tail:]))
            if before is not None:
                reason = "response of an earlier hit still ringing"
                detail = (f"{names[before[0] + 1]} at {100 * before[1]:.0f} % of this hit's peak when it started")
            elif np.any(end > np.maximum(decay_fraction * np.maximum(top, np.finfo(float).tiny), end_floor)):
                j = int(np.argmax(end / np.maximum(top, np.finfo(float).tiny)))
                reason = "response not decayed within the record"
                detail = (f"{names[j + 1]} at {100 * end[j] / top[j]:.0f} % of its peak at the end of the "
                          f"{record_length}-sample record")
            elif k + 1 < trigger.size and nxt - pre < s + record_length:
                reason = "next hit within the record"
                detail = f"the next hit starts {1e3 * (nxt - t) / fs:.0f} ms after this one"
        if reason is not None:
            accepted[k] = False
            item = {"hit": k + 1, "time_s": float(trigger[k] / fs), "reason": reason}
            if detail:
                item["detail"] = detail
            rejected.append(item)
        else:
            pulse_len = max(pulse_len, ev[0][1] - ev[0][0] + 1)
    return Hits(trigger, accepted, start, record_length, int(pulse_len), threshold, rejected, overloads)


def reject_pulses_the_window_cuts(hits: Hits, force: np.ndarray, force_window: np.ndarray, sample_rate_hz: float,
                                  labels: list[dict]) -> Hits:
    """``hits`` with every accepted hit rejected as a ``"double hit"`` whose record holds a force pulse where
    ``force_window`` cuts the force.

    A pulse below the trigger threshold (a light rebound, a second tap at a few per cent of the hit) is no hit of
    its own, so :func:`find_hits` keeps its hit. A force window then takes its force out of the record while the
    response to it stays: the estimate divides a response to two pulses by the force of one, a bias that grows
    with the signal-to-noise ratio (a 2 % rebound 60 ms after a hit, force noise 0.2 % of the peak, moved a
    mode's frequency by 14 standard errors). A rectangular window keeps such a pulse and needs no check.

    Parameters
    ----------
    hits : Hits
        Hits found in ``force``.
    force : ndarray, shape (n_samples,)
        The force channel as the hits were found in it (any offset).
    force_window : ndarray, shape (record_length,)
        The window the force records take (1 over the hit, falling to 0 after it).
    sample_rate_hz : float
        Samples per second, Hz.
    labels : list of dict
        Per hit (in ``hits.trigger_index``'s order): the fields its rejection carries besides ``reason`` and
        ``detail`` (``hit``, ``time_s``, for takes ``take`` and ``take_name``).
    """
    weakened = np.flatnonzero(np.asarray(force_window) < 1)
    if weakened.size == 0 or not hits.accepted.any():
        return hits
    cut_from = int(weakened[0])
    centred = force - np.median(force)
    peak_of = {k: float(np.max(np.abs(centred[hits.record_start[k]:hits.record_start[k] + cut_from])))
               for k in np.flatnonzero(hits.accepted)}
    width = BASELINE_PULSES * max(1, hits.pulse_samples)
    # the matched filter of a half-sine pulse as long as the hits', of unit energy: white noise keeps its
    # standard deviation through it, a pulse of that shape gains √(Σ sin²) (1.4 for 4 samples), and a lone
    # spike of the noise is spread below it
    kernel = np.sin(np.pi * (np.arange(max(2, hits.pulse_samples)) + 0.5) / max(2, hits.pulse_samples))
    kernel /= np.linalg.norm(kernel)
    accepted = hits.accepted.copy()
    rejected = list(hits.rejected)
    for k, peak in peak_of.items():
        first = int(hits.record_start[k]) + cut_from
        segment = centred[first:int(hits.record_start[k]) + hits.record_length]
        residual = segment - _local_level(segment, width)
        filtered = np.convolve(residual, kernel, mode="same")
        # the noise of this record's own stretch (takes at other levels, other gains, have their own), as
        # filtered (a coloured noise gains through the filter as the pulse does); for a noise-free force, 1e-4 of
        # the hit's peak (a pulse that small biases the FRF by 1e-4 of itself, below any measured FRF's noise)
        noise = float(np.median(np.abs(filtered - np.median(filtered)))) / 0.6745
        outside = np.abs(filtered) > max(CUT_PULSE_SIGMAS * noise, 1e-4 * peak)
        runs = [(a, b) for a, b in _pulses(outside, 1) if b > a]
        if not runs:
            continue
        a, b = max(runs, key=lambda run: np.max(np.abs(residual[run[0]:run[1] + 1])))
        after_ms = 1e3 * (first + a - int(hits.trigger_index[k])) / float(sample_rate_hz)
        accepted[k] = False
        rejected.append({**labels[k], "reason": "double hit",
                         "detail": f"a pulse of {100 * np.max(np.abs(residual[a:b + 1])) / peak:.1f} % of the hit's "
                                   f"peak {after_ms:.0f} ms after it, below the trigger threshold: the force window "
                                   "cuts its force, the record keeps its response (window 'rect' keeps both)"})
    if accepted.sum() == hits.accepted.sum():
        return hits
    rejected.sort(key=lambda item: (item.get("take", 0), item["hit"]))
    return replace(hits, accepted=accepted, rejected=rejected)


def _local_level(values: np.ndarray, width: int) -> np.ndarray:
    """The straight line fitted by least squares to ``values`` over ``width`` samples centred on each (fewer at
    the ends), at that sample: a slow drift's level, unbiased where the drift is straight (also at the ends, where
    a mean over the samples on one side would lag a sloping level)."""
    index = np.arange(values.size, dtype=float)
    sums = [np.concatenate(([0.0], np.cumsum(v))) for v in (np.ones(values.size), index, index**2, values,
                                                             index * values)]
    low = np.maximum(np.arange(values.size) - width // 2, 0)
    high = np.minimum(np.arange(values.size) + width // 2 + 1, values.size)
    n, k, kk, v, kv = (total[high] - total[low] for total in sums)
    spread = n * kk - k**2
    slope = np.divide(n * kv - k * v, spread, out=np.zeros(values.size), where=spread > 0)
    return (v - slope * k) / n + slope * index
