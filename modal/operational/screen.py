"""Lab mistakes in an ambient record that the identification itself would not notice.

Covariance-driven identification finds the modes' frequencies robustly from a damaged record;
what suffers are the shapes and the errors, silently. These checks name the damage:

* :func:`check_units`: channels in different quantities or units (a velocity among accelerations,
  a channel in V among channels in m/s²) make the shape mix units: refused.
* :func:`screen_samples`: a channel that holds one value for a run of samples (a dropout, a stuck
  converter, a gap filled with zeros) or is clipped at its converter's rail: warned, naming the
  channel and where, since its correlations (and so its shape entries) are biased by the share of
  the record affected.
* :func:`unresponsive_channels`: a channel whose shape entry is indistinguishable from zero in every
  mode found does not respond to the structure's modes: a disconnected or dead sensor, a channel
  that is not a response (a force, a tachometer pulse), or a sensor on a node of every mode: warned.
* :func:`held_factor`: a channel that repeats each sample h times (sampled at a rate h times lower than the
  record says, written out by holding each sample) holds images of its modes above its real Nyquist
  frequency: a band reaching above it is refused (:func:`check_held`).
* :func:`transient_kurtosis`: a record of transients (hammer hits, shocks, bursts) rather than stationary
  random response: its modes are flagged ``non_stationary`` and the record warned of.

The sample checks look at every :data:`STRIDE`-th sample first (a run of
:data:`MIN_STUCK_SAMPLES` identical samples, or a clipped channel's repeated extreme, shows there)
and read the whole channel only where they saw something: a clean record of 64 channels × 10⁶
samples costs them about 10 ms.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError, QualityWarning, warn
from .selection import DETERMINED_SIGMAS

__all__ = ["check_units", "screen_samples", "screen_findings", "stuck_runs", "unresponsive_channels", "transient_kurtosis",
           "warn_transients", "held_factor", "check_held", "STRIDE", "MIN_STUCK_SAMPLES", "NODE_SIGMAS", "TRANSIENT_SIGMAS", "TRANSIENT_KURTOSIS"]

#: the sample checks first look at every STRIDE-th sample of each channel
STRIDE = 128
#: a run of at least this many identical samples (seen for certain through the stride) is a dropout or a
#: stuck converter: a measured response never repeats a value exactly for that long, while quantisation
#: of a smooth, oversampled peak repeats a code a few samples at most (the shipped real record: no two
#: neighbouring samples are equal)
MIN_STUCK_SAMPLES = 2 * STRIDE
#: a shape entry within this many of its standard errors of zero does not show the channel moving in the
#: mode (for Gaussian errors a moving entry falls inside with probability below 0.3 %): the complement of a
#: determined entry (:data:`modal.operational.selection.DETERMINED_SIGMAS`)
NODE_SIGMAS = DETERMINED_SIGMAS
#: a record whose (median) channel's kurtosis lies this many of its standard errors above a Gaussian response's 3 is
#: not stationary random response. Over 450 Gaussian records (one or two modes of 0.2-2 % damping, 30-60 s, the
#: shortest and most lightly damped the identification accepts) the deviation in standard errors had SD 0.72 and
#: never exceeded 3.1; hammer records (hits every 2-15 s, the responses alone) lie 8-280 above it...
TRANSIENT_SIGMAS = 6.0
#: ... and at least this far from 3 (a Gaussian response's kurtosis; a sinusoid's 1.5): a deviation too small to
#: bias the covariances, however well determined, is not named
TRANSIENT_KURTOSIS = 4.0
#: the hold check reads this many samples of each channel from its start
HELD_SAMPLES = 1 << 14
#: ... and calls a channel held when at least this fraction of its neighbouring samples repeat exactly, every one
#: of them within a run of one length h (a measured response sampled at its rate repeats a value between two
#: neighbours rarely: never in the shipped real record; a coarsely quantised one often, but in runs of any length)
HELD_FRACTION = 0.45
#: the kurtosis is judged on at most this many channels (spread over the record's channels; transients reach them
#: all) ...
TRANSIENT_CHANNELS = 8
#: ... and on at most about this many samples of each (every k-th: the band's responses span several samples; its
#: standard error's correlation sum, one FFT of twice this length, costs about 10 ms)
TRANSIENT_SAMPLES = 1 << 16


def _channel_label(names, ch: int) -> str:
    name = names[ch] if names and ch < len(names) else None
    plain = name is None or name in (str(ch), str(ch + 1))  # an array's index or a file's number says nothing more
    return f"channel {ch + 1}" + ("" if plain else f" ({name})")


def check_units(record) -> str | None:
    """Refuse a time record whose channels measured different quantities or are in different units.

    Parameters
    ----------
    record : TimeRecord
        After reading (units the readers know are already converted to SI).

    Returns
    -------
    str or None
        The quantity every channel measured (None when the file says for none).

    Raises
    ------
    ParameterError
        Channels of different quantities, or some in a unit the toolkit does not convert (or none)
        among others in a known one: the shapes would compare numbers in different units.
    """
    units = [(q, u) for q, u in zip(record.quantities, record.units)]
    if len(set(units)) <= 1:
        return units[0][0] if units else None
    groups: dict[tuple, list[int]] = {}
    for k, key in enumerate(units):
        groups.setdefault(key, []).append(k)
    listing = "; ".join(f"{', '.join(str(k + 1) for k in chans)} in {u or 'no unit'}"
                        + (f" ({q})" if q else "") for (q, u), chans in groups.items())
    raise ParameterError(f"{record.source}: the channels are in different units ({listing}); expected one quantity "
                         "in one unit on every channel, or the shapes compare numbers in different units (give "
                         "each channel's unit in the file, e.g. 'a1 [g]', 'a2 [m/s^2]', which the reader converts, "
                         "or leave the odd channels out)")


def stuck_runs(row: np.ndarray, min_samples: int = MIN_STUCK_SAMPLES, coarse: np.ndarray | None = None
               ) -> list[tuple[int, int]]:
    """(first sample, length) of every run of at least ``min_samples`` identical samples in ``row``.

    A run that long holds two neighbours of the stride ``min_samples // 2`` with one value; only
    those places are read in full. ``coarse``: ``row[::min_samples // 2]`` when the caller has it.
    """
    step = max(1, min_samples // 2)
    coarse = row[::step] if coarse is None else coarse
    candidates = np.flatnonzero(coarse[1:] == coarse[:-1])
    runs: list[tuple[int, int]] = []
    end = -1
    for i in candidates:
        start = int(i) * step
        if start < end:
            continue  # inside the run found last
        value = row[start]
        if not np.all(row[start:start + step + 1] == value):
            continue
        first = start
        while first > 0 and row[first - 1] == value:
            first -= 1
        end = start + step + 1
        while end < row.size and row[end] == value:
            end += 1
        if end - first >= min_samples:
            runs.append((first, end - first))
    return runs


def _clipped(row: np.ndarray, coarse: np.ndarray):
    """The channel's overload (flat tops at its extreme) when its ``coarse`` samples (every
    :data:`STRIDE`-th) repeat an extreme, else None."""
    if coarse.size < 2:
        return None
    top, bottom = coarse.max(), coarse.min()
    if np.count_nonzero(coarse == top) < 2 and np.count_nonzero(coarse == bottom) < 2:
        return None
    from ..estimate.overload import find_overloads

    found = find_overloads(row[None, :])
    return found[0] if found else None


def screen_samples(signals: np.ndarray, sample_rate_hz: float, names=(), source: str = "<array>",
                   findings: list[str] | None = None) -> None:
    """Warn of dropouts (runs of :data:`MIN_STUCK_SAMPLES` or more identical samples) and clipping.

    Parameters
    ----------
    signals : ndarray, shape (n_channels, n_samples)
        The record as read (before centring or decimation).
    sample_rate_hz : float
    names : sequence of str, optional
    source : str
    findings : list of str, optional
        :func:`screen_findings` of these samples, when looked for already (on another thread).

    Warns
    -----
    QualityWarning
        One per channel with a dropout or a clipped extreme, naming the channel, where and how much.
    """
    for message in screen_findings(signals, sample_rate_hz, names, source) if findings is None else findings:
        warn(message, QualityWarning)


def screen_findings(signals: np.ndarray, sample_rate_hz: float, names=(), source: str = "<array>") -> list[str]:
    """The warnings :func:`screen_samples` gives, in order: a clipped channel's as each channel is read, then one per
    longest dropout, naming the channels that hold it."""
    n = signals.shape[1]
    messages = []
    stuck: dict[tuple[int, int], list[tuple[int, int, int]]] = {}  # longest run → (channel, runs, samples)
    for ch in range(signals.shape[0]):
        row = signals[ch]
        coarse = np.ascontiguousarray(row[::STRIDE])  # one strided pass serves both checks
        runs = stuck_runs(row, MIN_STUCK_SAMPLES, coarse)
        if runs:
            longest = max(runs, key=lambda r: r[1])
            stuck.setdefault(longest, []).append((ch, len(runs), sum(r[1] for r in runs)))
        overload = _clipped(row, coarse)
        if overload is not None:
            messages.append(f"{source}: {overload.describe(_channel_label(names, ch))}, {100 * overload.samples / n:.2g} % of "
                            "the record: its shape entries are too small and its spectrum distorted where it clipped; lower "
                            "the gain or use a sensor of a larger range")
    for (first, length), found in stuck.items():
        listing = ("every channel" if len(found) == signals.shape[0] > 1 else
                   ", ".join(_channel_label(names, ch) for ch, _, _ in found))
        count, total = max(f[1] for f in found), max(f[2] for f in found)
        value = signals[found[0][0], first]
        more = f"; {count} such runs, {100 * total / n:.2g} % of the record" if count > 1 else \
            f" ({100 * total / n:.2g} % of the record)"
        messages.append(f"{source}: {listing} hold{'s' if len(found) == 1 or len(found) == signals.shape[0] else ''} the value {value:.6g} for {length} samples "
                        f"({length / sample_rate_hz:.4g} s) from sample {first + 1}{more}: a dropout or a stuck converter, not "
                        "a response; the correlations and shape entries are biased by that share; cut the record around it or "
                        "leave the channel out")
    return messages


def unresponsive_channels(result) -> list[int]:
    """Channels whose shape entry lies within :data:`NODE_SIGMAS` standard errors of zero in every mode.

    Needs at least two modes with shape errors (one mode may have a node at any channel); empty otherwise.
    """
    modes = [m for m in result if m.std.mode_shape is not None]
    if len(modes) < 2:
        return []
    shapes = np.abs(np.array([m.mode_shape for m in modes]))
    errors = np.array([np.asarray(m.std.mode_shape, float) for m in modes])
    with np.errstate(invalid="ignore"):
        still = shapes <= NODE_SIGMAS * errors
    return [int(ch) for ch in np.flatnonzero(np.all(still, axis=0))]


def warn_unresponsive(result, source: str) -> list[int]:
    """:func:`unresponsive_channels`, each warned of; returns them."""
    channels = unresponsive_channels(result)
    if channels:
        names = list(result.settings.get("channel_names") or [])
        listing = ", ".join(_channel_label(names, ch) for ch in channels)
        warn(f"{source}: {listing} moves in none of the {len(result)} modes beyond {NODE_SIGMAS:g} standard errors "
             "of its shape entry: a disconnected or dead sensor, a channel that is not a response (a force, a "
             "tachometer pulse) or a sensor on a node of every mode; check it, or leave it out (its shape entries "
             "read as nodes)", QualityWarning)
    return channels


def _gaussian_kurtosis_std(centred: np.ndarray) -> float:
    """Standard error of the sample kurtosis of ``centred`` were it stationary Gaussian with its own correlation:
    ``sqrt(24 Σ_k ρ_k⁴ / n)`` over all lags k (the sum counts the samples that are not independent)."""
    from scipy.fft import irfft, next_fast_len, rfft

    n = centred.size
    power = np.abs(rfft(centred, next_fast_len(2 * n))) ** 2
    acf = irfft(power)[:n]
    rho = acf / acf[0]
    return float(np.sqrt(24 * (2 * np.sum(rho**4) - 1) / n))


def transient_kurtosis(prepared) -> tuple[float, float, int]:
    """The kurtosis of the record's median channel (of up to :data:`TRANSIENT_CHANNELS`), its standard error under
    stationary Gaussian response, and the channel (0-based).

    Stationary response to random forces is Gaussian (kurtosis 3, less with machine tones); a record of hammer
    hits, shocks or bursts, each ringing down, has most of its energy in a few stretches: a kurtosis far above 3
    in every channel. Judged on every k-th sample (at most :data:`TRANSIENT_SAMPLES`) of the band's record."""
    signals = prepared.signals
    n_channels, n = signals.shape
    step = max(1, int(np.ceil(n / TRANSIENT_SAMPLES)))
    channels = np.unique(np.linspace(0, n_channels - 1, min(n_channels, TRANSIENT_CHANNELS)).round().astype(int))
    kurtosis = []
    for ch in channels:
        centred = np.asarray(signals[ch, ::step], dtype=np.float64) - prepared.mean[ch]
        squares = centred * centred
        kurtosis.append(float(np.mean(squares * squares) / np.mean(squares) ** 2))
    middle = int(np.argsort(kurtosis)[len(kurtosis) // 2])
    ch = int(channels[middle])
    centred = np.asarray(signals[ch, ::step], dtype=np.float64) - prepared.mean[ch]
    return kurtosis[middle], _gaussian_kurtosis_std(centred), ch


def warn_transients(prepared, measured: tuple[float, float, int] | None = None) -> bool:
    """Whether the record holds transients rather than stationary response (:func:`transient_kurtosis` above both
    :data:`TRANSIENT_SIGMAS` standard errors and :data:`TRANSIENT_KURTOSIS`), warned of; ``measured``: its
    :func:`transient_kurtosis` when measured already (on another thread)."""
    kurtosis, std, ch = transient_kurtosis(prepared) if measured is None else measured
    excess = kurtosis - 3.0
    if not (excess > TRANSIENT_SIGMAS * std and kurtosis > TRANSIENT_KURTOSIS):
        return False
    warn(f"{prepared.source}: the record is not stationary random response: {_channel_label(prepared.names, ch)} "
         f"has kurtosis {kurtosis:.3g} ({excess / std:.0f} standard errors above a Gaussian response's 3): hammer "
         "hits, shocks or bursts ringing down (or steps: a dropout to zero); operational analysis assumes stationary random forces, and its "
         "frequencies, damping and error bars are biased (modes flagged non_stationary): for a hammer test with a "
         "force channel use python -m modal fit --impact, otherwise cut the transients out or record the machine "
         "running steadily", QualityWarning)
    return True


def held_factor(row: np.ndarray) -> int:
    """h when ``row`` repeats each sample h times (h ≥ 2: all but one in every h neighbouring pairs equal, the
    changes exactly h samples apart) over its first :data:`HELD_SAMPLES`, else 1."""
    head = np.asarray(row[:HELD_SAMPLES])
    if head.size < 16:
        return 1
    same = head[1:] == head[:-1]
    if same.mean() < HELD_FRACTION:
        return 1
    changes = np.flatnonzero(~same)
    if changes.size < 8:
        return 1  # a stuck channel (screen_samples names it), not a held one
    gaps = np.diff(changes)
    h = int(np.median(gaps))
    return h if h >= 2 and np.all(gaps % h == 0) and np.mean(gaps == h) > 0.5 else 1


def check_held(signals: np.ndarray, sample_rate_hz: float, band_hz, src: str, names=()) -> None:
    """Refuse a band reaching above the real Nyquist frequency of channels that repeat each sample
    (:func:`held_factor`): there they hold images of the modes below it, which the identification reports as
    modes (a 50 Hz record written at 100 Hz by holding gave 'modes' at 38.6 and 38.8 Hz, images of 11.4 and 11.2)."""
    factors = [held_factor(row) for row in signals]
    held = [ch for ch, h in enumerate(factors) if h > 1]
    if not held:
        return
    h = max(factors[ch] for ch in held)
    nyquist = sample_rate_hz / (2 * h)
    if band_hz[1] <= nyquist:
        return
    listing = "every channel" if len(held) == signals.shape[0] else ", ".join(_channel_label(names, ch) for ch in held)
    raise ParameterError(f"{src}: {listing} repeat{'' if 1 < len(held) < signals.shape[0] else 's'} each sample {h} times: sampled at "
                         f"{sample_rate_hz / h:g} Hz and written at {sample_rate_hz:g} Hz, so above {nyquist:g} Hz "
                         f"{'it holds' if len(held) == 1 else 'they hold'} images of the modes below, not modes; "
                         f"expected a band up to {nyquist:g} Hz ('band_hz', --band; the band asked for reaches "
                         f"{band_hz[1]:g} Hz), or the record at its own rate")
