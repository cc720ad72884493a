"""Periodic excitation whose period fits the records: no leakage to model.

A periodic chirp, a pseudo-random or periodic random signal, or a sine held at each line repeats with a
period the analyst makes divide the record length. In steady state the response repeats with it, every
record holds whole periods of both, and the DFT of a rectangular record is the FRF itself at its lines:
the leakage a random excitation leaves (a record's response holding the decay of forces from before it,
the lag window ρ(τ) = 1 − τ/N and the decay cut off at the record's end, :mod:`modal.leakage`) is not
there. Modelling it anyway takes a bias out that the data do not hold: a periodic chirp measured exactly
gave its modes' damping 15 % low, 36 of their standard errors.

:func:`repeats_every` tells whether channels repeat with a period that divides the record;
:func:`shortest_period` whether that period is a fraction of the record: then only every k-th line of the
records' transform holds the excitation, and the lines between hold its noise alone.
"""
from __future__ import annotations

import numpy as np

__all__ = ["repeats_every", "shortest_period", "REPEAT_LIMIT"]

#: channels whose samples one record length apart differ by less than this fraction of twice their power
#: repeat (a period dividing the record): white noise of 10 % of a channel's RMS leaves 0.01; samples of a
#: stationary random signal a record apart are independent, 1; a periodic signal whose period does not divide
#: the record, tens of per cent
REPEAT_LIMIT = 0.05


def repeats_every(signals, length: int, limit: float = REPEAT_LIMIT) -> bool:
    """Whether every channel repeats, to within its noise, ``length`` samples on (in steady state).

    Parameters
    ----------
    signals : array_like, shape (n_channels, n_samples)
    length : int
        Samples per record.
    limit : float
        Largest mean square of x[n + length] − x[n], relative to twice the channel's mean square about
        its mean, that still counts as repeating.

    Returns
    -------
    bool
        False when the channels hold fewer than two records.
    """
    for channel in signals:
        x = np.asarray(channel, dtype=float)
        if x.size < 2 * length:
            return False
        x = x - np.mean(x)
        power = 2.0 * float(np.mean(x**2))
        if power <= 0 or float(np.mean((x[length:] - x[:-length]) ** 2)) > limit * power:
            return False
    return True


def shortest_period(signals, length: int, largest_count: int = 16) -> int:
    """The fewest samples, ``length`` / k for k = 1 … ``largest_count`` dividing ``length``, after which every
    channel repeats (:func:`repeats_every`); ``length`` when the channels repeat only after a whole record
    (or not at all)."""
    period = length
    for count in range(2, largest_count + 1):
        if length % count == 0 and repeats_every(signals, length // count):
            period = length // count
    return period
