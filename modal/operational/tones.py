"""Machine tones told apart from structural modes.

A running machine's harmonics are sinusoids in every channel: the identification finds them as
poles of (nearly) zero damping, as stable over the orders as any mode. Three pieces of evidence
say that a pole is a tone (Brincker, Andersen & Møller, IMAC 2000; Jacobsen 2006):

* its damping is indistinguishable from zero (ζ < 3σ_ζ) and below :data:`TONE_DAMPING`, where few structures
  are (for a method without error bars, below it). A small damping resolved from zero is measured decay: a
  lightly damped mode's, or a line's beat or wander, which only the record's length tells apart (below);
* the response band-passed around it is not Gaussian: a sinusoid's kurtosis is 1.5 where a
  structural mode driven by random forces gives 3 (:data:`KURTOSIS_LIMIT`). The band spans
  :data:`MIN_BANDWIDTH_TIME` lines around the strongest line the pole stands for: within its half-power
  band, or, for a pole of nearly zero damping, within the lags' resolution (a tone that wanders, or two
  close lines the correlation lags cannot tell apart, give one pole between them), so that one tone
  dominates the band;
* it lies on a harmonic ``k × f₀`` of the running speed (``rotor_speed_hz``, or the fundamental
  that the tones found by the first two pieces of evidence share).

A pole with two of them is a tone; a mode on a harmonic without further evidence stays a mode,
flagged ``harmonic``.

The kurtosis alone makes a tone where the record resolves the pole's damping: a structural mode of damping
ratio ζ at ω = 2πf holds ζωT decay times in a record of T seconds, and with at least
:data:`MIN_DECAYS` of them (ζ less three of its standard errors) its response band-passed around its
strongest line is Gaussian (a random mode with fewer looks like a slowly drifting sinusoid: its kurtosis
falls below the limit in 16 % of records at 2 decay times, 5 % at 4, never in 1000 at 16). Such a pole
whose band is a sinusoid's stands for a line whose apparent damping is not a structure's: two tones closer
than the correlation lags resolve (one pole between them, damped by their beat, as the shipped record's
181.7/182.8 Hz pair), or a tone whose frequency wanders. A pole with a sinusoid's band that the record does
not resolve so and that has no second piece of evidence stays a mode, flagged ``tone_like``: a tone, or a
mode so lightly damped that the record holds few of its decay times, which one record cannot tell apart.

Mains hum (a ground loop, an unshielded cable: 50 or 60 Hz and its harmonics, often on a few channels
only) is a line too, but it need not look undamped to the identification: a mode within
:data:`HUM_TOLERANCE` of a multiple of 50 or 60 Hz where some channel's spectrum holds a line
:data:`HUM_LINE_RATIO` times above the lines around it is flagged ``mains_hum`` (:func:`flag_mains_hum`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..flags import HARMONIC_SIGMAS, HARMONIC_TOLERANCE, KURTOSIS_LIMIT, MIN_DECAYS
from ..parallel import map_over_threads
from .inputs import Prepared
from .pole import PoleEstimate

__all__ = ["separate_tones", "warn_speed_off_the_tones", "nearly_undamped", "zero_damping", "resolved_decays", "band_kurtosis", "strongest_line_hz", "harmonic_of",
           "KURTOSIS_LIMIT", "TONE_DAMPING", "MIN_DECAYS", "flag_mains_hum", "line_ratio", "MAINS_HZ", "HUM_TOLERANCE", "HUM_LINE_RATIO"]

#: a pole whose damping ratio is below this with its error (ζ + 3σ_ζ) has nearly zero damping
TONE_DAMPING = 0.002
ZERO_DAMPING_SIGMAS = 3.0
#: the band-pass spans at least this many lines, i.e. this bandwidth times the record's duration (Hz·s)
MIN_BANDWIDTH_TIME = 64.0
#: ... and, for a pole whose line is looked for over a wider range, this many times wider in turn up to that
#: range: a tone whose frequency wanders (a machine's speed) over more than the narrowest band moves in and out
#: of it (kurtosis above 3) but keeps one amplitude in a band that holds its wander (1.5)
BAND_STEP = 4.0
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


def zero_damping(estimate: PoleEstimate) -> bool:
    """Whether a pole's damping ratio is indistinguishable from zero (ζ < 3σ_ζ) and below :data:`TONE_DAMPING`
    (where few structures are), the tone's evidence. A damping resolved from zero, however small, is measured
    decay: a mode's, or a line's beat or wander, which only the record's length tells apart
    (:func:`resolved_decays`). Where the method gives no error bars (EFDD), the damping ratio below
    :data:`TONE_DAMPING` stands for it."""
    zeta, std = estimate.damping_ratio, estimate.std_damping_ratio
    if not np.isfinite(std):
        return nearly_undamped(estimate)
    return bool(zeta < min(ZERO_DAMPING_SIGMAS * std, TONE_DAMPING))


def resolved_decays(estimate: PoleEstimate, duration_s: float) -> float:
    """The decay times (ζ − 3σ_ζ)·2πf·T a structural mode of the estimate's damping ratio, less three of its
    standard errors, holds in a record of ``duration_s`` (σ_ζ taken as 0 where the method gives none; NaN where
    it measures no damping)."""
    if not estimate.damping_known or not np.isfinite(estimate.damping_ratio):
        return float("nan")
    std = estimate.std_damping_ratio if np.isfinite(estimate.std_damping_ratio) else 0.0
    return float((estimate.damping_ratio - ZERO_DAMPING_SIGMAS * std) * abs(estimate.pole) * duration_s)


def _judged_channel(estimate: PoleEstimate, prepared: Prepared) -> int:
    """The channel an estimate's band is judged on: where it is strongest against the rest."""
    return int(np.argmax(np.abs(estimate.shape) / prepared.scale))


def _channel_spectrum(prepared: Prepared, channel: int) -> tuple[np.ndarray, int]:
    """A record-long FFT of one channel, centred: (spectrum, samples transformed).

    The samples transformed are the record's first ``n``, ``n`` the longest FFT length at most the record's
    whose factors are 2, 3 and 5 (at most a few tenths of a percent shorter): a length with a large prime factor
    would cost ten times as much (a record of 999 983 samples, prime). The mean comes off in double precision
    as the samples are rounded to single (an offset costs no precision); the scale is left on (the tests only
    compare lines of one channel)."""
    from scipy.fft import prev_fast_len, rfft

    n = prev_fast_len(prepared.n_samples, real=True)
    centred = np.empty(n, np.float32)
    np.subtract(prepared.signals[channel, :n], prepared.mean[channel], out=centred, casting="same_kind")
    return rfft(centred, overwrite_x=True), n


def _band_is_peaky(estimate: PoleEstimate, prepared: Prepared, spectra: dict, resolution_hz: float | None) -> bool:
    """Whether the response band-passed around one estimate's strongest line is non-Gaussian (kurtosis below
    :data:`KURTOSIS_LIMIT`); ``spectra`` holds the FFT of each channel judged on
    (:func:`_judged_channel`) and the samples it transformed (:func:`_channel_spectrum`).

    The band spans :data:`MIN_BANDWIDTH_TIME` lines around the strongest line of the channel where the pole is
    strongest, looked for within the pole's half-power band ±ζf (or three of its frequency's standard errors, at
    least 2 lines) or, for a pole of nearly zero (or unknown) damping, within the lags' resolution
    ``resolution_hz``: a line there is what the pole stands for (two lines the lags cannot tell apart give one
    pole between them, damped by their beat), and a band holding one line of them is a sinusoid's where a band
    holding both beats (kurtosis 2.25). A line farther from a damped pole is not the pole's: a tone beside a
    structural mode does not make the mode a tone. Bands :data:`BAND_STEP` times wider in turn, up to the
    range searched, are judged too (a wandering tone)."""
    zeta = estimate.damping_ratio if np.isfinite(estimate.damping_ratio) else 0.0
    f = estimate.natural_frequency_hz
    spectrum, n = spectra[_judged_channel(estimate, prepared)]
    duration_s = n / prepared.sample_rate_hz  # of the stretch transformed
    std_f = estimate.std_frequency_hz if np.isfinite(estimate.std_frequency_hz) else 0.0
    search = max(max(zeta, 0.0) * f, ZERO_DAMPING_SIGMAS * std_f, 2.0 / duration_s)
    if (nearly_undamped(estimate) or not estimate.damping_known) and resolution_hz:
        search = max(search, resolution_hz / 2)
    centre = strongest_line_hz(spectrum, n, prepared.sample_rate_hz, f - search, f + search)
    width = MIN_BANDWIDTH_TIME / duration_s
    while True:  # bands 4 times wider in turn, up to the search's: a tone that wanders fills the band that holds it
        kurtosis = band_kurtosis(spectrum, n, prepared.sample_rate_hz, centre, width)
        if np.isfinite(kurtosis) and kurtosis < KURTOSIS_LIMIT:
            return True
        width *= BAND_STEP
        if width > 2 * search:
            return False


def separate_tones(estimates: list[PoleEstimate], prepared: Prepared, rotor_speed_hz: float | None,
                   resolution_hz: float | None = None, workers: int = 1):
    """Which estimates are machine tones; the modes left on a harmonic flagged ``harmonic``, those whose band is
    a sinusoid's though the record cannot tell them from a lightly damped mode flagged ``tone_like``.

    ``resolution_hz``, the frequency resolution of the method's correlation lags (sample rate / lags):
    a pole of nearly zero damping (or unknown damping) is judged on the strongest line within half of it
    on either side. None: on the pole's own band.

    ``workers`` threads transform the channels judged on (a record-long FFT each).

    Returns
    -------
    (is_tone, estimates) : (list of bool, list of PoleEstimate)
        The estimates in the same order, those that are not tones with their flags added.
    """
    # a record-long FFT per channel judged on, shared by its poles; the channels' on threads in turn
    judged = sorted({_judged_channel(e, prepared) for e in estimates})
    spectra = dict(zip(judged, map_over_threads(lambda ch: _channel_spectrum(prepared, ch), judged, workers)))
    peaky = [_band_is_peaky(e, prepared, spectra, resolution_hz) for e in estimates]

    def is_peaky(k: int) -> bool:
        return peaky[k]

    undamped = [zero_damping(e) for e in estimates]
    # a pole whose damping the record resolves as a structure's would be Gaussian: its kurtosis alone decides
    resolving = [resolved_decays(e, prepared.duration_s) >= MIN_DECAYS for e in estimates]
    fundamental = rotor_speed_hz
    if fundamental is None:
        # the tones the data show clearly, whose comb is looked for: non-Gaussian and nearly undamped (below
        # TONE_DAMPING), or with a damping the record resolves (or non-Gaussian where the method measures no
        # damping); a comb is one more piece of evidence, never the only one
        clear = [(e.natural_frequency_hz, e.std_frequency_hz) for k, e in enumerate(estimates)
                 if (nearly_undamped(e) or resolving[k] or not e.damping_known) and is_peaky(k)]
        fundamental = _fundamental([f for f, _ in clear], [s for _, s in clear])
    is_tone, out = [], []
    for k, estimate in enumerate(estimates):
        on_comb = fundamental is not None and harmonic_of(estimate.natural_frequency_hz,
                                                          estimate.std_frequency_hz, fundamental) > 0
        others = undamped[k] + on_comb  # two of the three pieces of evidence make a tone
        tone = others == 2 or ((others == 1 or resolving[k]) and is_peaky(k))
        is_tone.append(tone)
        added = set() if tone else {f for f, holds in (("harmonic", on_comb), ("tone_like", is_peaky(k))) if holds}
        out.append(replace(estimate, flags=estimate.flags | added) if added else estimate)
    if rotor_speed_hz is not None:
        warn_speed_off_the_tones([e for e, t in zip(estimates, is_tone) if t], rotor_speed_hz, prepared.source)
    return is_tone, out


def warn_speed_off_the_tones(tones: list[PoleEstimate], rotor_speed_hz: float, source: str) -> bool:
    """Warn (and return True) when the record's machine tones (mains lines left aside) lie on no harmonic of
    the running speed given: a nameplate speed where the motor slips (an induction motor runs 1-5 % slow under
    load), rpm given as Hz, or the tones of another machine. The ``harmonic`` flags then follow a comb that is
    not the record's; the fundamental the tones share, when two or more do, is named."""
    from ..errors import QualityWarning, warn

    own = [t for t in tones if not mains_lines_near(t.natural_frequency_hz)]
    if not own or any(harmonic_of(t.natural_frequency_hz, t.std_frequency_hz, rotor_speed_hz) for t in own):
        return False
    frequencies = sorted(t.natural_frequency_hz for t in own)
    fundamental = _fundamental([t.natural_frequency_hz for t in own], [t.std_frequency_hz for t in own])
    shared = f"; they are harmonics of {fundamental:.5g} Hz ({60 * fundamental:.5g} rpm)" if fundamental else ""
    warn(f"{source}: the machine tones found ({', '.join(f'{f:.5g}' for f in frequencies)} Hz) lie on no harmonic "
         f"of the running speed given, {rotor_speed_hz:.5g} Hz ({60 * rotor_speed_hz:.5g} rpm){shared}: check the "
         "speed (a motor's slip under load, rpm given as Hz, another machine's tones); the 'harmonic' flags follow "
         "the speed given", QualityWarning)
    return True


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


def mains_lines_near(frequency_hz: float, std_hz: float = 0.0) -> list[float]:
    """The mains harmonics (Hz) within :data:`HUM_TOLERANCE` of ``frequency_hz``, or 3 of its standard errors."""
    return [k * mains for mains in MAINS_HZ for k in range(1, MAINS_HARMONICS + 1)
            if abs(frequency_hz - k * mains) <= max(HUM_TOLERANCE * k * mains, 3 * std_hz)]


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
        lines = mains_lines_near(f, std)
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
