"""Whether an impact estimate's hits see one linear structure: its FRF tested against the hits' force levels.

A linear structure answers every hit with the same FRF, however hard the hit; a joint that slips,
a rattling part or a hardening spring changes its frequencies and damping with the force, and the
average of hits at several levels then mixes its states (a smeared peak: damping too high, a
frequency between them, errors that only say the hits scatter). Each line is tested on its own:
the responses of the n hits, Y_k = (a + b u_k) X_k + e_k, with u_k the centred logarithm of hit k's
peak force, against the linear Y_k = a X_k + e_k (H1's model). With errors independent between
hits and alike in each (response noise, and force noise through H, both the same for every hit),

    F = (RSS₀ − RSS₁)(n − 2) / RSS₁  ~  F(2, 2(n − 2))

when the structure is linear (complex least squares: one complex parameter more, 2(n − 2) real
degrees of freedom left). The record's smallest p over its lines and responses is compared with a
family-wise level spread over them (Bonferroni, which holds however the lines correlate), on the lines
where the FRF changes by at least :data:`MATERIAL_CHANGE` of itself.

Takes saved in several files are tested the same way against one FRF per take
(:func:`take_dependence`): F = ((RSS₀ − RSS_T)/(T − 1)) / (RSS_T/(n − T)) ~ F(2(T − 1), 2(n − T)),
which files of one point that do not measure one FRF fail (a roving point labelled twice, a sensor
moved or the structure changed between takes).

One record's hits are tested the same way for a change part way through (:func:`change_dependence`): the
hits before hit j and from it on as two takes, for every j, the family-wise level spread over the n − 1
places too. A hammer moved to the next point, or a sensor knocked loose, part way through a record gives an
average of two FRFs as smooth as either, whose fit's residual (and so its error bars) says nothing of it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..quantiles import f_survival

__all__ = ["HitSpectra", "hit_spectra", "LevelTest", "TakeTest", "ChangeTest", "level_dependence", "take_dependence",
           "change_dependence",
           "FAMILY_LEVEL", "MIN_LEVEL_RATIO", "MIN_HITS", "MATERIAL_CHANGE", "MAX_SPECTRUM_VALUES",
           "RESONANT_POWER_RATIO"]

#: chance that a linear structure's record is reported level-dependent (over all its lines and responses), as the
#: F distribution of Gaussian errors gives it; its far tail, with the few degrees of freedom of a handful of hits,
#: rests on the errors being Gaussian to 1e-7 of their distribution, which real ones need not be (1e-3 warned 1 of
#: 120 linear records of 5-9 hits): set low, a 0.3 % frequency shift over a factor 8 in force is still found
FAMILY_LEVEL = 1e-4
#: the hits' peak forces must span at least this ratio for the test to say anything
MIN_LEVEL_RATIO = 1.5
#: a change of the FRF smaller than this fraction of it (over the hits' levels, or between a take and the
#: others) is not reported, however significant: a hit's record that holds the previous hit's ringing at 1 %
#: (a lightly damped mode, hits a few seconds apart, little noise) is no nonlinearity worth a warning
MATERIAL_CHANGE = 0.02
#: a response's line whose power summed over the hits is at least this many times its median over the force's band
#: is resonant (:func:`change_dependence` also tests those lines alone: a resonance stands 20-60 dB out of its
#: neighbours, the median line is off resonance)
RESONANT_POWER_RATIO = 10.0
#: hits needed: two parameters per line and degrees of freedom left for the noise
MIN_HITS = 4
#: hits × lines × channels of spectra the test holds at most (64 MiB of complex values); above, it is not run
MAX_SPECTRUM_VALUES = 1 << 22
#: lines tested: those where every hit's force spectrum is at least this fraction of its largest (the hammer's
#: band; above it the force is noise and the FRF undefined)
FORCE_BAND_FRACTION = 0.1


@dataclass(frozen=True)
class HitSpectra:
    """The hits' transforms over the force's band, computed once for the level, take and change tests.

    Attributes
    ----------
    force : ndarray, shape (hits, band lines)
        The windowed force records' transforms on the band's lines.
    responses : ndarray, shape (outputs, hits, band lines)
        The windowed response records' transforms on the same lines.
    lines : ndarray of int
        The band's lines (:func:`_force_band`).
    peaks : ndarray, shape (hits,)
        Each hit record's largest |force|, the force's unit (before windowing).
    """

    force: np.ndarray
    responses: np.ndarray
    lines: np.ndarray
    peaks: np.ndarray

    @property
    def force_power(self) -> np.ndarray:
        """|force|² of each hit's line, (hits, band lines)."""
        return np.abs(self.force) ** 2

    def of_hits(self, index) -> "HitSpectra":
        """The spectra of the hits ``index`` (a take's) alone, on the same lines."""
        return HitSpectra(self.force[index], self.responses[:, index], self.lines, self.peaks[index])


def hit_spectra(force, response, starts, length: int, input_window, output_window) -> HitSpectra | None:
    """The hits' spectra over the force's band (:class:`HitSpectra`), or None where the band is empty or the
    spectra would exceed :data:`MAX_SPECTRUM_VALUES` (hits × lines × channels). Parameters as
    :func:`level_dependence`'s."""
    starts = np.asarray(starts, int)
    n_out = np.shape(response)[0]
    if starts.size * (length // 2 + 1) * (n_out + 1) > MAX_SPECTRUM_VALUES:
        return None
    segments = _records(force, starts, length)
    X, lines = _force_band(segments, input_window)
    if lines.size == 0:
        return None
    Y = np.stack([np.fft.rfft(_records(response[o], starts, length) * output_window, axis=1)[:, lines]
                  for o in range(n_out)]) if n_out else np.zeros((0, starts.size, lines.size), complex)
    return HitSpectra(X[:, lines], Y, lines, np.max(np.abs(segments), axis=1))


def _records(channel, starts: np.ndarray, length: int) -> np.ndarray:
    """The hits' records of one channel, (hits, length)."""
    return np.stack([np.asarray(channel[s:s + length], float) for s in starts])


def _force_band(segments: np.ndarray, input_window: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The force records' transforms (hits, lines) and the lines tested: those where every hit's force
    spectrum is at least :data:`FORCE_BAND_FRACTION` of its largest, without 0 Hz (the mean, not a vibration)
    and the Nyquist line of an even length (real: one degree of freedom per hit, not two)."""
    X = np.fft.rfft(segments * input_window, axis=1)
    power = np.abs(X) ** 2
    band = np.all(power >= FORCE_BAND_FRACTION**2 * power.max(axis=1, keepdims=True), axis=0)
    band[0] = False
    if segments.shape[1] % 2 == 0:
        band[-1] = False
    return X, np.flatnonzero(band)


@dataclass(frozen=True)
class LevelTest:
    """The smallest p of the line-by-line test and where it was found.

    Attributes
    ----------
    p_value : float
        Smallest p over the lines and responses tested.
    limit : float
        :data:`FAMILY_LEVEL` over the number of tests: below it, the FRF changes with the force level.
    frequency_hz : float
        The line of the smallest p, Hz.
    output : int
        The response (0-based, in the order given) of the smallest p.
    force_range : tuple of float
        The smallest and largest peak force of the hits, in the force's unit.
    n_hits, n_lines : int
    """

    p_value: float
    limit: float
    frequency_hz: float
    output: int
    force_range: tuple[float, float]
    n_hits: int
    n_lines: int

    @property
    def level_dependent(self) -> bool:
        return self.p_value < self.limit


def level_dependence(force, response, starts, length: int, input_window, output_window,
                     sample_rate_hz: float, spectra: HitSpectra | None = None) -> LevelTest | None:
    """Test the hits' FRFs against their force levels (see the module), or None where the test cannot say.

    Parameters
    ----------
    force : ndarray, shape (n_samples,)
    response : array_like, shape (n_outputs, n_samples)
    starts : ndarray of int
        First sample of each accepted hit's record.
    length : int
        Samples per record.
    input_window, output_window : ndarray, shape (length,)
        The windows the estimate applied.
    sample_rate_hz : float
    spectra : HitSpectra, optional
        These hits' spectra (:func:`hit_spectra`) where already computed.

    Returns
    -------
    LevelTest or None
        None with fewer than :data:`MIN_HITS` hits, peak forces within :data:`MIN_LEVEL_RATIO` of each other,
        no line in the force's band, or spectra above :data:`MAX_SPECTRUM_VALUES`.
    """
    n = np.size(starts)
    if n < MIN_HITS:
        return None
    spectra = spectra or hit_spectra(force, response, starts, length, input_window, output_window)
    if spectra is None:
        return None
    peaks, lines, Xb, n_out = spectra.peaks, spectra.lines, spectra.force, spectra.responses.shape[0]
    if not (np.all(peaks > 0) and peaks.max() >= MIN_LEVEL_RATIO * peaks.min()):
        return None
    u = np.log(peaks) - np.mean(np.log(peaks))
    Pb = np.abs(Xb) ** 2
    s_xx, s_ux, s_uu = Pb.sum(axis=0), (u[:, None] * Pb).sum(axis=0), (u[:, None] ** 2 * Pb).sum(axis=0)
    det = s_xx * s_uu - s_ux**2
    best = (np.inf, 0.0, 0)
    for o, Y in enumerate(spectra.responses):
        cross = np.conj(Xb) * Y
        r0, r1 = cross.sum(axis=0), (u[:, None] * cross).sum(axis=0)
        s_yy = (np.abs(Y) ** 2).sum(axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            rss0 = s_yy - np.abs(r0) ** 2 / s_xx
            # the 2 × 2 solve of [X, uX] per line: r^H G⁻¹ r with G = [[s_xx, s_ux], [s_ux, s_uu]]
            explained = (s_uu * np.abs(r0) ** 2 - 2 * s_ux * np.real(np.conj(r0) * r1) + s_xx * np.abs(r1) ** 2) / det
            rss1 = s_yy - explained
            F = (rss0 - rss1) * (n - 2) / rss1
            # the FRF's change over the hits' range of levels, relative to it: b (u_max − u_min) / |a|
            a = (s_uu * r0 - s_ux * r1) / det
            b = (s_xx * r1 - s_ux * r0) / det
            change = np.abs(b) * (u.max() - u.min()) / np.abs(a)
        ok = np.isfinite(F) & (rss1 > 0) & (change >= MATERIAL_CHANGE)
        if not ok.any():
            continue
        p = f_survival(2.0, 2.0 * (n - 2), np.maximum(F[ok], 0.0))
        k = int(np.argmin(p))
        if p[k] < best[0]:
            best = (float(p[k]), float(lines[np.flatnonzero(ok)[k]] * sample_rate_hz / length), o)
    if not np.isfinite(best[0]):
        return None
    return LevelTest(p_value=best[0], limit=FAMILY_LEVEL / (lines.size * n_out), frequency_hz=best[1],
                     output=best[2], force_range=(float(peaks.min()), float(peaks.max())), n_hits=n,
                     n_lines=int(lines.size))


@dataclass(frozen=True)
class TakeTest:
    """The smallest p of the line-by-line test of one FRF for every take, and where it was found.

    Attributes
    ----------
    p_value, limit, frequency_hz, output
        As :class:`LevelTest`'s.
    n_takes, n_hits, n_lines : int
    """

    p_value: float
    limit: float
    frequency_hz: float
    output: int
    n_takes: int
    n_hits: int
    n_lines: int

    @property
    def takes_differ(self) -> bool:
        return self.p_value < self.limit


def take_dependence(force, response, starts, take_of_hit, length: int, input_window, output_window,
                    sample_rate_hz: float, spectra: HitSpectra | None = None) -> TakeTest | None:
    """Test whether the takes' hits share one FRF (see the module), or None where the test cannot say.

    Parameters
    ----------
    take_of_hit : ndarray of int
        The take (0-based) of each accepted hit.

    Other parameters as :func:`level_dependence`. None with fewer than two takes, no take of two hits or more
    (no noise left once each take has its FRF), no line in the force's band, or spectra too large.
    """
    n = np.size(starts)
    labels, takes = np.unique(np.asarray(take_of_hit, int), return_inverse=True)
    n_takes = labels.size
    if n_takes < 2 or n - n_takes < 2:
        return None
    spectra = spectra or hit_spectra(force, response, starts, length, input_window, output_window)
    if spectra is None:
        return None
    lines, Xb, Pb, n_out = spectra.lines, spectra.force, spectra.force_power, spectra.responses.shape[0]
    member = np.eye(n_takes)[takes]  # (hits, takes)
    s_xx_t = member.T @ Pb  # (takes, lines)
    best = (np.inf, 0.0, 0)
    for o, Y in enumerate(spectra.responses):
        cross = np.conj(Xb) * Y
        s_yy = (np.abs(Y) ** 2).sum(axis=0)
        cross_t = member.T @ cross
        with np.errstate(divide="ignore", invalid="ignore"):
            rss0 = s_yy - np.abs(cross.sum(axis=0)) ** 2 / Pb.sum(axis=0)
            rss_t = s_yy - np.sum(np.abs(cross_t) ** 2 / s_xx_t, axis=0)
            F = ((rss0 - rss_t) / (n_takes - 1)) / (rss_t / (n - n_takes))
            common = cross.sum(axis=0) / Pb.sum(axis=0)
            change = np.max(np.abs(cross_t / s_xx_t - common), axis=0) / np.abs(common)
        ok = np.isfinite(F) & (rss_t > 0) & (change >= MATERIAL_CHANGE)
        if not ok.any():
            continue
        p = f_survival(2.0 * (n_takes - 1), 2.0 * (n - n_takes), np.maximum(F[ok], 0.0))
        k = int(np.argmin(p))
        if p[k] < best[0]:
            best = (float(p[k]), float(lines[np.flatnonzero(ok)[k]] * sample_rate_hz / length), o)
    if not np.isfinite(best[0]):
        return None
    return TakeTest(p_value=best[0], limit=FAMILY_LEVEL / (lines.size * n_out), frequency_hz=best[1], output=best[2],
                    n_takes=int(n_takes), n_hits=int(n), n_lines=int(lines.size))


@dataclass(frozen=True)
class ChangeTest:
    """The smallest p of the test for a change part way through one record's hits, and where it was found.

    Attributes
    ----------
    p_value, limit, frequency_hz, output
        As :class:`LevelTest`'s; ``limit`` that of the family the smallest p (against its limit) was found in,
        spread over the places too.
    first_after : int
        The first hit (0-based, of those tested) after the change.
    change : float
        At that line, the larger of the two groups' FRFs' distance from the average, relative to the average.
    n_hits : int
    n_lines : int
        Lines of that family, summed over the responses.
    resonant : bool
        Found among the resonant lines (the second family of :func:`change_dependence`).
    """

    p_value: float
    limit: float
    frequency_hz: float
    output: int
    first_after: int
    change: float
    n_hits: int
    n_lines: int
    resonant: bool = False

    @property
    def changed(self) -> bool:
        return self.p_value < self.limit


def change_dependence(force, response, starts, length: int, input_window, output_window,
                      sample_rate_hz: float, spectra: HitSpectra | None = None,
                      family_level: float = FAMILY_LEVEL) -> ChangeTest | None:
    """Test one record's hits for a change of FRF part way through (see the module), or None where the test
    cannot say.

    For each place j the hits before it and from it on are two takes, tested as :func:`take_dependence`
    tests them, F ~ F(2, 2(n − 2)). The smallest p is sought in two families, each at half of
    :data:`FAMILY_LEVEL` over its number of tests (lines × places, summed over the responses): every line of
    the force's band, and the resonant lines alone (a response's power summed over the hits at least
    :data:`RESONANT_POWER_RATIO` times its median over the band), where a moved hammer or sensor changes most
    and a family of a few dozen lines asks for a change a few times smaller. Choosing lines by their summed
    power leaves the test's null distribution as it is: with Gaussian errors F is independent of
    Σ|Y_k|² = |Σ X̄_k Y_k|²/S_xx + RSS₀ (the fitted part and the residual's two parts are independent, and a
    ratio of independent χ² is independent of their sum).

    Parameters as :func:`level_dependence`'s, ``starts`` in time order, and ``family_level`` the chance of a
    warning for an unchanged record (:data:`FAMILY_LEVEL`; a record of several takes tested take by take spreads it
    over them). None with fewer than :data:`MIN_HITS` hits, no line in the force's band, or spectra above
    :data:`MAX_SPECTRUM_VALUES`.
    """
    n = np.size(starts)
    if n < MIN_HITS:
        return None
    spectra = spectra or hit_spectra(force, response, starts, length, input_window, output_window)
    if spectra is None:
        return None
    lines, Xb, Pb, n_out = spectra.lines, spectra.force, spectra.force_power, spectra.responses.shape[0]
    # the hits before each place j = 1 … n − 1 (rows), summed over the hits by running sums
    p_before = np.cumsum(Pb, axis=0)[:-1]
    p_total = p_before[-1] + Pb[-1]
    p_after = p_total - p_before
    # every test has the same degrees of freedom, so the smallest p of a family is that of its largest F: each
    # family's largest F (and where) is kept per response, and p computed for it alone
    largest = [None, None]  # per family: (F, output, place, line index, change)
    resonant_lines = 0
    for o, Y in enumerate(spectra.responses):
        cross = np.conj(Xb) * Y
        s_yy = (np.abs(Y) ** 2).sum(axis=0)
        c_before = np.cumsum(cross, axis=0)[:-1]
        c_total = c_before[-1] + cross[-1]
        c_after = c_total - c_before
        with np.errstate(divide="ignore", invalid="ignore"):
            rss0 = s_yy - np.abs(c_total) ** 2 / p_total
            rss2 = s_yy - np.abs(c_before) ** 2 / p_before - np.abs(c_after) ** 2 / p_after
            F = (rss0 - rss2) / (rss2 / (n - 2))
            common = c_total / p_total
            change = (np.maximum(np.abs(c_before / p_before - common), np.abs(c_after / p_after - common))
                      / np.abs(common))
        resonant = s_yy >= RESONANT_POWER_RATIO * np.median(s_yy)
        resonant_lines += int(resonant.sum())
        F = np.where(np.isfinite(F) & (rss2 > 0) & (change >= MATERIAL_CHANGE), np.maximum(F, 0.0), -np.inf)
        for family, tested in enumerate((F, np.where(resonant[None, :], F, -np.inf))):
            place, k = np.unravel_index(int(np.argmax(tested)), tested.shape)
            if np.isfinite(tested[place, k]) and (largest[family] is None or tested[place, k] > largest[family][0]):
                largest[family] = (float(tested[place, k]), o, int(place), int(k), float(change[place, k]))
    best = None
    for family, n_tests in ((0, lines.size * n_out), (1, resonant_lines)):
        if largest[family] is None:
            continue
        F_max, o, place, k, size = largest[family]
        p = float(f_survival(2.0, 2.0 * (n - 2), np.array([F_max]))[0])
        limit = family_level / 2 / (max(n_tests, 1) * (n - 1))
        if best is None or p / limit < best[0] / best[1]:
            best = (p, limit, float(lines[k] * sample_rate_hz / length), o, place + 1, size, n_tests, bool(family))
    if best is None:
        return None
    return ChangeTest(p_value=best[0], limit=best[1], frequency_hz=best[2], output=best[3], first_after=best[4],
                      change=best[5], n_hits=int(n), n_lines=int(best[6]), resonant=best[7])
