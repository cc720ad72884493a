"""Residual check after a least-squares fit: does the band hold a mode the model lacks?

Peak detection misses a weak mode on the shoulder of a strong one (it needs a
peak standing out by a prominence and 10× above the noise). The fit then
bends the strong mode towards the hidden one, its estimates move by many of
their standard errors, and the residual variance grows only a little (χ² ≈ 3
for a mode at 115 Hz hidden beside one at 154 Hz), so ``model_inadequate``
rarely fires.

The check here asks the question directly. Where the residual, smoothed over a
mode's width, is largest, it adds one mode and refits. It then keeps the added
mode only when three things hold:

* both an F-test (self-normalised: it needs no noise estimate) and the
  likelihood ratio against the noise find the reduction in residual
  significant at 1e-6. The noise is the smaller of the estimate from the raw
  data and the same neighbour-misfit estimate on the residual (on a coarse
  axis the raw estimate is the resonances' curvature, which the fitted modes
  remove), and at least sqrt(eps)·max|H| (below that, structure is rounding);
* the new mode's half-power band reaches a fitting band that resolves it (its
  half-power width is at most half that band);
* its modal overlap 2·max(ζωn)/Δωn with every fitted pole is at most 1.5
  (closer, it cannot be told from a split of that mode).

Structure that is not a mode (the slope of a mode outside the bands, rounding
on exact data) fails these conditions. The result is a flag (``missing_mode``)
with the frequency of the hidden mode; the modes reported are not changed,
because a mode found this way has not passed peak detection.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..frf import line_spacing
from ..model import mode_basis, solve_linear
from ..nls import fit_modes
from ..peaks import neighbour_noise_std
from ..quantiles import chi2_upper_quantile, f_upper_quantile, gamma_lower_inverse
from ..units import TWO_PI

__all__ = [
    "MissingMode", "find_missing_mode", "fit_residual", "fit_residual_noise_std", "residual_noise_std",
    "residual_structure", "restart_pole", "SIGNIFICANCE",
]

#: false-alarm probability of each test for one added mode
SIGNIFICANCE = 1e-6
#: an added mode overlapping a fitted one more than this (2·max(ζωn)/Δωn) counts as a
#: split of it, not another mode (the same limit as identify's close_modes)
SPLIT_OVERLAP = 1.5
#: channels (strongest first) the check works on
CHECK_CHANNELS = 8
#: Levenberg–Marquardt iterations of the fit with the added mode: over the test suite a mode
#: the residual holds converged from the residual's peak in 7–37 iterations, while an added
#: mode chasing noise crawls for hundreds (96 on 1000 channels at 1 % noise, 200 and more
#: elsewhere) and is then discarded as unconverged anyway
CHECK_MAX_ITER = 60
#: noise is taken to be at least this fraction of a channel's max|H| (sqrt of the float64
#: epsilon): structure below it is the rounding of the fit, not the data
ARITHMETIC_FLOOR = float(np.sqrt(np.finfo(float).eps))


@dataclass(frozen=True)
class MissingMode:
    """A mode the residual holds but the model lacks.

    Attributes
    ----------
    frequency_hz : float
        Natural frequency of the added mode, Hz.
    damping_ratio : float
        Its damping ratio.
    band : int
        Index of the band it lies in or next to (within its half-power half-width).
    f_statistic, f_threshold : float
        F-test of the residual reduction and its 1e-6 threshold.
    moved_bands : tuple of int
        Bands (in frequency order of the fitted modes) whose pole moved by more than
        3 of its standard errors when the mode was added: they are biased by it too.
    """

    frequency_hz: float
    damping_ratio: float
    band: int
    f_statistic: float
    f_threshold: float
    moved_bands: tuple[int, ...] = ()


def _design(omega, omega_n, zeta, power, region):
    phi = mode_basis(omega, omega_n, zeta, power).T
    offsets = np.zeros((omega.size, int(region.max()) + 1), dtype=complex)
    offsets[np.arange(omega.size), region] = 1.0
    return np.hstack([phi, offsets])


def fit_residual(omega: np.ndarray, response: np.ndarray, power: int, region: np.ndarray,
                 omega_n, damping_ratio) -> np.ndarray:
    """Residual (n_channels, n_freq) of the modes at the given poles, their constants and one
    complex offset per region solved linearly: what every check here measures."""
    omega_n = np.atleast_1d(np.asarray(omega_n, float))
    zeta = np.atleast_1d(np.asarray(damping_ratio, float))
    design = _design(omega, omega_n, zeta, power, region)
    coef = solve_linear(design, response.T)
    return response - (design @ coef).T


def _strongest(score: np.ndarray) -> np.ndarray:
    """Indices of the ``CHECK_CHANNELS`` highest scores, highest first."""
    if score.size == 1:
        return np.zeros(1, dtype=int)
    return np.argsort(score)[::-1][:CHECK_CHANNELS]


#: channels whose signal-to-noise ratio is within this factor of the best one's count as equally good
#: for the missing-mode check (far beyond the sampling error of a noise estimate, a few per cent)
SNR_TIE = 2.0


def _check_channels(peak: np.ndarray, noise_std: np.ndarray) -> np.ndarray:
    """The channels :func:`find_missing_mode` works on: the ``CHECK_CHANNELS`` highest peaks among the
    channels whose peak/σ is within :data:`SNR_TIE` of the best, then the rest by peak/σ.

    Ranked by the estimated peak/σ alone, the chosen channels of many with the same true
    ratio are those whose σ estimate came out low by chance (1000 channels, σ² estimated on
    741 lines: the 8 chosen ones 15–17 % low in σ²), and the residual then looks like more than noise.
    Within a factor :data:`SNR_TIE` the estimates' errors cannot decide membership, and the
    peak does not depend on them.
    """
    snr = peak / noise_std
    if peak.size <= CHECK_CHANNELS:  # all of them
        return _strongest(snr)
    tied = snr >= snr.max() / SNR_TIE
    return np.lexsort((np.where(tied, 0.0, snr), np.where(tied, peak, 0.0), tied))[::-1][:CHECK_CHANNELS]


def _smoothed(values: np.ndarray, region: np.ndarray, width: int) -> np.ndarray:
    """Moving average over ``width`` lines within each region (no mixing across gaps)."""
    kernel = np.ones(width) / width
    if not region.size or region.min() == region.max():  # one region
        w = min(width, values.size)
        return np.convolve(values, kernel[:w] * width / w, mode="same")
    out = np.empty_like(values)
    for r in np.unique(region):
        sel = region == r
        seg = values[sel]
        w = min(width, seg.size)
        out[sel] = np.convolve(seg, kernel[:w] * width / w, mode="same")
    return out


def _level(energy: np.ndarray, n_channels: int) -> float:
    """Noise level of a residual energy (|r|²/σ² averaged over channels) from its median.

    The mean of ``n_channels`` Exp(1) variables is Gamma(n, 1/n), with median
    ``gammaincinv(n, 0.5)/n``: ln 2 for one channel, 0.96 for eight.
    """
    return float(np.median(energy)) / _exp_mean_median(n_channels)


@functools.lru_cache(maxsize=64)
def _exp_mean_median(n_channels: int) -> float:
    """Median of the mean of ``n_channels`` Exp(1) variables: gammaincinv(n, 1/2)/n."""
    return gamma_lower_inverse(n_channels, 0.5) / n_channels


def _seen_through(noise_std, seen, peak):
    """The noise per channel as a residual shows it: the smaller of the raw-data estimate and the
    residual's own neighbour-misfit estimate ``seen``, at least ``ARITHMETIC_FLOOR`` times the
    channel's max |H| (``peak``); see :func:`residual_noise_std`."""
    return np.maximum(np.minimum(np.asarray(noise_std, float), seen), ARITHMETIC_FLOOR * peak)


def residual_noise_std(omega: np.ndarray, response: np.ndarray, power: int, region: np.ndarray,
                       omega_n, damping_ratio, noise_std, residual: np.ndarray | None = None) -> np.ndarray:
    """Noise σ per channel as the fit's residual shows it.

    The raw-data estimate (:func:`modal.peaks.estimate_noise_std`) takes in the
    resonances' curvature where the lines are coarse: 3.7σ at 16 lines across
    a band of ±5 half-power widths. The same
    neighbour-misfit estimate on the residual of the fitted modes has that
    curvature removed, and a misfit that is smooth on the lines does not enter
    it either (1.02σ there). The result is the smaller of the two, and at least
    ``ARITHMETIC_FLOOR``·max|H|: exact data fit to rounding leave a structured
    residual at 1e-16·|H| which is the arithmetic of the fit, not data.

    Parameters
    ----------
    omega, response, power, region, omega_n, damping_ratio
        As for :func:`find_missing_mode`.
    noise_std : ndarray, shape (n_channels,)
        Raw-data estimate per channel.
    residual : ndarray, shape (n_channels, n_freq), optional
        The fit's residual if the caller has it (:func:`fit_residual`); computed otherwise.

    Returns
    -------
    ndarray, shape (n_channels,)
    """
    res = residual if residual is not None else fit_residual(omega, response, power, region, omega_n, damping_ratio)
    return _seen_through(noise_std, neighbour_noise_std(omega, res), np.max(np.abs(response), axis=1))


def fit_residual_noise_std(omega: np.ndarray, fit, noise_std, channels=slice(None)) -> np.ndarray:
    """:func:`residual_noise_std` from the residual a fit already holds (no second solve).

    Parameters
    ----------
    omega : ndarray, shape (n_freq,)
        The lines of the fit, rad/s.
    fit : modal.nls.NLSFit
        An unweighted fit with the offset per region (``background_powers=(0,)``, the model
        of :func:`residual_noise_std`), holding ``residual`` and ``channel_scale``.
    noise_std : ndarray, shape (n_channels,)
        Raw-data estimate per channel (of the ``channels`` only, when given).
    channels : slice or ndarray of int, optional
        The fit's channels to measure (default all).

    Returns
    -------
    ndarray, shape (n_channels,)
    """
    return _seen_through(noise_std, neighbour_noise_std(omega, fit.residual[channels]),
                         np.asarray(fit.channel_scale, float)[channels])


def residual_structure(omega: np.ndarray, response: np.ndarray, power: int, region: np.ndarray,
                       omega_n, damping_ratio, residual: np.ndarray | None = None,
                       peak: np.ndarray | None = None) -> float:
    """How far the fit's residual is from white: its variance over its line-to-line noise.

    The residual variance (sum of squares over the degrees of freedom) is
    divided by the square of :func:`modal.peaks.neighbour_noise_std` of the
    same residual, which sees only what changes from line to line. For white
    noise the ratio is 1 (within a few 1/sqrt(lines)); a misfit that is smooth
    across the lines (the model's truncation on near-exact data, a lost mode)
    raises it. The median over the ``CHECK_CHANNELS`` strongest channels.

    Parameters
    ----------
    omega, response, power, region, omega_n, damping_ratio, residual, peak
        As for :func:`find_missing_mode`.

    Returns
    -------
    float
        The ratio; NaN when the residual leaves no degree of freedom or is zero.
    """
    omega_n = np.atleast_1d(np.asarray(omega_n, float))
    zeta = np.atleast_1d(np.asarray(damping_ratio, float))
    peak = np.max(np.abs(response), axis=1) if peak is None else peak
    strongest = _strongest(peak)
    if residual is not None:
        res = residual[strongest]
    else:
        res = fit_residual(omega, response[strongest], power, region, omega_n, zeta)
    dof = omega.size - omega_n.size - (int(region.max()) + 1) - omega_n.size / res.shape[0]
    if dof <= 0:
        return np.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.sum(np.abs(res) ** 2, axis=1) / dof / neighbour_noise_std(omega, res) ** 2
    ratio = ratio[np.isfinite(ratio)]
    if ratio.size == 1:
        return float(ratio[0])
    return float(np.median(ratio)) if ratio.size else np.nan


def restart_pole(omega: np.ndarray, response: np.ndarray, power: int, region: np.ndarray,
                 omega_n, damping_ratio, in_band: np.ndarray) -> tuple[float, float] | None:
    """Where a mode that the joint fit lost should start again.

    The residual of the other modes, as energy relative to each channel's
    max|H|² averaged over the ``CHECK_CHANNELS`` strongest channels and
    smoothed over their median half-power width, is largest where the lost
    mode's energy is. The start ζ is the other modes' median.

    Parameters
    ----------
    omega, response, power, region
        As for :func:`find_missing_mode`.
    omega_n, damping_ratio : array_like
        The other modes' poles (rad/s, dimensionless), at least one.
    in_band : ndarray of bool, shape (n_freq,)
        The lost mode's band.

    Returns
    -------
    (ωn [rad/s], ζ) or None
        None when the band holds fewer than 3 lines.
    """
    omega_n = np.atleast_1d(np.asarray(omega_n, float))
    zeta = np.atleast_1d(np.asarray(damping_ratio, float))
    if np.count_nonzero(in_band) < 3 or omega_n.size == 0:
        return None
    scale = np.max(np.abs(response), axis=1)
    strongest = _strongest(scale)
    scale = np.where(scale[strongest] > 0, scale[strongest], 1.0)
    res = fit_residual(omega, response[strongest], power, region, omega_n, zeta)
    energy = np.mean(np.abs(res) ** 2 / scale[:, None] ** 2, axis=0)
    spacing = float(np.median(np.diff(omega)))
    width = int(np.clip(np.round(np.median(2 * zeta * omega_n) / spacing), 1, max(1, omega.size // 4)))
    smooth = np.where(in_band, _smoothed(energy, region, width), -np.inf)
    return float(omega[int(np.argmax(smooth))]), float(np.median(zeta))


def find_missing_mode(omega: np.ndarray, response: np.ndarray, power: int, region: np.ndarray,
                      omega_n, damping_ratio, noise_std, bands_rad,
                      residual: np.ndarray | None = None,
                      residual_noise: np.ndarray | None = None,
                      peak: np.ndarray | None = None, budget=None) -> MissingMode | None:
    """Test the residual of fitted modes for one more mode.

    Parameters
    ----------
    omega : ndarray, shape (n_freq,)
        Lines of the bands, rad/s.
    response : ndarray, shape (n_channels, n_freq)
        FRF on those lines.
    power : int
        Kind power (0 receptance, 1 mobility, 2 accelerance).
    region : ndarray of int, shape (n_freq,)
        Band region of each line (one complex offset each).
    omega_n, damping_ratio : array_like, shape (n_modes,)
        Fitted poles (rad/s, dimensionless).
    noise_std : ndarray, shape (n_channels,)
        Raw-data noise estimate σ per channel (E|n|² = σ²); the check uses the
        noise as the residual shows it (:func:`residual_noise_std`).
    bands_rad : list of (low, high)
        The fitting bands, rad/s.
    residual : ndarray, shape (n_channels, n_freq), optional
        The residual of the fitted modes if the caller has it (:func:`fit_residual`);
        computed otherwise.
    residual_noise : ndarray, shape (n_channels,), optional
        :func:`residual_noise_std` of that residual if the caller has it (it is per
        channel, so the strongest channels' values are the same); computed otherwise.
    peak : ndarray, shape (n_channels,), optional
        max |H| of each channel on these lines, when the caller has it (a fit's
        ``channel_scale``): the strongest channels are chosen by it.
    budget : EvaluationBudget, optional
        The identification's :class:`~modal.work_budget.EvaluationBudget`: the trial fit with one more mode
        takes what is left of it (and gives no verdict where it runs out).

    Returns
    -------
    MissingMode or None
    """
    omega_n = np.atleast_1d(np.asarray(omega_n, float))
    zeta = np.atleast_1d(np.asarray(damping_ratio, float))
    noise_std = np.asarray(noise_std, float)
    if not (np.all(np.isfinite(noise_std)) and np.all(noise_std > 0) and omega.size > 8):
        return None
    peak = np.max(np.abs(response), axis=1) if peak is None else peak
    strongest = _check_channels(peak, noise_std)
    Y = response[strongest]
    n_ch = Y.shape[0]
    res = residual[strongest] if residual is not None else fit_residual(omega, Y, power, region, omega_n, zeta)
    if residual_noise is not None:
        sigma2 = np.asarray(residual_noise, float)[strongest] ** 2
    else:
        sigma2 = _seen_through(noise_std[strongest], neighbour_noise_std(omega, res), peak[strongest]) ** 2
    if not np.all(sigma2 > 0):
        return None
    energy = np.mean(np.abs(res) ** 2 / sigma2[:, None], axis=0)
    spacing = line_spacing(omega)
    half_power = float(np.median(2 * zeta * omega_n)) if zeta.size > 1 else float(2 * zeta[0] * omega_n[0])
    width = int(min(max(round(half_power / spacing), 3), max(3, omega.size // 4)))
    smooth = _smoothed(energy, region, width)
    # screen (cheap): the smoothed residual must rise above its noise level by 4 of its
    # standard deviations (1/sqrt(lines × channels) of an Exp(1) mean); the level is the
    # noise above or, when the residual's own median says more (noise the estimate misses),
    # that median: the mean of |r|²/σ² ~ Exp(1) over n channels is Gamma(n, 1/n), whose median
    # is ln 2 for one channel and 0.96 for eight. A misfit spread over the whole band (few
    # lines) passes when the mean residual is above the noise by 4 of its standard deviations
    level = max(1.0, _level(energy, n_ch))
    peaked = smooth.max() > level * (1 + 4 / np.sqrt(width * n_ch))
    if not (peaked or np.mean(energy) > 1 + 4 / np.sqrt(energy.size * n_ch)):
        return None
    i = int(np.argmax(smooth))
    start_wn = np.append(omega_n, omega[i])
    start_zeta = np.append(zeta, max(np.median(zeta), width * spacing / (2 * omega[i])))
    with np.errstate(all="ignore"):
        fit = fit_modes(omega, Y, power, start_wn, start_zeta, region=region, max_iter=CHECK_MAX_ITER,
                        max_evaluations=None if budget is None else budget.for_fit())
    if budget is not None:
        budget.spend(fit)  # a trial the budget stopped gives no verdict (and its modes are flagged work_capped)
    if not fit.converged or fit.capped:
        return None
    new_wn, new_zeta = float(fit.omega_n[-1]), float(fit.damping_ratio[-1])
    if not (np.isfinite(new_wn) and 0 < new_zeta < 1):
        return None
    # the nearest band must reach the new mode's half-power band and resolve it
    gaps = [max(lo - new_wn, new_wn - hi, 0.0) for lo, hi in bands_rad]
    band = int(np.argmin(gaps))
    lo, hi = bands_rad[band]
    if gaps[band] > new_zeta * new_wn or 2 * new_zeta * new_wn > 0.5 * (hi - lo):
        return None  # away from the bands, or broader than a band can resolve
    others_wn, others_zeta = fit.omega_n[:-1], fit.damping_ratio[:-1]
    overlap = 2 * np.maximum(others_zeta * others_wn, new_zeta * new_wn) / np.abs(others_wn - new_wn)
    if np.any(overlap > SPLIT_OVERLAP):
        return None  # too close to a fitted mode to tell from a split of it
    res1 = fit_residual(omega, Y, power, region, fit.omega_n, fit.damping_ratio)
    rss0 = np.sum(np.abs(res) ** 2, axis=1)
    rss1 = np.sum(np.abs(res1) ** 2, axis=1)
    n_b = omega_n.size + int(region.max()) + 1
    q = 2 + 2 * n_ch  # the pole, and a complex constant per channel
    dof = 2 * n_ch * (omega.size - n_b - 1) - 2 * (omega_n.size + 1)
    if dof <= 0 or np.sum(rss1) <= 0:
        return None
    f_stat = float((np.sum(rss0 - rss1) / q) / (np.sum(rss1) / dof))
    f_limit = f_upper_quantile(q, dof, SIGNIFICANCE)
    # against the noise above: each real part of the noise has variance σ²/2
    ratio = float(np.sum(2 * (rss0 - rss1) / sigma2))
    ratio_limit = chi2_upper_quantile(q, SIGNIFICANCE)
    if f_stat > f_limit and ratio > ratio_limit:
        # a fitted mode that moves by more than 3 of its errors once the hidden one is in the
        # model was biased by it as well, wherever its band (a neighbour that absorbed a
        # mode lost below the noise had its ζ 17 errors off, unflagged)
        with np.errstate(all="ignore"):
            std = np.sqrt(np.abs(fit.mode_cov[:-1, 0][:, [0, 1], [0, 1]]))  # (n_modes, 2)
            shift = np.abs(np.column_stack([fit.omega_n[:-1] - omega_n, fit.damping_ratio[:-1] - zeta]))
        moved = np.any(shift > 3 * std, axis=1)
        rank = np.argsort(np.argsort(omega_n))  # band index of each fitted mode
        return MissingMode(new_wn / TWO_PI, new_zeta, band, f_stat, f_limit,
                           tuple(sorted(int(b) for b in rank[moved])))
    return None
