"""The least-squares refinement of every band's mode together (method ``"nls"``, and the check of the others).

:func:`nls_fit` starts each band from the cheapest start that serves
(:mod:`modal.sdof.starts`) and fits all modes jointly (:func:`fit_bands`, over
:func:`modal.nls.fit_modes`), restarting a mode that collapsed onto a noise spike;
:func:`truncation` measures the bias of modes outside the bands where the residual
is smooth.
"""
from __future__ import annotations

import numpy as np

from ..flags import REL_STD_LIMIT
from ..leakage import bias_matters, window_bias
from ..nls import fit_modes, truncation_shift
from ..units import TWO_PI
from . import starts
from .bands import band_data, band_influence, band_relative_error, line_weight, line_whitening
from .checks import residual_structure, restart_pole

__all__ = ["STRUCTURED_RATIO", "doubtful", "nls_fit", "fit_cost", "fit_bands", "truncation", "with_shift",
           "without_window_bias", "WINDOW_BIAS_ROUNDS"]

#: rounds of the fixed point that fits the model convolved with the estimate's lag window
WINDOW_BIAS_ROUNDS = 3

#: a fit whose residual variance is more than this many times its line-to-line noise
#: (checks.residual_structure) has a smooth misfit: its truncation shift is measured
STRUCTURED_RATIO = 4.0


def doubtful(fit, bands) -> bool:
    """Whether a band-wise NLS fit shows a sign of a poor start: not converged, a pole outside
    its band, ζ at or past critical or not resolved (relative error above ``REL_STD_LIMIT``)."""
    if not fit.converged or not np.all(np.isfinite(fit.noise_var)):
        return True
    order = np.argsort(fit.omega_n)  # bands go up in frequency
    wn, zeta = fit.omega_n[order], fit.damping_ratio[order]
    s_zeta = np.sqrt(np.abs(fit.mode_cov[order, 0, 1, 1]))
    low = TWO_PI * np.array([b.low_hz for b in bands])
    high = TWO_PI * np.array([b.high_hz for b in bands])
    return not (np.all((wn >= low) & (wn <= high)) and np.all((zeta > 0) & (zeta < 1))
                and np.all(s_zeta <= REL_STD_LIMIT * zeta))


def nls_fit(frf, bands, power, noise, data=None, band_peak=None, budget=None):
    """The band-wise NLS fit of every band's mode, from the cheapest start that serves.

    Each band starts from its one-mode rational fit (a few linear solves); a band where
    that gives no pole, or a fit that looks doubtful (:func:`doubtful`), takes the
    half-power and circle starts of :func:`~modal.sdof.starts.start_pole` as well (of
    :func:`~modal.sdof.starts.principal_start`, one curve per band, for many channels), and the fit
    with the lower residual is kept.
    ``data``: the :func:`band_data` of the bands, when the caller has it; ``band_peak``: its
    :func:`band_peaks`. ``budget``: the identification's :class:`~modal.work_budget.EvaluationBudget`
    (where the quick fit spends it, the careful starts are not tried).
    """
    quick = [starts.quick_start(frf, band, power, noise) for band in bands]
    if all(q is not None for q in quick):
        fit = fit_bands(frf, bands, power, [q[0] for q in quick], [q[1] for q in quick], data=data,
                        band_peak=band_peak, budget=budget, noise=noise)
        if not doubtful(fit, bands) or (budget is not None and budget.spent):
            return fit
    else:
        fit = None
    start = starts.principal_start if frf.n_channels > 1 else starts.start_pole
    careful_starts = [start(frf, band, power, noise) for band in bands]
    careful = fit_bands(frf, bands, power, [s[0] for s in careful_starts], [s[1] for s in careful_starts], data=data,
                        band_peak=band_peak, budget=budget, noise=noise)
    if fit is None or fit_cost(careful) <= fit_cost(fit):
        return careful
    return fit


def fit_cost(fit) -> float:
    """Residual of a band-wise fit summed over channels, each over what it was fitted over (its noise where known,
    else its largest value: :attr:`modal.nls.NLSFit.weight_scale`)."""
    if not np.all(np.isfinite(fit.noise_var)):
        return np.inf
    return float(np.sum(fit.noise_var / fit.weight_scale**2))


def fit_bands(frf, bands, power, omega_n0, damping_ratio0, channels=None, data=None, band_peak=None, budget=None,
              noise=None):
    """:func:`modal.nls.fit_modes` of every band's mode together, with collapsed modes reseated.

    A weak mode whose start lies on a noise spike can collapse there inside the
    joint fit (ζ shrinking to the spike's width, its error larger than a tenth
    of it) while its neighbour absorbs the real mode: a neighbour 5.4 errors
    off, unflagged, with the collapsed mode formally still in the model. Such a mode (relative error of ζ above
    ``REL_STD_LIMIT``, or ζ ≥ 1) restarts where the residual of the other
    modes peaks in its band (:func:`modal.sdof.checks.restart_pole`), and the joint
    fit runs again. The restart is kept only when its residual is lower: the
    reported fit is the better least-squares optimum of the same model. ``data``: the
    :func:`band_data` of these bands and channels, when the caller has it; ``band_peak``: its
    :func:`band_peaks`. ``budget``: an :class:`~modal.work_budget.EvaluationBudget` each fit takes what is left
    of (no restart once it is spent). ``noise``: each of the FRF's channels' noise standard deviation, when
    known: the channels are weighed by it (:func:`modal.nls.fit_modes`'s ``channel_noise``).
    """
    omega, response, region = band_data(frf, bands, channels) if data is None else data
    weight = line_weight(frf, bands)
    whitening = line_whitening(frf, bands)
    lags = correlated_lags(frf, omega, damping_ratio0, omega_n0)
    influence, overlapping = band_influence(frf, bands, channels)
    common = band_relative_error(frf, bands, channels)
    scale = None if band_peak is None else band_peak.max(axis=0)  # max |H| of each channel on the lines
    if noise is not None:
        noise = np.asarray(noise, float) if channels is None else np.asarray(noise, float)[channels]
    with np.errstate(all="ignore"):
        fit = fit_modes(omega, response, power, omega_n0, damping_ratio0, region=region, line_weight=weight,
                        channel_scale=scale, whitening=whitening, correlated_lags=lags,
                        record_influence=influence, overlapping_records=overlapping, relative_error=common,
                        max_evaluations=None if budget is None else budget.for_fit(), channel_noise=noise)
    if budget is not None:
        budget.spend(fit)
    if len(bands) < 2:
        return fit
    for r in range(len(bands)):
        if budget is not None and budget.spent:
            break
        zeta, s_zeta = fit.damping_ratio[r], np.sqrt(abs(fit.mode_cov[r, 0, 1, 1]))
        if zeta < 1 and s_zeta <= REL_STD_LIMIT * zeta:
            continue
        band = bands[int(np.sum(fit.omega_n < fit.omega_n[r]))]  # bands go up in frequency
        in_band = (omega >= TWO_PI * band.low_hz) & (omega <= TWO_PI * band.high_hz)
        others = np.arange(len(bands)) != r
        with np.errstate(all="ignore"):
            start = restart_pole(omega, response, power, region, fit.omega_n[others],
                                 fit.damping_ratio[others], in_band)
        if start is None:
            continue
        start_wn, start_zeta = fit.omega_n.copy(), fit.damping_ratio.copy()
        start_wn[r], start_zeta[r] = start
        with np.errstate(all="ignore"):
            restart = fit_modes(omega, response, power, start_wn, start_zeta, region=region, line_weight=weight,
                                channel_scale=scale, whitening=whitening, correlated_lags=lags,
                                record_influence=influence, overlapping_records=overlapping,
                                relative_error=common, max_evaluations=None if budget is None else budget.for_fit(),
                                channel_noise=noise)
        if budget is not None:
            budget.spend(restart)
        if fit_cost(restart) < fit_cost(fit):
            fit = restart
    return fit


def correlated_lags(frf, omega, damping_ratio, omega_n) -> int:
    """Lags over which an estimate's errors may correlate beyond its noise model: the half-power width of the
    narrowest mode in lines (at least 2, at most a sixth of the lines), for an FRF estimated from time records
    (it carries a :class:`~modal.noise_model.NoiseModel`); 0 otherwise."""
    if frf.noise_model is None or omega.size < 12:
        return 0
    spacing = float(np.median(np.diff(omega)))
    width = 2 * np.asarray(damping_ratio, float) * np.asarray(omega_n, float) / spacing
    width = width[np.isfinite(width) & (width > 0)]
    lines = int(np.ceil(width.min())) if width.size else 2
    return int(np.clip(lines, 2, omega.size // 6))


def truncation(frf, bands, power, fit, channels=None, residual=None, data=None):
    """Shift of the fit when the band backgrounds gain a slope and a curvature, or None.

    Measured only where the residual is smooth across the lines (ratio of
    :func:`modal.sdof.checks.residual_structure` above ``STRUCTURED_RATIO``): there
    the noise is below the misfit of the plain offset, and the shift is the
    truncation bias of the modes outside the bands (:func:`modal.nls.truncation_shift`).
    With white residuals the shift would be noise only and is not measured.
    Returns (pole shift (n_modes, 2), constant shift (n_modes, n_channels)) in
    the fit's order of modes. ``residual``: the fit's residual, if the caller has it; ``data``: the
    :func:`band_data` of these bands and channels.
    """
    omega, response, region = band_data(frf, bands, channels) if data is None else data
    with np.errstate(all="ignore"):
        structure = residual_structure(omega, response, power, region, fit.omega_n, fit.damping_ratio, residual,
                                       peak=fit.channel_scale)
    if not structure > STRUCTURED_RATIO:
        return None
    return truncation_shift(omega, response, power, region, fit)


def with_shift(cov, pole_shift, constant_shift):
    """Covariance (n_ch, 4, 4) of one mode plus the outer product of its shift per channel."""
    d = np.column_stack([np.broadcast_to(pole_shift, (constant_shift.size, 2)),
                         constant_shift.real, constant_shift.imag])
    return cov + d[:, :, None] * d[:, None, :]


def without_window_bias(frf, bands, power, data, band_peak, fit, budget=None, noise=None):
    """The fit of the model convolved with the estimate's lag window (:mod:`modal.leakage`), when its window
    biases these modes: the data less the window's bias of the fitted modes, refitted, a few rounds (a fixed
    point; the bias changes little with the poles, each round takes its error down by the bias's own
    relative change).

    Returns (data, fit, note): the corrected lines of the bands, their fit, and what was done (a sentence for
    the result's settings), or the arguments unchanged and None when the FRF carries no lag window or it
    does not bias these modes. ``budget``, ``noise``: as for :func:`fit_bands` (no round once it is spent).
    """
    model = frf.noise_model
    if model is None or not bias_matters(model.lag_window, model.sample_interval_s, fit.omega_n,
                                         fit.damping_ratio):
        return data, fit, None
    omega, response, region = data
    if budget is not None and budget.spent:
        return data, fit, None
    first, corrected = fit, data
    for _ in range(WINDOW_BIAS_ROUNDS):
        if budget is not None and budget.spent:
            break
        with np.errstate(all="ignore"):
            bias = window_bias(omega, power, fit.omega_n, fit.damping_ratio, fit.modal_constant, model.lag_window,
                               model.sample_interval_s)
        if not np.all(np.isfinite(bias)):
            return data, first, None
        corrected = (omega, response - bias, region)
        fit = fit_bands(frf, bands, power, fit.omega_n, fit.damping_ratio, data=corrected, band_peak=band_peak,
                        budget=budget, noise=noise)
        if not (np.all(np.isfinite(fit.omega_n)) and np.all(np.isfinite(fit.damping_ratio))):
            return data, first, None
    with np.errstate(all="ignore"):
        s_zeta = np.sqrt(np.abs(fit.mode_cov[:, 0, 1, 1]))
        moved = np.abs(np.sort(fit.damping_ratio) - np.sort(first.damping_ratio)) / s_zeta[np.argsort(fit.omega_n)]
    largest = float(np.nanmax(moved)) if np.any(np.isfinite(moved)) else 0.0
    note = (f"fitted the model convolved with the estimate's lag window (leakage of {model.lag_window.size}-sample "
            f"records); damping moved by up to {largest:.2g} standard errors")
    return corrected, fit, note
