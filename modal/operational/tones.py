"""Machine tones told apart from structural modes.

A running machine's harmonics are sinusoids in every channel: the identification finds them as
poles of (nearly) zero damping, as stable over the orders as any mode. Three pieces of evidence
say that a pole is a tone (Brincker, Andersen & Møller, IMAC 2000; Jacobsen 2006):

* its damping is nearly zero: below :data:`TONE_DAMPING` (where few structures are) either with its
  error (ζ + 3σ_ζ) or indistinguishable from zero (ζ < 3σ_ζ);
* the response band-passed around it is not Gaussian: a sinusoid's kurtosis is 1.5 where a
  structural mode driven by random forces gives 3 (:data:`KURTOSIS_LIMIT`). The band is the pole's
  own (4 half-power widths) or :data:`MIN_BANDWIDTH_TIME` lines, whichever is wider; a pole of nearly
  zero damping stands for the strongest line within its resolution (a tone that wanders, or two close
  lines the correlation lags cannot tell apart, give one pole between them), and the band is centred
  on that line, so that the tone dominates it;
* it lies on a harmonic ``k × f₀`` of the running speed (``rotor_speed_hz``, or the fundamental
  that the tones found by the first two pieces of evidence share).

A pole with two of them is a tone; a mode on a harmonic without further evidence stays a mode,
flagged ``harmonic``.

Mains hum (a ground loop, an unshielded cable: 50 or 60 Hz and its harmonics, often on a few channels
only) is a line too, but it need not look undamped to the identification: a mode within
:data:`HUM_TOLERANCE` of a multiple of 50 or 60 Hz where some channel's spectrum holds a line
:data:`HUM_LINE_RATIO` times above the lines around it is flagged ``mains_hum`` (:func:`flag_mains_hum`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..flags import HARMONIC_SIGMAS, HARMONIC_TOLERANCE
from .inputs import Prepared
from .pole import PoleEstimate

__all__ = ["separate_tones", "nearly_undamped", "band_kurtosis", "strongest_line_hz", "harmonic_of", "KURTOSIS_LIMIT",
           "TONE_DAMPING", "flag_mains_hum", "line_ratio", "MAINS_HZ", "HUM_TOLERANCE", "HUM_LINE_RATIO"]

#: a pole whose damping ratio is below this with its error (ζ + 3σ_ζ) has nearly zero damping
TONE_DAMPING = 0.002
ZERO_DAMPING_SIGMAS = 3.0
#: kurtosis of the band-passed response below which it holds a sinusoid: 3 for Gaussian narrow-band
#: response, 1.5 for a pure tone, 2.25 for two equal tones. The estimate (from the band's lines, never
#: below 1.5) has a short lower tail: for Gaussian response over :data:`MIN_BANDWIDTH_TIME` = 64 lines
#: its 10⁻⁴ quantile is 2.27 with a flat spectrum and 2.18 with a mode's bell spanning the band
#: (10⁵ draws each; ``tests/modal/operational/test_tones.py`` checks the margin)
KURTOSIS_LIMIT = 1.95
#: the band-pass spans at least this many lines, i.e. this bandwidth times the record's duration (Hz·s)
MIN_BANDWIDTH_TIME = 64.0
#: the mains frequencies (Hz); their harmonics up to :data:`MAINS_HARMONICS` are where hum lies
MAINS_HZ = (50.0, 60.0)
MAINS_HARMONICS = 6
#: a mode within this fraction of a mains harmonic may be its hum: hum of 0.5 RMS on two channels of the shipped
#: 58b record (band 30-400 Hz) came out as a "mode" at 50.34 Hz, 0.7 % off, damping 1.4 ± 0.6 %
HUM_TOLERANCE = 0.01
#: a line whose power (Hann-windowed periodogram of a stretch of :data:`HUM_SAMPLES`) stands this many times above
#: the median of the lines 4-40 bins around it is a line, not a mode's bell: a noise line's ratio is exponential
#: (above 100 with probability e^-69), the shipped real record's strongest at a mains harmonic is 41 (100 Hz), a
#: mode of 1 % damping gives a few
HUM_LINE_RATIO = 100.0
HUM_SAMPLES = 1 << 15


def strongest_line_hz(spectrum: np.ndarray, n_samples: int, sample_rate_hz: float, low_hz: float,
                      high_hz: float) -> float:
    """Frequency (Hz) of the strongest line of an ``rfft`` ``spectrum`` (``n_samples`` long) between ``low_hz``
    and ``high_hz`` (the nearest line when none lies between)."""
    spacing = sample_rate_hz / n_samples
    lo = min(max(int(np.ceil(low_hz / spacing)), 1), spectrum.size - 1)
    hi = max(min(int(np.floor(high_hz / spacing)), spectrum.size - 1), lo)
    return float((lo + int(np.argmax(np.abs(spectrum[lo:hi + 1])))) * spacing)


def band_kurtosis(spectrum: np.ndarray, n_samples: int, sample_rate_hz: float, centre_hz: float,
                  bandwidth_hz: float) -> float:
    """Kurtosis E[x⁴]/E[x²]² of a signal band-passed (ideal) to ``centre_hz ± bandwidth_hz/2``, from its
    ``rfft`` ``spectrum`` (``n_samples`` long).

    The band-passed signal is the real part of its complex envelope z, and for a narrow band
    E[x⁴]/E[x²]² = (3/2) E|z|⁴/(E|z|²)²; the envelope needs only as many samples as the band has lines,
    so it comes from one short inverse FFT of the band's lines.
    """
    spacing = sample_rate_hz / n_samples
    lo = max(int(np.ceil((centre_hz - bandwidth_hz / 2) / spacing)), 1)
    hi = min(int(np.floor((centre_hz + bandwidth_hz / 2) / spacing)), spectrum.size - 1)
    if hi < lo:
        return float("nan")
    lines = spectrum[lo:hi + 1]
    from scipy.fft import next_fast_len

    z = np.fft.ifft(lines, n=next_fast_len(4 * lines.size))
    power = np.abs(z) ** 2
    mean = power.mean()
    return float(1.5 * np.mean(power**2) / mean**2) if mean > 0 else float("nan")


def harmonic_of(frequency_hz: float, std_hz: float, fundamental_hz: float) -> int:
    """The harmonic number k ≥ 1 when ``frequency_hz`` lies on k·``fundamental_hz`` (within
    :data:`modal.flags.HARMONIC_TOLERANCE` of it or :data:`modal.flags.HARMONIC_SIGMAS` of its errors), else 0."""
    k = int(round(frequency_hz / fundamental_hz))
    if k < 1:
        return 0
    allowed = max(HARMONIC_TOLERANCE * frequency_hz, HARMONIC_SIGMAS * (std_hz if np.isfinite(std_hz) else 0.0))
    return k if abs(frequency_hz - k * fundamental_hz) <= allowed else 0


def _fundamental(tones_hz: list[float], stds: list[float]) -> float | None:
    """The running speed that explains the most of two or more tones as its harmonics (the lowest such),
    or None."""
    if len(tones_hz) < 2:
        return None
    best = None
    for f in tones_hz:
        for k in range(1, 5):
            f0 = f / k
            hits = sum(harmonic_of(g, s, f0) > 0 for g, s in zip(tones_hz, stds))
            if hits >= 2 and (best is None or hits > best[0] or (hits == best[0] and f0 > best[1])):
                best = (hits, f0)
    return None if best is None else best[1]


def nearly_undamped(estimate: PoleEstimate) -> bool:
    """Whether a pole's damping ratio lies below :data:`TONE_DAMPING`, with its error (ζ + 3σ_ζ) or
    indistinguishable from zero (ζ < 3σ_ζ)."""
    zeta = estimate.damping_ratio
    margin = ZERO_DAMPING_SIGMAS * (estimate.std_damping_ratio if np.isfinite(estimate.std_damping_ratio) else 0.0)
    return bool(zeta < TONE_DAMPING and (zeta + margin < TONE_DAMPING or zeta < margin))


def _band_is_peaky(estimate: PoleEstimate, prepared: Prepared, spectra: dict, resolution_hz: float | None) -> bool:
    """Whether the response band-passed around one estimate is non-Gaussian (kurtosis below
    :data:`KURTOSIS_LIMIT`); ``spectra`` caches each channel's FFT."""
    from scipy.fft import rfft

    zeta = estimate.damping_ratio if np.isfinite(estimate.damping_ratio) else 0.0
    f = estimate.natural_frequency_hz
    channel = int(np.argmax(np.abs(estimate.shape) / prepared.scale))  # where it is strongest against the rest
    width = max(4 * max(zeta, 0.0) * f, MIN_BANDWIDTH_TIME / prepared.duration_s)
    n = prepared.n_samples
    if channel not in spectra:
        spectra[channel] = rfft(prepared.channel(channel))
    centre = f
    if (nearly_undamped(estimate) or not estimate.damping_known) and resolution_hz:
        centre = strongest_line_hz(spectra[channel], n, prepared.sample_rate_hz, f - resolution_hz / 2,
                                   f + resolution_hz / 2)
    kurtosis = band_kurtosis(spectra[channel], n, prepared.sample_rate_hz, centre, width)
    return bool(np.isfinite(kurtosis) and kurtosis < KURTOSIS_LIMIT)


def separate_tones(estimates: list[PoleEstimate], prepared: Prepared, rotor_speed_hz: float | None,
                   resolution_hz: float | None = None):
    """Which estimates are machine tones, and the modes left on a harmonic flagged ``harmonic``.

    ``resolution_hz``, the frequency resolution of the method's correlation lags (sample rate / lags):
    a pole of nearly zero damping (or unknown damping) is judged on the strongest line within half of it
    on either side. None: on the pole's own frequency.

    Returns
    -------
    (is_tone, estimates) : (list of bool, list of PoleEstimate)
        The estimates in the same order, those on a harmonic that are not tones with the flag added.
    """
    spectra: dict = {}
    peaky: dict[int, bool] = {}

    def is_peaky(k: int) -> bool:  # the kurtosis costs a record-long FFT: taken only where it decides
        if k not in peaky:
            peaky[k] = _band_is_peaky(estimates[k], prepared, spectra, resolution_hz)
        return peaky[k]

    undamped = [nearly_undamped(e) for e in estimates]
    fundamental = rotor_speed_hz
    if fundamental is None:
        # the tones the data show clearly: nearly undamped and non-Gaussian (or non-Gaussian where the method
        # measures no damping)
        clear = [(e.natural_frequency_hz, e.std_frequency_hz) for k, e in enumerate(estimates)
                 if (undamped[k] or not e.damping_known) and is_peaky(k)]
        fundamental = _fundamental([f for f, _ in clear], [s for _, s in clear])
    is_tone, out = [], []
    for k, estimate in enumerate(estimates):
        on_comb = fundamental is not None and harmonic_of(estimate.natural_frequency_hz,
                                                          estimate.std_frequency_hz, fundamental) > 0
        others = undamped[k] + on_comb  # two of the three pieces of evidence make a tone
        tone = others == 2 or (others == 1 and is_peaky(k))
        is_tone.append(tone)
        out.append(replace(estimate, flags=estimate.flags | {"harmonic"}) if on_comb and not tone else estimate)
    return is_tone, out


def line_ratio(samples: np.ndarray, sample_rate_hz: float, frequency_hz: float) -> float:
    """Power of the strongest of the three lines nearest ``frequency_hz`` over the median of the lines 4-40 bins
    around it, in a Hann-windowed periodogram of the first :data:`HUM_SAMPLES` of ``samples`` (NaN when the
    record is too short or the frequency too near an end of the spectrum)."""
    from scipy.fft import rfft

    stretch = np.asarray(samples[:HUM_SAMPLES], dtype=np.float64)
    stretch = stretch - stretch.mean()
    power = np.abs(rfft(stretch * np.hanning(stretch.size))) ** 2
    k = int(round(frequency_hz * stretch.size / sample_rate_hz))
    if k - 40 < 1 or k + 41 > power.size:
        return float("nan")
    around = np.concatenate([power[k - 40:k - 3], power[k + 4:k + 41]])
    floor = np.median(around)
    return float(power[k - 1:k + 2].max() / floor) if floor > 0 else float("inf")


def flag_mains_hum(estimates: list[PoleEstimate], prepared: Prepared) -> list[PoleEstimate]:
    """The estimates, those on a mains line (:data:`HUM_TOLERANCE` or 3 standard errors of a multiple of 50 or
    60 Hz, where some channel holds a line :data:`HUM_LINE_RATIO` above its surroundings) flagged ``mains_hum``,
    each such line warned of naming the channels that hold it. The spectra are taken only where a mode lies near
    a mains harmonic."""
    from ..errors import QualityWarning, warn
    from .screen import _channel_label

    out = []
    for estimate in estimates:
        f = estimate.natural_frequency_hz
        std = estimate.std_frequency_hz if np.isfinite(estimate.std_frequency_hz) else 0.0
        lines = [k * mains for mains in MAINS_HZ for k in range(1, MAINS_HARMONICS + 1)
                 if abs(f - k * mains) <= max(HUM_TOLERANCE * k * mains, 3 * std)]
        humming = []
        for line in lines:
            ratios = [line_ratio(prepared.signals[ch], prepared.sample_rate_hz, line)
                      for ch in range(prepared.n_channels)]
            channels = [ch for ch, r in enumerate(ratios) if r >= HUM_LINE_RATIO]
            if channels:
                humming.append(line)
                listing = ", ".join(_channel_label(prepared.names, ch) for ch in channels)
                warn(f"{prepared.source}: {listing} hold{'s' if len(channels) == 1 else ''} a line at {line:g} Hz "
                     f"(mains), {max(ratios[ch] for ch in channels):.3g} times the spectrum around it, where a mode "
                     f"was found at {f:.5g} Hz: electrical hum (a ground loop, an unshielded cable) rather than a "
                     "structural mode; its frequency, damping and shape may be the hum's (flagged mains_hum): "
                     "ground the sensors' cables at one point or leave those channels out", QualityWarning)
        out.append(replace(estimate, flags=estimate.flags | {"mains_hum"}) if humming else estimate)
    return out
