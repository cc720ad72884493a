"""The band-wise methods, one mode per band: half-power, circle fit and least squares (``"nls"``).

:func:`identify_bands` runs one method on given bands, in one sequence:

1. the noise per channel: the FRF's own per line (an estimate from time data), the
   caller's, or the raw-data estimate;
2. the method's poles and modal constants (:mod:`modal.sdof.estimates` for half-power
   and circle, :mod:`modal.sdof.refine` for least squares) with their covariance;
3. its checks (:mod:`modal.sdof.quality`): chi-square and misfit near each mode, a
   mode the bands missed and, for half-power and circle, the distance from the
   least-squares refinement of the same modes (a bias beyond the errors is folded
   into them, flag ``method_bias``);
4. the results, through :func:`modal.assemble.assemble_modes`.
"""
from __future__ import annotations

import numpy as np

from ..assemble import ModeEstimate, assemble_modes, driving_points
from ..flags import BIAS_LIMIT, model_inadequate
from ..frf import KIND_POWER, line_spacing
from ..noise_model import MAX_INFLUENCE_VALUES, MEASURED_CORRELATION_RECORDS
from ..peaks import channel_sample, neighbour_noise_rms
from ..results import IdentificationResult
from ..units import TWO_PI
from .bands import (POLE_CHANNELS, band_data, band_mask, band_noise, band_peaks, constants_at_poles, regions,
                    strongest_channels)
from .checks import fit_residual, fit_residual_noise_std
from .estimates import bandwise_covariance, rescaled, sdof_estimates, without_neighbours
from .quality import chi2_of, constant_distance, fit_noise, local_misfit, missing_mode_in_bands, refinement_check
from .refine import nls_fit, truncation, with_shift, without_window_bias
from ..work_budget import EvaluationBudget, default_max_evaluations

__all__ = ["BANDWISE_METHODS", "identify_bands"]

#: the band-wise methods (one band per mode)
BANDWISE_METHODS = ("nls", "circle", "halfpower")
#: relative precision of the refinement's poles (the stopping rule of :func:`modal.nls.fit_modes`)
REFINEMENT_PRECISION = 1e-13


def identify_bands(frf, method: str, bands, *, raw_noise: np.ndarray, noise_std=None,
                   driving_point=None, max_evaluations: int | None = None) -> IdentificationResult:
    """Identify one mode per band with a band-wise method.

    Parameters
    ----------
    frf : FRF
    method : {"nls", "circle", "halfpower"}
    bands : list of ModeBand
        One band per mode, in increasing frequency (:func:`modal.peaks.find_modes`,
        :func:`modal.peaks.bands_from_hz`).
    raw_noise : ndarray, shape (n_channels,)
        The raw-data noise estimate per channel (:func:`modal.peaks.estimate_noise_std`).
    noise_std : float or array_like over channels, optional
        Known noise σ per channel (finite, >= 0); default: the FRF's own per line, else ``raw_noise``.
    driving_point : bool, array_like of bool or channel indices, optional
        Declares which channels are driving points (:func:`modal.assemble.driving_points`).
    max_evaluations : int, optional
        Model evaluations the least-squares fits may take together (``"nls"``'s, or those of the refinement that
        checks a half-power or circle estimate; default
        :func:`modal.work_budget.default_max_evaluations`); where they run out the modes are flagged
        ``work_capped``, with a warning.
    """
    power = KIND_POWER[frf.kind]
    n_ch = frf.n_channels
    estimated_noise = raw_noise
    # an FRF estimated from time data carries its own calibrated noise per line (modal.estimate_frf)
    line_noise = frf.noise_std
    known_noise = noise_std is None and line_noise is not None
    if known_noise:
        estimated_noise = band_noise(frf, bands, line_noise)
    noise = estimated_noise if noise_std is None else np.broadcast_to(np.asarray(noise_std, float), (n_ch,)).copy()
    if method in ("halfpower", "circle"):
        rescale = noise_std is None and not known_noise
        estimates, missing_mode, budget = _single_mode_fits(frf, bands, power, method, noise, estimated_noise,
                                                            known_noise, rescale, max_evaluations)
        settings = {}
        fitted = "the least-squares refinement that checks it"
    else:
        estimates, missing_mode, settings, budget = _least_squares_fits(frf, bands, power, noise, estimated_noise,
                                                                        known_noise, max_evaluations)
        fitted = "the least-squares fit"
    settings.update(max_evaluations=int(budget.limit), evaluations=int(budget.used))
    if budget.capped:
        from ..errors import QualityWarning, warn_caller

        warn_caller(f"{frf.source}: {method}: {fitted} stopped at its budget of {budget.limit} model evaluations "
                    "before converging (the checks that refit were cut short); its modes are flagged "
                    "work_capped; identify(..., max_evaluations=N) or --max-evaluations N with N above it lets it "
                    "go on", QualityWarning)
    for index, (band, estimate) in enumerate(zip(bands, estimates)):
        if missing_mode is not None and (missing_mode.band == index or index in missing_mode.moved_bands):
            estimate.flags.add("missing_mode")
            estimate.details["missing_mode"] = (f" (near {missing_mode.frequency_hz:.6g} Hz, "
                                                f"zeta {missing_mode.damping_ratio:.3g})")
        if any(b is not band and band.low_hz < b.peak_hz < band.high_hz for b in bands):
            estimate.flags.add("close_modes")  # another mode's peak inside this mode's band
    driving, known = driving_points(frf, driving_point)
    modes = assemble_modes(estimates, method=method, source=frf.source, single=frf.response.ndim == 1,
                           driving=driving, driving_known=known,
                           window_decay_s=frf.exponential_decay_s, window_power=KIND_POWER[frf.kind])
    return IdentificationResult(modes, method, frf.kind, n_ch, noise_std=estimated_noise, settings=settings)


def _estimate(frf, band, wn, zeta, const, cov, s_wn, s_z, flags, chi2, quality, reference=None) -> ModeEstimate:
    """A band's mode as a :class:`~modal.assemble.ModeEstimate` (its band, lines and resolution with it)."""
    omega_b = frf.omega_rad_s[band_mask(frf, band)]
    spacing = line_spacing(omega_b) if omega_b.size > 1 else np.nan
    return ModeEstimate(wn, zeta, np.asarray(const, complex), cov, s_wn, s_z, (band.low_hz, band.high_hz),
                        int(omega_b.size), 2 * zeta * wn / spacing if spacing > 0 else np.nan, set(flags),
                        chi2=chi2, quality=quality, reference=reference)


def _single_mode_fits(frf, bands, power, method, noise, estimated_noise, known_noise, rescale, max_evaluations=None):
    """Half-power or circle estimates of every band's mode, checked against their least-squares refinement.

    ``rescale``: the errors follow the noise the refinement's residual shows (the noise was not given).
    ``max_evaluations``: the refinement's budget of model evaluations (default scaled to the size of one, on the
    bands' lines and the channels it fits); where it binds, no mode is checked and every mode is flagged
    ``work_capped``.
    Returns the modes' :class:`~modal.assemble.ModeEstimate`, the missing mode found (or None) and the
    refinement's :class:`~modal.work_budget.EvaluationBudget`.
    """
    n_ch = frf.n_channels
    poles = []
    for band in bands:
        strongest = None
        if n_ch > POLE_CHANNELS:
            strongest = strongest_channels(frf, band, noise, POLE_CHANNELS)
        poles.append(sdof_estimates(frf, band, power, noise, method, strongest))
    if method == "halfpower" and len(bands) > 1:
        poles = without_neighbours(frf, bands, power, noise, poles)
    consts = np.array([p[4] for p in poles])  # (n_modes, n_ch)
    missing = ~np.isfinite(consts)
    if method == "halfpower":
        # half-power gives poles only: every constant from one solve with all the poles
        # (a peak-height constant ignores the neighbours' contribution)
        missing[:] = True
    if missing.any():
        filled = constants_at_poles(frf, bands, power, [p[0] for p in poles], [p[1] for p in poles])
        consts[missing] = filled[missing]
    refined = {}
    lines, region = regions(bands, frf.frequency_hz)  # the refinement's lines and its offsets (one per region)
    n_regions = int(region.max()) + 1 if region.size else 0
    budget = EvaluationBudget(max_evaluations or default_max_evaluations(int(np.count_nonzero(lines)), len(bands),
                                                                         min(n_ch, POLE_CHANNELS), n_regions))
    check, missing_mode = refinement_check(frf, bands, power, poles, consts, noise, estimated_noise, known_noise,
                                           refined, budget)
    if rescale:
        poles = rescaled(frf, bands, power, poles, noise, refined.get("noise_var"))
    errors = bandwise_covariance(frf, bands, power, poles, noise, ~missing if method == "circle" else None)
    # the misfit near each mode of the refined model (the model whose chi-square is tested)
    refined_poles = np.array([[p[0] - c[0], p[1] - c[1]] for p, c in zip(poles, check)], float)
    usable = np.all(np.isfinite(refined_poles), axis=1) & np.all(refined_poles > 0, axis=1)
    relative = np.full(len(bands), np.nan)
    if usable.all():
        relative = local_misfit(frf, bands, power, refined_poles[:, 0], refined_poles[:, 1])
    estimates = []
    for b, (band, (wn, zeta, s_wn, s_z, _, flags, q, _e), const, cov, reference) in enumerate(zip(
            bands, poles, consts, errors, check)):
        d_wn, d_z, d_const, chi2, bound_wn, bound_z = reference
        if model_inadequate(chi2, relative[b]):
            flags.add("model_inadequate")
        if budget.capped:  # the refinement stopped at its budget: the estimate is not checked against it
            flags.add("work_capped")
        # the difference from the refinement has at most the variance of the two errors
        # together (equality when they are independent; less when both see the same noise)
        scale_wn = np.hypot(np.nan_to_num(s_wn), bound_wn)
        scale_z = np.hypot(np.nan_to_num(s_z), bound_z)
        pole_biased = abs(d_wn) > BIAS_LIMIT * scale_wn or abs(d_z) > BIAS_LIMIT * scale_z
        noise_cov = cov.copy()  # k, c, m take the bias exactly (modal.assemble.physical_with_flags), not through it
        if pole_biased:
            # the method's own bias dominates its noise error: fold it into the errors, with
            # the error of the refinement that measures it (its standard error, and at least
            # its stopping rule, relative step 1e-13: on exact data its actual error is that
            # rounding, 30x its rounding-level standard error)
            fold_wn = abs(d_wn) + np.hypot(bound_wn, REFINEMENT_PRECISION * abs(wn - d_wn))
            fold_z = abs(d_z) + np.hypot(bound_z, REFINEMENT_PRECISION * abs(zeta - d_z))
            cov[:, 0, 0] += fold_wn**2
            cov[:, 1, 1] += fold_z**2
            s_wn = float(np.hypot(np.nan_to_num(s_wn), fold_wn))
            s_z = float(np.hypot(np.nan_to_num(s_z), fold_z))
        # modal constants against each channel's own error (the circle's come from its
        # geometry, which a neighbour bends even when the pole passes)
        with np.errstate(divide="ignore", invalid="ignore"):
            z_const = constant_distance(d_const, cov[:, 2:, 2:], REFINEMENT_PRECISION * np.abs(const - d_const))
        const_biased = pole_biased | (z_const > BIAS_LIMIT)
        # biased: the difference is added to the covariance along it
        diff = np.column_stack([d_const.real, d_const.imag])
        extra = np.where(const_biased, 1.0, 0.0)
        cov[:, 2:, 2:] += extra[:, None, None] * diff[:, :, None] * diff[:, None, :]
        finite = z_const[np.isfinite(z_const)]
        if pole_biased or (finite.size and np.median(finite) > BIAS_LIMIT):
            flags.add("method_bias")
        reference = None
        if pole_biased or np.any(const_biased):
            reference = (wn - d_wn, zeta - d_z, np.where(const_biased, const - d_const, const), noise_cov)
        estimates.append(_estimate(frf, band, wn, zeta, const, cov, s_wn, s_z, flags, chi2, q, reference))
    return estimates, missing_mode, budget


def _least_squares_fits(frf, bands, power, noise, estimated_noise, known_noise, max_evaluations=None):
    """The joint least-squares fit of every band's mode (method ``"nls"``) and its checks.

    Returns the modes' :class:`~modal.assemble.ModeEstimate`, the missing mode found (or None), the result's
    settings for an estimate from time records (what was done about the window's bias, ``window_bias``, and
    where the poles' errors came from, ``pole_errors``: :func:`pole_errors_note`), and the
    :class:`~modal.work_budget.EvaluationBudget` of the fits (``max_evaluations`` its limit, default scaled to
    the size of one evaluation); where the fits spent it, the checks that refit are not run.
    """
    data = band_data(frf, bands)  # the lines of the bands, taken out once
    band_peak = band_peaks(bands, data)
    n_regions = int(data[2].max()) + 1 if data[2] is not None and data[2].size else 0
    budget = EvaluationBudget(max_evaluations or default_max_evaluations(data[0].size, len(bands), frf.n_channels,
                                                                         n_regions))
    fit = nls_fit(frf, bands, power, noise, data, band_peak, budget)
    # an estimate from windowed records: fit the model as the window shows it (its bias is the window's)
    data, fit, note = without_window_bias(frf, bands, power, data, band_peak, fit, budget, noise)
    # the checks all measure the residual of the same modes on the same lines: the fit's own when it is
    # unweighted (no second solve), else computed once
    own = fit.residual is not None and not fit.line_weighted
    if own:
        residual = fit.residual
    else:
        with np.errstate(all="ignore"):
            residual = fit_residual(data[0], data[1], power, data[2], fit.omega_n, fit.damping_ratio)
    # χ² is a median over the channels: many channels are sampled (peaks.channel_sample)
    rows = channel_sample(frf.n_channels)
    if known_noise:
        residual_noise = estimated_noise[rows]
    elif own:
        with np.errstate(all="ignore"):
            residual_noise = fit_residual_noise_std(data[0], fit, estimated_noise[rows], rows)
    else:
        residual_noise = fit_noise(frf, bands, power, fit.omega_n, fit.damping_ratio, estimated_noise,
                                   residual=residual, data=data)[rows]
    chi2_noise = residual_noise
    if own and frf.noise_model is not None:
        # an estimate from one record (no noise level per line): the chi-square compares mean squares, and
        # where the noise level varies along the lines (noise on the force makes the errors proportional to
        # |H|, large at the peaks) the residual's RMS line-to-line misfit is the noise it holds, above its
        # median level; a misfit of the model, smooth on lines that resolve the modes, does not enter it
        with np.errstate(all="ignore"):
            chi2_noise = np.fmax(residual_noise, neighbour_noise_rms(data[0], fit.residual[rows]))
    chi2 = chi2_of(fit.noise_var[rows], chi2_noise)
    # the check's noise is the residual's own (of every channel, when at hand; else it measures its own)
    missing_mode = shift = None  # (neither check, each a refit, where the fits spent their budget)
    if not budget.capped:
        missing_mode = missing_mode_in_bands(frf, bands, power, fit.omega_n, fit.damping_ratio, estimated_noise,
                                             residual, None if known_noise or isinstance(rows, np.ndarray)
                                             else residual_noise, data, fit.channel_scale, budget)
        # near-exact data: the offset's truncation (modes outside the bands) biases the poles
        # beyond their white-noise errors; its measured shift is added to them
        # an estimate from many records (a continuous one carries its errors' correlation as measured over
        # them): the structure is read on the fit's own residual, whitened with that correlation (the raw
        # residual of a windowed estimate correlates between lines and looks smooth however well the model
        # fits: the shift, noise, was added to every random record's errors, 1.5-2 times too wide). With
        # fewer records the raw residual decides
        measured = frf.noise_model is not None and frf.noise_model.averages >= MEASURED_CORRELATION_RECORDS \
            and fit.residual is not None
        # errors measured over the records are widened by any misfit they do not see (the residual's power over
        # theirs, modal.record_variance.misfit_ratio), a truncation's too: its shift would count it twice (three
        # outputs of one shaker, whitened with the window's model: measured on 18 of 20 records, errors 1.2-1.6 wide)
        if not fit.record_errors:
            shift = truncation(frf, bands, power, fit, residual=fit.residual if measured else residual, data=data)
    order = np.argsort(fit.omega_n)  # two close poles may cross during the fit
    relative = local_misfit(frf, bands, power, fit.omega_n[order], fit.damping_ratio[order], data, band_peak)
    estimates = []
    for b, (band, r) in enumerate(zip(bands, order)):
        flags: set[str] = set()
        if budget.capped:  # a fit stopped at the budget: the poles are where it stood
            flags.add("work_capped")
        elif not fit.converged:
            flags.add("did_not_converge")
        if not np.all(np.isfinite(fit.noise_var)):
            flags.add("too_few_points")  # no lines left over for a residual: no errors
        elif not np.all(np.isfinite(fit.mode_cov[r])):
            # errors undetermined: the data do not determine a pole (pole_covariance.FISHER_RCOND)
            flags.add("high_uncertainty")
        if model_inadequate(chi2, relative[b]):
            flags.add("model_inadequate")
        cov = fit.mode_cov[r] if shift is None else with_shift(fit.mode_cov[r], shift[0][r], shift[1][r])
        s_wn = float(np.sqrt(max(cov[0, 0, 0], 0))) if np.isfinite(cov[0, 0, 0]) else np.nan
        s_z = float(np.sqrt(max(cov[0, 1, 1], 0))) if np.isfinite(cov[0, 1, 1]) else np.nan
        wn, zeta = float(fit.omega_n[r]), float(fit.damping_ratio[r])
        if not (band.low_hz <= wn / TWO_PI <= band.high_hz):
            flags.add("band_edge_peak")
        if frf.noise_model is not None and under_resolved(frf.frequency_hz, wn / TWO_PI, zeta):
            flags.add("resolution_limited")
        estimates.append(_estimate(frf, band, wn, zeta, fit.modal_constant[r], cov, s_wn, s_z, flags, chi2, chi2))
    settings = {} if note is None else {"window_bias": note}
    errors_note = pole_errors_note(frf.noise_model, fit)
    if errors_note is not None:
        settings["pole_errors"] = errors_note
    return estimates, missing_mode, settings, budget


#: an FRF estimated from time records whose mode's half-power band (fn ± ζ fn) holds fewer lines than this is
#: flagged ``resolution_limited`` by the least-squares fit too (as the global method flags every FRF): its
#: records' leakage then dominates the error and the fit's errors are too small. Measured on random excitation
#: (240 s, Hann, 16384-sample segments, 40 records each): z spread of fn / ζ 1.76 / 1.33 at 1.3 lines per
#: half-power bandwidth (80 records), 1.09–1.33 / 1.08–1.10 at 2.4–2.6, 1.04–1.15 / 0.85–1.19 at 3.8–4.0. An
#: FRF given as lines (exact or with independent noise) is not flagged: there the lines off the resonance
#: carry the pole
RESOLVED_LINES = 3


def under_resolved(frequency_hz: np.ndarray, natural_frequency_hz: float, damping_ratio: float) -> bool:
    """Whether fewer than :data:`RESOLVED_LINES` lines lie within the half-power band fn ± ζ fn."""
    half_width = damping_ratio * natural_frequency_hz
    return int(np.count_nonzero(np.abs(frequency_hz - natural_frequency_hz) <= half_width)) < RESOLVED_LINES


def pole_errors_note(model, fit) -> str | None:
    """Where the poles' errors of an estimate from many continuous records came from (a sentence), or None
    for an FRF that carries no records' influences and had none withheld."""
    if model is None:
        return None
    if fit.record_errors:
        return (f"measured over the {model.averages} records the FRF was estimated from (each record's share of "
                "its error projected through the fit)")
    if model.record_influence is not None:
        return ("from the fit's information and the lines' measured correlation: the records' covariance could not "
                "be measured (too few records for the parameters, or not positive definite)")
    if model.influence_withheld:
        return ("from the fit's information and the lines' measured correlation: the records' influences "
                f"({model.averages} records) exceed the memory budget of {MAX_INFLUENCE_VALUES} values")
    return None
