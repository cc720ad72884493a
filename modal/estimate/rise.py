"""Does a response channel rise with the hits? Its energy after each trigger against its level before.

A hammer test gives a few records (3 hits are common), and with n records chance gives every line a coherence
of 1/n on average: the mean coherence of :mod:`.unrelated` tells a response from a dead sensor only where many
of the driven lines are coherent, and is not made with fewer than 3 hits. A hit's response, though, is
concentrated in time: the structure rings for a while after the trigger and the channel held only its
noise (and the previous hit's tail) before it. A live sensor's energy rises after every hit; a dead one's does
not.

For each channel, the power at the triggers (windows of :data:`AFTER_FRACTION` of the record centred on each
accepted hit's trigger, K_a of them: the Hann taper below then weighs the response's start, its largest part,
fully) is set against the power just before them (windows of the same length ending :data:`GUARD_PULSES` pulse
widths before each after-window, clear of every hit's after-window, K_b of them).
Each window, less its mean (a drifting offset is no response), is Hann-windowed and transformed; the power is
summed over its lines but 0 Hz, the Nyquist line and the tones of the before-windows' mean spectrum
(mains hum: :func:`.unrelated.tones`, ±2 lines). A tone's power is nearly the same in every window: counted as
noise it would leave a window a few degrees of freedom and hide any rise. For a dead channel, stationary
Gaussian noise of smooth spectrum P, a window's summed power E has variance Σ_f P_f² Σ_m |c(m)|² (c the Hann
window's line correlation, :func:`modal.noise_model.window_line_correlation`: 1.94), that is
ν = 2 (Σ P)² / (1.94 Σ P²) degrees of freedom (L / 1.94 for white noise over L samples; fewer where the
noise is coloured), estimated from the before-windows with Σ P² over pairs of different windows (unbiased).
The log of the ratio of the mean powers R = Ē_a / Ē_b is then nearly normal with mean 0 and variance
2 / (K_a ν) + 2 / (K_b ν): the channel rises when log R lies :data:`RISE_SIGMAS` standard errors above 0.

The before-windows read the noise the after-windows would hold were the channel dead; anything else there (a
previous hit's ringing, a response's slow AC-coupled recovery) only raises Ē_b, which makes a live channel
look less live, never a dead one live.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..noise_model import window_line_correlation
from .unrelated import near_tones, tones

__all__ = ["RiseTest", "rise_tests", "RISE_SIGMAS", "AFTER_FRACTION", "GUARD_PULSES", "MIN_BEFORE_SAMPLES"]

#: standard errors of log R above 0 that make a channel rise with the hits: a dead channel's log R is nearly
#: normal (its windows hold tens to hundreds of degrees of freedom), so 5 are passed by chance less than once
#: in a million channels, and an error of 2 in the variance (a mis-estimated ν) still leaves chance below 1e-3
RISE_SIGMAS = 5.0
#: the after-window is this fraction of the hit record, centred on the trigger: a lightly damped mode keeps
#: ringing past it, a well damped one has decayed within it; a shorter window would hold fewer degrees of freedom
AFTER_FRACTION = 1.0 / 8.0
#: the before-window ends this many pulse widths before the after-window, and starts as many after the previous
#: hit's after-window (the force, and so the response, starts below the trigger level)
GUARD_PULSES = 2
#: a line of the before-windows' mean spectrum above this many times its neighbours' median is a tone. Lines
#: are dropped by the before-windows' own power, so a noise line dropped by chance biases R upwards: one
#: exponential variable exceeds 10 times the median of its kind (6.9 times its mean) with probability 1e-3, the
#: mean of 2 with 1e-6 (one before-window of 128 lines: a noise line lost in one dead channel of eight, Ē_b
#: then low by about 5 %); a weaker tone holds too little of the power to matter
TONE_RATIO = 10.0
#: before-windows shorter than this are not read (the periodogram of fewer samples tells ν poorly)
MIN_BEFORE_SAMPLES = 32


@dataclass(frozen=True)
class RiseTest:
    """One response channel's power after the hits against its power before them.

    Attributes
    ----------
    output : int
        Response channel (from 0).
    ratio : float
        R, the mean power after the triggers over that before them (tones left out).
    log_se : float
        Standard error of log R for a dead channel.
    hits : int
        After-windows (accepted hits) read.
    quiet_windows : int
        Before-windows read.
    window_s : float
        Length of each after- and before-window, s.
    """

    output: int
    ratio: float
    log_se: float
    hits: int
    quiet_windows: int
    window_s: float

    @property
    def sigmas(self) -> float:
        """Standard errors of log R above 0."""
        return float(np.log(self.ratio) / self.log_se) if self.ratio > 0 else -np.inf

    @property
    def rises(self) -> bool:
        """The channel's power rises after the hits by more than :data:`RISE_SIGMAS` standard errors."""
        return self.sigmas >= RISE_SIGMAS


def _spectra(signal: np.ndarray, starts: np.ndarray, length: int) -> np.ndarray:
    """|Hann-windowed transform|² of the windows of ``length`` samples from ``starts`` of every row, each less
    its mean: (rows, windows, lines)."""
    index = starts[:, None] + np.arange(length)[None, :]
    cut = signal[:, index]
    cut = (cut - cut.mean(axis=2, keepdims=True)) * np.hanning(length)
    return np.abs(np.fft.rfft(cut, axis=2)) ** 2


def _degrees_of_freedom(quiet: np.ndarray, spread: float) -> np.ndarray:
    """ν of one window's summed power per row, from its before-windows' line powers (rows, windows, lines)."""
    k = quiet.shape[1]
    total = quiet.sum(axis=1)
    if k >= 2:  # Σ over pairs of different windows: unbiased for P², whatever each window's own scatter
        squares = (total ** 2 - np.sum(quiet ** 2, axis=1)) / (k * (k - 1))
    else:  # one window: E[P̂²] = 2 P² for a line's periodogram
        squares = total ** 2 / 2.0
    mean = total / k
    with np.errstate(divide="ignore", invalid="ignore"):
        nu = 2.0 * mean.sum(axis=1) ** 2 / (spread * np.maximum(squares.sum(axis=1), 0.0))
    return np.where(np.isfinite(nu), np.clip(nu, 1.0, 2.0 * quiet.shape[2]), 1.0)


def rise_tests(response: np.ndarray, trigger_index: np.ndarray, accepted: np.ndarray, record_length: int,
               pulse_samples: int, sample_rate_hz: float) -> list[RiseTest]:
    """Each response channel's power after the accepted hits' triggers against its power before them.

    Parameters
    ----------
    response : ndarray, shape (n_outputs, n_samples)
        Response channels (offsets removed or not: each window's mean is taken out).
    trigger_index : ndarray of int
        Every hit's trigger sample, accepted or not (no before-window overlaps a hit).
    accepted : ndarray of bool
        The hits estimated from (their after-windows are read).
    record_length : int
        Samples per hit record.
    pulse_samples : int
        Longest force pulse, samples.
    sample_rate_hz : float
        Samples per second, Hz.

    Returns
    -------
    list of RiseTest
        One per output; empty where no after-window or no before-window of at least
        :data:`MIN_BEFORE_SAMPLES` samples fits.
    """
    response = np.atleast_2d(response)
    n = response.shape[1]
    triggers = np.sort(np.asarray(trigger_index, dtype=np.int64))
    taken = np.asarray(trigger_index, dtype=np.int64)[np.asarray(accepted, bool)]
    guard = GUARD_PULSES * max(int(pulse_samples), 1)
    after = max(MIN_BEFORE_SAMPLES, int(record_length * AFTER_FRACTION))
    # an after-window must end before the next hit's force starts
    following = np.searchsorted(triggers, taken, side="right")
    limit = np.where(following < triggers.size, triggers[np.minimum(following, triggers.size - 1)] - guard, n)
    taken = taken[taken + after <= limit]
    if taken.size == 0:
        return []
    # each after-window is centred on its trigger (the Hann taper's full weight on the response's start, its
    # largest part); each before-window ends a guard before that, from the previous hit's after-window on (or the
    # record's start). Where no trigger has a full window's room, both windows shrink to the most room there is
    previous = np.concatenate([[0], triggers[:-1] + after // 2 + guard])
    room = (triggers - guard - previous) // 3 * 2  # a before-window and the after-window's first half
    length = int(min(after, room.max())) // 2 * 2
    if length < MIN_BEFORE_SAMPLES:
        return []
    ends = triggers[room >= length] - guard - length // 2
    taken = taken[taken >= length // 2]
    if taken.size == 0:
        return []
    quiet = _spectra(response, ends - length, length)
    loud = _spectra(response, taken - length // 2, length)
    kept = np.ones(quiet.shape[2], bool)
    kept[0] = kept[-1] = False  # 0 Hz (the mean taken out) and the Nyquist line
    kept = kept[None, :] & ~np.array([near_tones(row) for row in tones(quiet.mean(axis=1), TONE_RATIO)])
    quiet = np.where(kept[:, None, :], quiet, 0.0)
    loud = np.where(kept[:, None, :], loud, 0.0)
    spread = float(np.sum(np.abs(window_line_correlation(np.hanning(length))) ** 2))
    nu = _degrees_of_freedom(quiet, spread)
    power_before = quiet.sum(axis=2).mean(axis=1)
    power_after = loud.sum(axis=2).mean(axis=1)
    k_a, k_b = taken.size, ends.size
    log_se = np.sqrt(2.0 / (k_a * nu) + 2.0 / (k_b * nu))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(power_before > 0, power_after / power_before, np.where(power_after > 0, np.inf, 0.0))
    window_s = length / float(sample_rate_hz)
    return [RiseTest(o, float(ratio[o]), float(log_se[o]), int(k_a), int(k_b), window_s)
            for o in range(response.shape[0])]
