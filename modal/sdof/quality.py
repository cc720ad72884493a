"""The checks of a band-wise fit on its bands: chi-square, misfit near each mode, missing modes, and the
comparison of a half-power or circle estimate with the least-squares refinement of the same modes.
"""
from __future__ import annotations

import numpy as np

from ..flags import lines_near_mode
from ..model import mode_basis, solve_linear
from ..units import TWO_PI
from .bands import POLE_CHANNELS, band_data, band_run, constants_at_poles, regions
from .checks import find_missing_mode, fit_residual_noise_std, residual_noise_std
from .refine import fit_bands, truncation

__all__ = ["refinement_check", "chi2_of", "constant_distance", "local_misfit", "fit_noise", "missing_mode_in_bands"]

def refinement_check(frf, bands, power, poles, consts, noise, estimated_noise, known_noise=False, residual=None,
                     budget=None):
    """Compare single-mode estimates with the least-squares refinement of the same modes.

    All modes are refined together by :func:`fit_modes`, started from the
    single-mode poles, on the strongest channels (at most ``POLE_CHANNELS``).
    Returns per mode (ωn − ωn_ref, ζ − ζ_ref, A − A_ref per channel, χ²,
    std ωn_ref, std ζ_ref), where χ² is the refined model's residual variance
    over the noise variance (the same test as for ``"nls"``: whether viscous
    modes explain the band at all) and the standard errors are the refinement's
    (Cramér–Rao) ones. Differences and errors are 0 where the refinement does
    not stand (for one mode: its refined pole left its band or has no finite error).
    ``residual``, a dict, receives the refinement's residual variance per channel
    (``"noise_var"``, NaN on the channels it did not use).
    ``budget``: the :class:`~modal.work_budget.EvaluationBudget` of the refinement and the missing-mode check's
    trial fit; where the refinement spends it (``budget.capped``) it stands nowhere in particular: no mode is
    compared with it and the missing-mode and truncation checks are not run (every mode as without a
    reference, its χ² not measured); where the trial fit spends it, the check gives no verdict.
    """
    n_modes = len(bands)

    def no_reference(chi2):
        return (0.0, 0.0, np.zeros(frf.n_channels, complex), chi2, 0.0, 0.0)

    # the refinement starts from the method's poles; a pole the method could not give (ζ ≤ 0
    # or non-finite: half-power under heavy noise) starts from its band instead, so that it
    # does not take the check away from the other modes
    peak = np.array([TWO_PI * b.peak_hz for b in bands])
    width = np.array([b.half_power_width_hz / (2 * b.peak_hz) if b.peak_hz > 0 else np.nan for b in bands])
    span = np.array([(b.high_hz - b.low_hz) / (12 * b.peak_hz) if b.peak_hz > 0 else np.nan for b in bands])
    wn0 = np.array([p[0] for p in poles], float)
    z0 = np.array([p[1] for p in poles], float)
    wn0 = np.where(np.isfinite(wn0) & (wn0 > 0), wn0, peak)
    fallback = np.where(np.isfinite(width) & (width > 0), width, span)
    z0 = np.where(np.isfinite(z0) & (z0 > 0) & (z0 < 1), z0, np.clip(fallback, 1e-9, 0.99))
    if not (np.all(np.isfinite(wn0)) and np.all(wn0 > 0) and np.all(np.isfinite(z0))):
        return [no_reference(np.nan)] * n_modes, None
    keep, _ = regions(bands, frf.frequency_hz)
    strongest = np.argsort(np.max(np.abs(frf.channels[:, keep]) / np.where(noise > 0, noise, 1.0)[:, None],
                                  axis=1))[::-1][:POLE_CHANNELS]
    fit = fit_bands(frf, bands, power, wn0, z0, strongest, budget=budget, noise=noise)
    if budget is not None and budget.capped:
        return [no_reference(np.nan)] * n_modes, None
    if residual is not None:
        residual["noise_var"] = np.full(frf.n_channels, np.nan)
        residual["noise_var"][strongest] = fit.noise_var
    # the noise as the fit's residual shows it (the raw estimate takes in curvature on coarse axes)
    chi2 = chi2_of(fit.noise_var, fit_noise(frf, bands, power, fit.omega_n, fit.damping_ratio,
                                           estimated_noise, strongest, known_noise, fit=fit))
    # the refinement may return the modes in another order (two close poles crossing)
    order = np.argsort(fit.omega_n)
    omega_n, damping_ratio = fit.omega_n[order], fit.damping_ratio[order]
    std_ref = np.sqrt(np.abs(fit.mode_cov[order][:, 0, [0, 1], [0, 1]]))  # (n_modes, 2)
    shift = truncation(frf, bands, power, fit, strongest)
    if shift is not None:  # the refinement's own truncation bias widens its errors
        std_ref = np.hypot(std_ref, shift[0][order])
    # an unconverged refinement still serves: a mode below the noise crawling along a flat
    # valley keeps LM from stopping while the other poles are long settled; the check only
    # adds flags and widens errors
    if not (np.all(np.isfinite(omega_n)) and np.all(damping_ratio > 0)):
        return [no_reference(chi2)] * n_modes, None
    missing = missing_mode_in_bands(frf, bands, power, omega_n, damping_ratio, estimated_noise, budget=budget)
    const_ref = constants_at_poles(frf, bands, power, omega_n, damping_ratio)
    out = []
    for r, (wn, zeta, *_) in enumerate(poles):
        band = bands[r]
        if not (band.low_hz <= omega_n[r] / TWO_PI <= band.high_hz and np.all(np.isfinite(std_ref[r]))):
            out.append(no_reference(chi2))
            continue
        d_const = np.where(np.isfinite(consts[r]) & np.isfinite(const_ref[r]), consts[r] - const_ref[r], 0)
        # a method value that is not a number gives no difference (it carries its own flags)
        d_wn = wn - omega_n[r] if np.isfinite(wn) else 0.0
        d_z = zeta - damping_ratio[r] if np.isfinite(zeta) else 0.0
        out.append((d_wn, d_z, d_const, chi2, *std_ref[r]))
    return out, missing


def chi2_of(residual_var, noise_std) -> float:
    """Median over channels of the residual variance over the estimated noise variance."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = residual_var / np.where(noise_std > 0, noise_std, np.nan) ** 2
    if not np.isfinite(ratio).any():
        return np.nan
    kept = ratio[~np.isnan(ratio)]  # the nan-median, without its cost on one channel
    return float(kept[0]) if kept.size == 1 else float(np.median(kept))


def constant_distance(difference: np.ndarray, cov: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """Per channel, the distance of a complex difference of modal constants in standard errors: the
    Mahalanobis distance of (Re, Im) under their 2×2 covariance ``cov`` (n_ch, 2, 2), each part's error
    at least ``floor`` (the refinement's own precision: on exact data the errors are rounding, and so
    is the difference).

    k, c, m depend on |A|, and a half-power or circle constant's covariance is often long across
    A and short along it: the difference divided by the total error sqrt(var Re + var Im) let a
    bias 10 of its errors along |A| pass as 1.9. Where the covariance
    is singular, that total error is used.
    """
    a, b, c = cov[:, 0, 0] + floor**2, cov[:, 0, 1], cov[:, 1, 1] + floor**2
    x, y = difference.real, difference.imag
    with np.errstate(divide="ignore", invalid="ignore"):
        det = a * c - b * b
        squared = (c * x * x - 2 * b * x * y + a * y * y) / det
        total = np.abs(difference) / np.sqrt(a + c)
    return np.where((det > 0) & (squared >= 0), np.sqrt(np.maximum(squared, 0)), total)


def local_misfit(frf, bands, power, omega_n, damping_ratio, data=None, band_peak=None) -> np.ndarray:
    """Per mode, the misfit near it relative to the data there (RMS over the strongest channels, at most
    ``POLE_CHANNELS``).

    In each band every fitted mode and a complex offset are solved linearly at the
    fitted poles; the residual is taken on the lines within ±3 half-power widths
    (at least ±3 lines) of the band's mode. ``data``: the :func:`band_data` of the bands
    (each band is a run of its lines); ``band_peak``: its :func:`band_peaks`.
    """
    out = np.full(len(bands), np.nan)
    if data is None:
        omega_all, response = frf.omega_rad_s, frf.channels
    else:
        omega_all, response, _ = data
    many = response.shape[0] > POLE_CHANNELS
    for b, (band, wn, zeta) in enumerate(zip(bands, omega_n, damping_ratio)):
        run = band_run(omega_all, band)  # a view: no copy of every channel
        if run.stop - run.start < 3:
            continue
        omega, h = omega_all[run], response[:, run]
        if many:  # the strong channels carry the misfit that matters; O(1) in channels
            peak = np.abs(h).max(axis=1) if band_peak is None else band_peak[b]
            h = h[np.argsort(peak)[::-1][:POLE_CHANNELS]]
        basis = mode_basis(omega, omega_n, damping_ratio, power).T
        design = np.hstack([basis, ((1j * omega) ** power)[:, None]])
        coef = solve_linear(design, h.T)
        residual = h - (design @ coef).T
        near = lines_near_mode(omega, wn, zeta)
        if near.sum() < 3:
            near = np.argsort(np.abs(omega - wn))[:3]
        data = np.linalg.norm(h[:, near])
        if data > 0:
            out[b] = np.linalg.norm(residual[:, near]) / data
    return out


def fit_noise(frf, bands, power, omega_n, damping_ratio, estimated_noise, channels=None, known=False, residual=None,
               fit=None, data=None):
    """:func:`modal.sdof.checks.residual_noise_std` on the lines of the bands (all or some channels).

    ``known``: the noise came with the FRF (an estimate from time data) and is taken as it is.
    ``residual``: the fit's residual on those lines and channels, if the caller has it.
    ``fit``: an unweighted :func:`fit_bands` fit of these poles on the same lines and channels,
    whose own residual is then used; ``data``: :func:`band_data` of them.
    """
    rows = slice(None) if channels is None else channels
    if known:
        return np.asarray(estimated_noise, float)[rows]
    if fit is not None:
        omega = frf.omega_rad_s[regions(bands, frf.frequency_hz)[0]] if data is None else data[0]
        with np.errstate(all="ignore"):
            return fit_residual_noise_std(omega, fit, np.asarray(estimated_noise, float)[rows])
    omega, response, region = band_data(frf, bands, channels) if data is None else data
    with np.errstate(all="ignore"):
        return residual_noise_std(omega, response, power, region, omega_n, damping_ratio, estimated_noise[rows],
                                  residual)


def missing_mode_in_bands(frf, bands, power, omega_n, damping_ratio, estimated_noise, residual=None, residual_noise=None,
                  data=None, peak=None, budget=None):
    """:func:`modal.sdof.checks.find_missing_mode` on the lines of the bands (``residual`` and ``residual_noise``:
    the fit's residual and its :func:`modal.sdof.checks.residual_noise_std`, if known; ``data``: the bands'
    :func:`band_data`; ``peak``: max |H| of each channel there; ``budget``: the identification's
    :class:`~modal.work_budget.EvaluationBudget`, which its trial fit shares)."""
    omega, response, region = band_data(frf, bands) if data is None else data
    bands_rad = [(TWO_PI * b.low_hz, TWO_PI * b.high_hz) for b in bands]
    with np.errstate(all="ignore"):
        return find_missing_mode(omega, response, power, region, omega_n, damping_ratio, estimated_noise,
                                 bands_rad, residual, residual_noise, peak, budget)
