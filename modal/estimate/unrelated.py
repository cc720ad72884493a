"""Is a response channel related to the force at all? Its mean coherence against chance.

A response channel whose sensor is unplugged, dead or wired to another input records noise unrelated to
the force. Its FRF is noise, and the fits weigh it by that noise, so nothing else shows it. Under no
relation, and for Gaussian noise in the response (conditioned on the force's spectra, any spectra), the
(multiple) coherence of one line over n independent records with q inputs is Beta(q, n − q) distributed:
mean q/n, variance q(n − q)/(n²(n + 1)) (Goodman 1963; Bendat & Piersol, *Random Data*, ch. 9). Overlapping
segments share records: n is taken as n over Welch's variance factor (:func:`.spectra.overlap_variance_factor`).

One line decides little (with 30 records chance reaches 0.1 on 5 lines in 100, and a real channel whose noise
equals its peak has median coherence 0.06-0.08, benchmarks/REPORT.md); the mean over the L driven lines does. Its
standard error under no relation is σ/√L times √(1 + 2 Σ_m r̄_m), r̄_m the mean correlation of the coherence of
lines k and k + m. The cross-spectrum S_yx of lines k and k + m, given the force, correlates by c_out(m) g_km, the
response window's line correlation (:func:`modal.noise_model.window_line_correlation`) times the force's own over
the records, g_km = Σ conj(X_k) X_{k+m} / √(S_xx,k S_xx,k+m); the squared magnitudes of correlated complex
Gaussians correlate by the square of that, r_km = |c_out(m) g_km|². Hann on random excitation: |c(1)|⁴ = 16/81 and
|c(2)|⁴ = 1/1296, a factor 1.40 (L/1.4 independent lines); a rectangular window 1; an exponential window on a
hammer's smooth force spectrum (g ≈ 1) several.

A channel is unrelated when its mean coherence lies less than :data:`RELATED_SIGMAS` standard errors above
chance: a channel of the structure's response has the modes' lines coherent and lies tens to hundreds of
standard errors above (benchmarks/REPORT.md, "A response channel unrelated to the force").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import QualityWarning, warn
from .excitation_noise import POWERED_LINE_FRACTION

__all__ = ["ChanceTest", "chance_tests", "tones", "near_tones", "warn_unrelated", "RELATED_SIGMAS", "MIN_RECORDS",
           "MIN_LINES"]

#: a channel whose mean coherence is more than this many standard errors above chance is related to the force.
#: Under no relation the mean over hundreds of lines is nearly normal: 5 standard errors are passed by chance
#: less than once in a million channels, and a model of the lines' correlation that is off by a factor 2 in
#: variance still leaves chance below 1e-3
RELATED_SIGMAS = 5.0
#: a force's line whose power exceeds this multiple of the median of its 2 × TONE_HALF_WIDTH + 1 neighbours is a
#: tone (mains hum, a shaker's harmonic), and lines within TONE_SPREAD of it are not counted (a Hann window's main
#: lobe). The lines are chosen from the force alone, and under no relation the coherence given the force is
#: Beta whatever it is: dropping lines costs a related channel a little evidence, and leaves chance as it was. A
#: random force's line averaged over 3 records exceeds 3 times its median with probability 0.014 (15 records:
#: 1e-7); a hammer's spectrum is smooth over far more lines
TONE_RATIO = 3.0
TONE_HALF_WIDTH = 8
TONE_SPREAD = 2
#: driven lines below which the test is not made: the mean of fewer is not near normal (with 3 records one line's
#: coherence is Beta(1, 2), skewness 0.57), and a force of a few lines (a sine) is not what it is made for
MIN_LINES = 16
#: records (segments or hits) below which the test is not made: with q + 1 records or fewer the coherence is
#: 1 (or nearly) on every line whatever the channel holds
MIN_RECORDS = 3


@dataclass(frozen=True)
class ChanceTest:
    """One response channel's mean coherence over the driven lines, against what chance gives.

    Attributes
    ----------
    output : int
        Response channel (from 0).
    mean_coherence : float
        Mean (multiple) coherence over the driven lines.
    chance : float
        Its mean under no relation, q/n_eff.
    chance_se : float
        Its standard error under no relation.
    records : int
        Records (segments or hits) averaged.
    lines : int
        Driven lines averaged over.
    """

    output: int
    mean_coherence: float
    chance: float
    chance_se: float
    records: int
    lines: int

    @property
    def sigmas(self) -> float:
        """Standard errors above chance."""
        return (self.mean_coherence - self.chance) / self.chance_se

    @property
    def detectable_share(self) -> float:
        """The share of the driven lines that, fully coherent, would lift the mean to
        :data:`RELATED_SIGMAS` standard errors above chance: how much relation the test can see."""
        return min(1.0, RELATED_SIGMAS * self.chance_se / (1.0 - self.chance))

    @property
    def unrelated(self) -> bool:
        """Not above chance by :data:`RELATED_SIGMAS` standard errors."""
        return self.sigmas < RELATED_SIGMAS

    def as_dict(self, channel: str) -> dict:
        """The fields a user reads (``EstimatedFRF.unrelated``), the channel by its name."""
        return {"channel": channel, "mean_coherence": self.mean_coherence, "chance": self.chance,
                "chance_se": self.chance_se, "records": self.records, "lines": self.lines}


def tones(power: np.ndarray, ratio: float = TONE_RATIO) -> np.ndarray:
    """The lines of each row of ``power`` (rows, lines) above ``ratio`` times the median of their
    2 × :data:`TONE_HALF_WIDTH` + 1 neighbours: a tone's, not a broad spectrum's."""
    padded = np.pad(power, ((0, 0), (TONE_HALF_WIDTH, TONE_HALF_WIDTH)), mode="edge")
    local = np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * TONE_HALF_WIDTH + 1, axis=1), axis=2)
    return power > ratio * local


def near_tones(tone: np.ndarray) -> np.ndarray:
    """The lines within :data:`TONE_SPREAD` of a line of ``tone`` (bool, lines), the tone's own included."""
    return np.convolve(tone, np.ones(2 * TONE_SPREAD + 1), mode="same") > 0


def chance_tests(sums, multiple_coherence: np.ndarray, output_correlation: np.ndarray,
                 overlap_factor: float = 1.0) -> list[ChanceTest]:
    """Each response channel's mean coherence over the driven lines, against chance.

    Parameters
    ----------
    sums : modal.estimate.spectra.SpectralSums
        The estimate's sums (``sxx``, ``n_records`` and, one input, ``sxx_lag``).
    multiple_coherence : ndarray, shape (n_outputs, n_lines)
        Multiple coherence of each output on the inputs (the ordinary coherence with one input).
    output_correlation : ndarray
        The response window's line correlation c_out(m), m = 0 … N − 1
        (:func:`modal.noise_model.window_line_correlation`).
    overlap_factor : float
        Welch's variance factor of overlapping segments (1 without overlap).

    Returns
    -------
    list of ChanceTest
        One per output; empty with fewer than :data:`MIN_RECORDS` records, q + 1 effective records or
        fewer, or fewer than :data:`MIN_LINES` driven lines.
    """
    n_in = sums.sxx.shape[0]
    n_eff = sums.n_records / overlap_factor
    if sums.n_records < MIN_RECORDS or n_eff <= n_in + 1:
        return []
    power = np.einsum("iif->if", sums.sxx).real
    n_lines = power.shape[1]
    # 0 Hz and the Nyquist line have real spectra (another distribution), and a force's offset leaks into
    # line 1 under a Hann window: the lines counted, and the force's largest, are those from line 2 on
    inner = np.zeros(n_lines, bool)
    inner[2:-1] = True
    if not np.any(inner):
        return []
    largest = power[:, inner].max(axis=1, keepdims=True)
    driven = inner & np.all(power >= POWERED_LINE_FRACTION * largest, axis=0) & np.all(power > 0, axis=0)
    # a tone in a force (mains hum, a shaker's harmonic) is no excitation of the structure, and a dead channel
    # that picks up the same hum is coherent with it there: such lines are not counted
    driven &= ~near_tones(np.any(tones(power), axis=0))
    lines = int(driven.sum())
    if lines < MIN_LINES:
        return []
    chance = n_in / n_eff
    variance = n_in * (n_eff - n_in) / (n_eff ** 2 * (n_eff + 1))
    # Σ over lag m of the mean correlation of the driven lines' coherence, r_km = |c_out(m) g_km|²
    spread = 1.0
    lags = 0 if sums.sxx_lag is None else sums.sxx_lag.shape[0]
    for m in range(1, min(lags, n_lines - 1) + 1):
        both = driven[:-m] & driven[m:]
        with np.errstate(divide="ignore", invalid="ignore"):
            g2 = np.abs(sums.sxx_lag[m - 1, :-m][both]) ** 2 / (power[0, :-m][both] * power[0, m:][both])
        spread += 2.0 * float(np.sum(np.minimum(abs(output_correlation[m]) ** 2 * g2, 1.0))) / lines
    # past the lags summed (several inputs: every lag), |g| ≤ 1 bounds r by |c_out(m)|², over the pairs of
    # driven lines m apart (their count by one autocorrelation)
    size = 1 << int(np.ceil(np.log2(2 * n_lines)))
    spectrum = np.fft.rfft(driven.astype(float), size)
    pairs = np.rint(np.fft.irfft(spectrum * np.conj(spectrum), size)[:n_lines])
    rest = np.arange(n_lines) > lags
    rest[0] = False
    c2 = np.abs(output_correlation[:n_lines]) ** 2
    spread += 2.0 * float(np.sum(c2[rest] * pairs[rest])) / lines
    se = float(np.sqrt(variance * spread / lines))
    coherence = np.atleast_2d(multiple_coherence)
    return [ChanceTest(o, float(np.mean(coherence[o, driven])), float(chance), se, int(sums.n_records), lines)
            for o in range(coherence.shape[0])]


def warn_unrelated(tests: list[ChanceTest], names, n_inputs: int, impact: bool, source: str,
                   rises=()) -> list[dict]:
    """Warn of each response channel that neither test finds related to the force (a
    :class:`~modal.errors.QualityWarning` naming it and its figures) and return them as
    ``EstimatedFRF.unrelated`` lists them.

    A channel is related when its mean coherence lies :data:`RELATED_SIGMAS` standard errors above chance or,
    for hits, its power rises after them (:mod:`.rise`); a channel neither test could be made on is not warned.

    Parameters
    ----------
    tests : list of ChanceTest
        One per output, or none (too few records or driven lines).
    names : sequence of str
        The response channels' names, by output.
    n_inputs : int
        Excitation channels.
    impact : bool
        The records are hits (messages count hits).
    source : str
        Name used in messages (the file).
    rises : sequence of modal.estimate.rise.RiseTest
        One per output, or none (not hits, or no room before them).
    """
    found = []
    force = "the force" if n_inputs == 1 else "the forces"
    records = "hits" if impact else "records"
    chance = {t.output: t for t in tests}
    rise = {r.output: r for r in rises}
    for output in sorted(set(chance) | set(rise)):
        test, up = chance.get(output), rise.get(output)
        if (test is not None and not test.unrelated) or (up is not None and up.rises):
            continue
        name = names[output]
        figures = []
        if test is not None:
            figures.append(f"mean coherence {test.mean_coherence:.3g} over its {test.lines} driven lines, chance "
                           f"{test.chance:.3g} ± {test.chance_se:.2g} with {test.records} {records} "
                           f"({test.sigmas:+.1f} standard errors; a response would show with about "
                           f"{100 * test.detectable_share:.2g} % of these lines coherent)")
        if up is not None:
            figures.append(f"its power in {1e3 * up.window_s:.0f} ms about the {up.hits} trigger(s) "
                           f"{up.ratio:.3g} times that before them ({up.sigmas:+.1f} standard errors of chance)")
        warn(f"{source}: {name} shows no relation to {force}: {'; '.join(figures)}: an unplugged or dead sensor, "
             "a cable at another input, a channel listed that was not measured, or a response buried in its noise; "
             "its FRF is noise (fits weigh it by that noise): check the sensor and its cable", QualityWarning)
        item = {"channel": name, "mean_coherence": None, "chance": None, "chance_se": None, "records": None,
                "lines": None} if test is None else test.as_dict(name)
        item.update(rise=None if up is None else up.ratio, rise_log_se=None if up is None else up.log_se)
        found.append(item)
    return found
