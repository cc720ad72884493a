"""Frequency-domain decomposition (FDD) and its enhanced form (EFDD): the quick looks.

The output half-spectra (outputs × references) near a lightly damped mode are nearly of rank one,
their first left singular vector the mode's shape (Brincker, Zhang & Andersen 2001). FDD: the peaks
of the first singular value in the band, each with the singular vector at the peak. EFDD: around each
peak the lines whose first singular vector has a MAC of at least :data:`BELL_MAC` with the peak's
form the mode's "bell"; the bell projected onto the peak's vectors and transformed back to the lag
domain is the mode's correlation function ``A e^{λτ}``, whose log-magnitude slope gives the decay
rate and whose phase slope the damped frequency. The half-spectra come from the correlations with a
known exponential lag window, whose decay is taken off exactly (a Hann-windowed Welch spectrum would
add damping that no fit removes). No error bars (NaN, flagged ``high_uncertainty``). Machine tones are told
apart as for the other methods (:mod:`modal.operational.tones`), FDD's peaks too with the damping their bell's
decay gives, which FDD does not report.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import IdentificationError, ParameterError
from .correlations import correlations
from .inputs import MIN_LAGS_IN_RECORD, Prepared
from .plscf import half_spectra
from .pole import PoleEstimate
from .result import oma_result
from .selection import shape_mac

__all__ = ["fdd", "singular_values"]

#: the peaks of the first singular value stand out of it by this much (dB)
MIN_PROMINENCE_DB = 6.0
#: the bell of a mode: lines whose first singular vector has at least this MAC with the peak's
BELL_MAC = 0.8
#: the lag window adds at most this damping ratio at the lowest frequency of interest
WINDOW_DAMPING = 0.005
#: the decay is fitted where the correlation's envelope lies between these fractions of its start
ENVELOPE = (0.9, 0.1)


def singular_values(prepared: Prepared, refs):
    """(lines Hz, first singular values, first left singular vectors (lines, outputs), half-spectra, decay β)."""
    fs = prepared.sample_rate_hz
    low, high = prepared.band_hz
    f_low = max(low, high / 10)
    n_lags = int(np.ceil(-np.log(0.01) / (WINDOW_DAMPING * 2 * np.pi * f_low) * fs))
    n_lags = min(n_lags, prepared.n_samples // MIN_LAGS_IN_RECORD)
    if n_lags < 16:
        raise ParameterError(f"{prepared.source}: the record lasts {prepared.duration_s:.4g} s; too short for a "
                             f"spectral decomposition down to {f_low:.4g} Hz")
    corr = correlations(prepared.signals, fs, refs, n_lags - 1, max_blocks=1, mean=prepared.mean,
                        scale=prepared.scale)
    spacing = fs / (4 * n_lags)
    lines = spacing * np.arange(max(int(np.ceil(low / spacing)), 1), int(np.floor(high / spacing)) + 1)
    S, beta = half_spectra(corr.mean, fs, lines)
    u, s, _ = np.linalg.svd(np.moveaxis(S, -1, 0), full_matrices=False)
    return lines, s[:, 0], u[:, :, 0], S, beta


def _peaks(values: np.ndarray) -> np.ndarray:
    from scipy.signal import find_peaks

    peaks, _ = find_peaks(10 * np.log10(values), prominence=MIN_PROMINENCE_DB)
    return peaks


def _decay(lines, S, u_peak, v_peak, bell, fs, beta):
    """(pole λ, rad/s) from the bell's correlation function ``A e^{λτ}``, or None."""
    projected = np.einsum("o,orf,r->f", u_peak.conj(), S, v_peak)  # (lines,)
    spacing = lines[1] - lines[0]
    n = int(round(fs / spacing))
    spectrum = np.zeros(n, complex)
    index = np.round(lines[bell] / spacing).astype(int)
    spectrum[index] = projected[bell]
    r = np.fft.ifft(spectrum)  # Σ_f S(f) e^{+iωτ}: the mode's e^{λτ}, sampled at 1/fs
    magnitude = np.abs(r)
    top = magnitude[0]
    below = np.flatnonzero(magnitude < ENVELOPE[1] * top)
    end = int(below[0]) if below.size else n // 2
    start = int(np.flatnonzero(magnitude[:end + 1] <= ENVELOPE[0] * top)[0]) if end > 0 else 0
    if end - start < 4:
        return None
    tau = np.arange(start, end) / fs
    sigma = -np.polyfit(tau, np.log(magnitude[start:end]), 1)[0]
    omega_d = np.polyfit(tau, np.unwrap(np.angle(r[start:end])), 1)[0]
    return complex(-(sigma - beta), abs(omega_d))


def fdd(prepared: Prepared, refs, *, enhanced: bool, rotor_speed_hz=None, record_flags=frozenset()):
    """FDD (``enhanced=False``) or EFDD of a prepared record: an :class:`~modal.results.IdentificationResult`
    (``record_flags`` on every mode, see :func:`modal.operational.result.oma_result`)."""
    from .tones import flag_mains_hum, separate_tones

    lines, s1, u1, S, beta = singular_values(prepared, refs)
    fs = prepared.sample_rate_hz
    peaks = _peaks(s1)
    if not peaks.size:
        raise IdentificationError(f"{prepared.source}: the first singular value has no peak of "
                                  f"{MIN_PROMINENCE_DB:g} dB in the band {prepared.band_hz[0]:g}-"
                                  f"{prepared.band_hz[1]:g} Hz")
    _, _, vh = np.linalg.svd(np.moveaxis(S, -1, 0)[peaks], full_matrices=False)
    estimates, judged = [], []
    nan_shape = np.full(prepared.n_channels, np.nan)
    for j, p in enumerate(peaks):
        u_peak = u1[p]
        raw = u_peak * prepared.scale
        shape = raw / raw[np.argmax(np.abs(raw))]
        line = PoleEstimate(complex(0.0, 2 * np.pi * lines[p]), shape, np.nan, np.nan, nan_shape, 1, 1, 0,
                            damping_known=False)
        mac = shape_mac(u1.T, u_peak[:, None])
        bell = np.zeros(lines.size, bool)
        lo = hi = p
        while lo > 0 and mac[lo - 1] >= BELL_MAC:
            lo -= 1
        while hi < lines.size - 1 and mac[hi + 1] >= BELL_MAC:
            hi += 1
        bell[lo:hi + 1] = True
        found = _decay(lines, S, u_peak, vh[j, 0].conj(), bell, fs, beta)
        decaying = line if found is None else PoleEstimate(found, shape, np.nan, np.nan, nan_shape, 1, 1, 0)
        estimates.append(decaying if enhanced else line)
        judged.append(decaying)  # FDD reports no damping, but its tones are told apart by the bell's decay too
    is_tone, flagged = separate_tones(judged, prepared, rotor_speed_hz, 4 * (lines[1] - lines[0]))
    estimates = [replace(e, flags=g.flags) for e, g in zip(estimates, flagged)]
    modes = flag_mains_hum([e for e, t in zip(estimates, is_tone) if not t], prepared)
    tones = [e.natural_frequency_hz for e, t in zip(estimates, is_tone) if t]
    method = "efdd" if enhanced else "fdd"
    settings = {"band_hz": list(prepared.band_hz), "reference_channels": list(refs),
                "sample_rate_hz": prepared.original_rate_hz, "decimation": prepared.decimation,
                "duration_s": prepared.duration_s, "rotor_speed_hz": rotor_speed_hz,
                "channel_names": list(prepared.names), "n_channels": prepared.n_channels, "source": prepared.source,
                "window_decay_per_s": float(beta), "line_spacing_hz": float(lines[1] - lines[0])}
    return oma_result(modes, method=method, quantity=prepared.quantity, band_hz=prepared.band_hz,
                      stabilisation=None, settings=settings, harmonics_hz=tones, source=prepared.source,
                      record_flags=record_flags)
