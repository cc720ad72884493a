"""Clipping and overload of a recorder's channels.

A converter that saturates writes its extreme code for as long as the signal
stays beyond it: the record shows *flat tops*, runs of samples exactly equal to
the channel's largest (or smallest) value. A smooth peak never repeats its
extreme value exactly in floating point (noise, or the sampling phase, make
neighbours differ), so a run of two or more identical samples at the extreme is
the mark of clipping. On data quantised to coarse codes a smooth, oversampled
peak can repeat its top code; there a flat top counts only when the samples on
either side of it stand more than four codes below it (a clipped pulse enters
and leaves the rail steeply). Once a channel's rail is known, every sample on it
is an overload, even a single one (a short hit that touched the rail).

A declared full scale (``TimeRecord.full_scale``, ``estimate_frf(full_scale=)``)
makes every sample at or beyond 99.9 % of it an overload as well.

A hammer hit sampled in two or three samples touches the rail in one: no run, but
every clipped hit then peaks at the very same value, where hits that were not
clipped scatter in amplitude by several per cent. For a record of hits
(``repeated_peaks=``) the extreme reached by that many separate samples, each a
steep peak, is a rail as well, unless the samples beside them are equal too (the
same pulse repeated exactly, as a record without noise can hold).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ChannelOverload", "find_overloads", "FULL_SCALE_FRACTION"]

#: a sample at or beyond this fraction of a declared full scale is an overload
FULL_SCALE_FRACTION = 0.999
#: samples beside a flat top must lie this many quantisation steps below it
_STEEP_CODES = 4
#: equal peaks of a record of hits mark a rail when the samples beside them spread by more than this fraction of
#: the peak (hits differ by per cents; a pulse repeated without noise differs by rounding, 1e-16 of it)
_FLANK_SPREAD = 1e-6


@dataclass(frozen=True)
class ChannelOverload:
    """Where one channel was clipped or overloaded.

    Attributes
    ----------
    channel : int
        Index of the channel in the arrays given.
    mask : ndarray of bool, shape (n_samples,)
        The overloaded samples.
    level : float
        The rail (the flat tops' value) or the declared full scale, in the channel's unit.
    how : str
        ``"flat tops"`` (clipped at the recorder's extreme) or ``"full scale"`` (at or beyond
        99.9 % of the declared full scale).
    longest_run : int
        Longest run of overloaded samples.
    """

    channel: int
    mask: np.ndarray
    level: float
    how: str
    longest_run: int

    @property
    def samples(self) -> int:
        return int(self.mask.sum())

    def describe(self, name: str, unit: str | None = None) -> str:
        """``force clipped at 90 N (flat tops, 12 samples, longest 3)``."""
        unit = f" {unit}" if unit else ""
        what = "clipped at" if self.how == "flat tops" else "at or beyond 99.9 % of its full scale"
        return (f"{name} {what} {self.level:.6g}{unit} ({self.how}, {self.samples} sample(s), longest run "
                f"{self.longest_run})")


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(start, stop) of each run of True (stop exclusive)."""
    edges = np.diff(mask.astype(np.int8), prepend=0, append=0)
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def _quantisation_step(x: np.ndarray) -> float:
    """The smallest gap between distinct sample values (one code of a quantised record)."""
    values = np.unique(x)
    if values.size < 2:
        return 0.0
    return float(np.min(np.diff(values)))


def _rail(x: np.ndarray, extreme: float, repeated_peaks: int | None = None) -> np.ndarray | None:
    """Samples on the rail at ``extreme`` when the channel shows a flat top there (or, with ``repeated_peaks``,
    reaches it in that many separate samples), else None."""
    on = x == extreme
    if np.count_nonzero(on) < 2 and (repeated_peaks is None or repeated_peaks > 1):
        return None  # one sample at the extreme: neither a flat top nor repeated peaks (most records end here)
    starts, stops = _runs(on)
    long = (stops - starts) >= 2
    # separate peaks on the rail, each counted (a run of one sample at a hit's peak), when there are enough
    peaks = repeated_peaks is not None and starts.size >= repeated_peaks
    if peaks:
        long[:] = True
    if not long.any():
        return None
    step = _quantisation_step(x)
    steep = np.ones(starts.size, bool)
    sides = []
    for k in np.flatnonzero(long):
        before = x[starts[k] - 1] if starts[k] > 0 else None
        after = x[stops[k]] if stops[k] < x.size else None
        sides.append((before, after))
        if step > 0:
            steep[k] = all(v is None or abs(v - extreme) > _STEEP_CODES * step for v in (before, after))
    flat_tops = long & steep & ((stops - starts) >= 2)
    # equal peaks whose flanks are equal too (to rounding) are equal pulses (a record without noise), not pulses of
    # several heights cut at one level
    flanks = np.array([[np.nan if v is None else v for v in pair] for pair in sides], float)
    spread = np.nanmax(np.nanmax(flanks, axis=0) - np.nanmin(flanks, axis=0)) if flanks.size else 0.0
    cut = peaks and steep.sum() >= repeated_peaks and spread > _FLANK_SPREAD * abs(extreme)
    if not (flat_tops.any() or cut):
        return None
    return on


def find_overloads(signals, full_scale=None, repeated_peaks: int | None = None) -> list[ChannelOverload]:
    """Clipped (flat tops at the extreme) and overloaded (declared full scale) samples, per channel.

    Parameters
    ----------
    signals : array_like, shape (n_channels, n_samples), or a sequence of channels
        Each channel is read on its own (an h5py dataset or memmap row by row).
    full_scale : float or sequence of (float or None), optional
        Declared full scale of every channel (one value) or of each channel, in the
        channels' units; None where unknown.
    repeated_peaks : int, optional
        A record of separate events (hammer hits): the extreme reached exactly by this many
        separate samples is a rail too (hits clipped in one sample each).

    Returns
    -------
    list of ChannelOverload
        One per channel found clipped or overloaded (none for a clean record).
    """
    if np.ndim(signals) == 1 or not hasattr(signals, "__len__"):
        signals = np.atleast_2d(np.asarray(signals, dtype=float))
    n_ch = len(signals)
    if full_scale is None or np.ndim(full_scale) == 0:
        levels = [full_scale] * n_ch
    else:
        levels = list(full_scale)
        if len(levels) != n_ch:
            raise ValueError(f"full_scale has {len(levels)} values; expected one per channel ({n_ch})")
    found = []
    for k in range(n_ch):
        ch = np.asarray(signals[k], dtype=float).ravel()  # one channel at a time: streamed arrays stay streamed
        if ch.size == 0:
            continue
        mask = np.zeros(ch.size, bool)
        how, level = None, 0.0
        scale = levels[k]
        if scale is not None and np.isfinite(scale) and scale > 0:
            beyond = np.abs(ch) >= FULL_SCALE_FRACTION * scale
            if beyond.any():
                mask |= beyond
                how, level = "full scale", float(scale)
        for extreme in (float(ch.max()), float(ch.min())):
            if extreme == 0:
                continue
            rail = _rail(ch, extreme, repeated_peaks)
            if rail is not None:
                mask |= rail
                if how is None:
                    how, level = "flat tops", abs(extreme)
        if mask.any():
            starts, stops = _runs(mask)
            found.append(ChannelOverload(k, mask, level, how, int(np.max(stops - starts))))
    return found
