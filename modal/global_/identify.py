"""``identify(frf, method="global")``: pLSCF poles → stabilisation → selection → joint refinement.

1. Poles by pLSCF (:mod:`modal.global_.plscf`) over all channels and references,
   for a sweep of model orders, each output row weighted by its RMS.
2. Stabilisation diagram and automatic selection (:mod:`modal.global_.stabilisation`),
   or the user's ``modes_hz`` hints, or one ``order``.
3. Joint refinement of every selected pole and every channel's modal constant,
   with upper and lower residual terms, by complex nonlinear least squares
   (:func:`modal.nls.fit_modes`, variable projection); standard errors from
   its Jacobian with each channel's residual noise (or the FRF's known noise). The final
   fit of an FRF estimated from time records weighs and whitens its lines by the
   estimate's noise model, as the band-wise fits do.
4. Results per mode: the usual fields, plus mode shapes normalised per reference,
   the participation vector and the MPC; the result carries the residual terms
   (``synthesize``), the stabilisation diagram and the settings used.
"""
from __future__ import annotations

import numpy as np

from ..assemble import ModeEstimate, assemble_modes, driving_points
from ..errors import IdentificationError
from ..flags import MPC_LIMIT, RIGID_BODY_RATIO, WEAK_FRACTION, lines_near_mode, model_inadequate
from ..frf import FRF, KIND_POWER
from ..model import mode_basis, solve_linear
from ..nls import fit_modes, orthonormal_factor
from ..peaks import estimate_noise_std, find_modes
from ..quantiles import gamma_upper_inverse
from ..results import IdentificationResult
from ..sdof.bands import weight_on_lines, whitening_on_lines
from ..sdof.refine import correlated_lags
from ..shared_error import MAX_FACTOR_BYTES
from ..units import TWO_PI
from ..work_budget import EvaluationBudget, checked_max_evaluations, default_max_evaluations
from .plscf import MAX_DAMPING, plscf_poles
from .stabilisation import SelectedPole, outside_band_poles, select_poles, stabilisation
from .sweep import most_stable, plan_sweep, refinement_mode_limit, sweep_lines, sweep_orders
from .window import without_window_factor

__all__ = ["identify_global", "channel_grid", "mpc"]

#: the stabilisation sweep's basis reaches this factor above the highest line (its Nyquist frequency, a margin
#: off the top line). The arc beyond the lines holds no data, so the poles there are set by little: reaching
#: 1.25, cond R was 1e3 at order 14 and 2e14 at 56, and a 1e-12 relative perturbation of the real beam moved
#: poles by 10 % and changed which edge pole the selection kept (and where the joint fit took it). 1.05 keeps
#: cond R below 4e2 at order 56 and 3e6 at 120 (the poles move by < 1e-9 under that perturbation)
BEYOND_BAND = 1.05
#: ... and a low-order sweep (orders up to ABOVE_MAX_ORDER, cond R below 1e6) looks this far above the band for
#: the modes leaking into it: a mode just above the band is modelled far better by its pole than by the upper
#: residual term
ABOVE_BAND = 1.25
ABOVE_MAX_ORDER = 24
#: relative pole step at which the first stage of the joint refinement stops (significance test) ...
LOOSE_STEP_TOL = 1e-5
#: ... and the final one (far below any standard error the data give, far above rounding)
TIGHT_STEP_TOL = 1e-9
#: ... or where the Gauss–Newton step is below about sqrt(2 · this) standard errors of the poles (see
#: ``decrement_tol`` of :func:`modal.nls.fit_modes`): 0.14 standard errors in the first stage, 0.014 in the final
#: one. A pole outside the lines converges linearly (each step ~0.9 of the last): on the wide-band case it
#: crept for 60 iterations below a tenth of its standard error, which cost a third of the identification
LOOSE_DECREMENT = 1e-2
TIGHT_DECREMENT = 1e-4
#: the loose stages fit every line within this many half-power bandwidths of a pole, and those in the top and
#: bottom LOOSE_END_SHARE of the band (where modes outside it leak in), and every LOOSE_EVERY-th line elsewhere,
#: weighted by sqrt(LOOSE_EVERY): far from every mode a line adds a smooth share to the poles' information
#: and noise to the cost, which the sample with its weight keeps in expectation. Where that leaves more than
#: LOOSE_MAX_SHARE of the lines, every line
LOOSE_NEAR_BANDWIDTHS = 2.0
LOOSE_END_SHARE = 0.05
LOOSE_EVERY = 4
LOOSE_MAX_SHARE = 0.8
#: rounds of the search for modes left in the residual, and candidates taken per round
MISSING_ROUNDS = 3
MISSING_PER_ROUND = 4
#: a residual peak is a candidate mode only where its power over the channels stands this far above the
#: residual's median over the lines (20 dB): the model's misfit of real data, 1-2 % everywhere, is no mode
MISSING_PEAK_RATIO = 100.0
#: ... and where it holds at least this share of the data's power (the model has no mode at the peak)
MISSING_SHARE = 0.25


def channel_grid(frf: FRF):
    """How the channels form an outputs × references matrix for pLSCF.

    Returns
    -------
    index : ndarray of int, shape (n_outputs, n_references)
        Channel of each (output, reference) pair.
    references : list of str
    transposed : bool
        True when the references were more than the outputs and the matrix was
        transposed by reciprocity (a roving-hammer test: one response, many hammer points).
    A set of channels that is not a full grid (or has no point ids) is taken as
    one reference with every channel an output.
    """
    n = frf.n_channels
    single = (np.arange(n)[:, None], ["?"], False)
    if frf.response_points is None or frf.reference_points is None:
        return single
    outs = list(dict.fromkeys(frf.response_points))
    refs = list(dict.fromkeys(frf.reference_points))
    if len(outs) * len(refs) != n or len(refs) == 1:
        return single
    index = np.full((len(outs), len(refs)), -1)
    for ch, (o, r) in enumerate(zip(frf.response_points, frf.reference_points)):
        index[outs.index(o), refs.index(r)] = ch
    if (index < 0).any():
        return single
    if len(refs) > len(outs):
        return index.T, outs, True
    return index, refs, False


def mpc(shape: np.ndarray) -> float:
    """Modal phase collinearity of a complex vector (Pappa et al. 1993): 1 for a real vector."""
    re, im = shape.real, shape.imag
    sxx, syy, sxy = re @ re, im @ im, re @ im
    total = sxx + syy
    if total == 0:
        return float("nan")
    return float(((sxx - syy) ** 2 + 4 * sxy**2) / total**2)


def _significance(omega, H, power, wn, zeta, noise):
    """Per mode, the growth of the residual sum of squares without it, in units of the noise variance.

    One linear fit (LSFD) of every channel at the poles ``wn`` (rad/s), ``zeta`` with the residual terms;
    for a mode r the residual sum of squares would grow by |C_rc|²/[(DᴴD)⁻¹]_rr in channel c without it.
    Summed over the channels in units of each channel's noise variance this is Gamma(n_channels)-distributed
    when the pole only fits noise. None when the noise is unknown or the design is singular.
    """
    if not np.all(np.isfinite(noise)) or np.any(noise <= 0):
        return None
    design = _lsfd_design(omega, power, wn, zeta)
    norms = np.linalg.norm(design, axis=0)
    norms[norms == 0] = 1.0
    Q, R = orthonormal_factor(design / norms)  # the ratio below does not depend on the columns' scale
    try:
        Rinv = np.linalg.inv(R)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(Rinv)):
        return None
    coef = Rinv @ (Q.conj().T @ H.T)
    inv_diag = np.sum(np.abs(Rinv) ** 2, axis=1)  # diag (DᴴD)⁻¹ = diag R⁻¹R⁻ᴴ
    n_modes = wn.size
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.abs(coef[:n_modes]) ** 2 / inv_diag[:n_modes, None] / noise[None, :] ** 2
    if not np.all(np.isfinite(gain)):
        return None
    return gain.sum(axis=1)


def _significance_threshold(n_channels: int) -> float:
    """Upper 1e-6 quantile of Gamma(n_channels, 1): a mode that only fits noise exceeds it once in 10⁶."""
    return gamma_upper_inverse(n_channels, 1e-6)


def _significant(omega, H, power, selected, noise):
    """The selected poles whose modes explain more than the noise, and the dropped ones' frequencies (Hz).

    A mode is kept when its :func:`_significance` exceeds the 1e-6 quantile of its noise-only distribution.
    Noise poles that the stabilisation keeps (they settle at high orders near band edges and on noise)
    fall below it (data of the benchmark case: 126-138 against 179 for 120 channels; modes 1e5-1e8).
    """
    if not selected:
        return selected, []
    wn = np.array([p.omega_n for p in selected])
    zeta = np.array([p.damping_ratio for p in selected])
    statistic = _significance(omega, H, power, wn, zeta, noise)
    if statistic is None:
        return selected, []
    keep = statistic > _significance_threshold(H.shape[0])
    return [p for p, k in zip(selected, keep) if k], [float(w / TWO_PI) for w, k in zip(wn, keep) if not k]


def _spare_duplicates(omega_n, weak, statistic):
    """``weak`` without the stronger of two weak poles within 1 % of each other: two poles fitted to one mode
    share it, so each alone explains little, yet dropping both would lose the mode."""
    weak = weak.copy()
    for i in np.flatnonzero(weak):
        partners = np.flatnonzero(weak & (np.abs(omega_n / omega_n[i] - 1) < 0.01))
        partners = partners[partners != i]
        if partners.size and statistic[i] >= statistic[partners].max():
            weak[i] = False
    return weak


def _local_misfit(omega, H, misfit, noise, wn, zeta):
    """(chi-square, relative misfit) on the lines within ±3 half-power widths (at least ±3 lines) of a mode."""
    return _misfit_on(H, misfit, noise, lines_near_mode(omega, wn, zeta))


def _inadequate(H, misfit, noise, near) -> bool:
    """The flags' ``model_inadequate`` test on the lines ``near`` (a mask)."""
    return model_inadequate(*_misfit_on(H, misfit, noise, near))


def _misfit_on(H, misfit, noise, near):
    """(chi-square, relative misfit) on the lines ``near`` (a mask over the lines)."""
    if not near.any():
        return np.nan, np.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        chi2 = float(np.nanmean(np.abs(misfit[:, near]) ** 2 / np.where(noise > 0, noise, np.nan)[:, None] ** 2))
        relative = float(np.linalg.norm(misfit[:, near]) / np.linalg.norm(H[:, near]))
    return chi2, relative


def _loose_lines(omega, wn, zeta):
    """The lines of a loose stage (see :data:`LOOSE_EVERY`): (indices, weights), or None for every line."""
    n = omega.size
    spacing = float(np.median(np.diff(omega)))
    near = np.zeros(n, bool)
    for w, z in zip(wn, zeta):
        near |= np.abs(omega - w) <= max(LOOSE_NEAR_BANDWIDTHS * 2 * z * w, 3 * spacing)
    ends = max(int(LOOSE_END_SHARE * n), 3)
    near[:ends] = near[-ends:] = True
    keep = near | (np.arange(n) % LOOSE_EVERY == 0)
    if keep.sum() > LOOSE_MAX_SHARE * n:
        return None
    index = np.flatnonzero(keep)
    return index, np.where(near[index], 1.0, np.sqrt(LOOSE_EVERY))


def _fit_within(omega, H, power, wn, zeta, step_tol, budget=None, weighting=(None, None, 0, None), noise=None):
    """The joint fit with residual terms, without the poles that widen past :data:`MAX_DAMPING`.

    A pole that the stabilisation kept on the tail of a mode outside the lines (or on noise) has no
    resonance to lock onto: the fit widens it into a smooth background that absorbs what the residual
    terms leave, two such poles side by side (an invented pair, ζ ≈ 3-8 on the 60-channel case, which the
    significance test then kept: together they explain the out-of-band modes' leakage). The fit stops
    when a pole within the lines leaves the physical damping range, or ends outside it anywhere; it is
    dropped and the others go on from where they are.
    Returns the fit and the dropped poles' frequencies (Hz). ``budget``: the identification's
    :class:`~modal.work_budget.EvaluationBudget` (each fit takes what is left of it; a fit it stops is returned).
    ``weighting``: (line weights, :class:`~modal.whitening.LineWhitening`, lags, shared error factor) of every line, for the tight fits
    (:func:`_line_weighting`); the loose ones, on a sample of the lines, only start others and go unweighted.
    ``noise``: each channel's noise standard deviation, when known (the channels weighed by it).
    """
    removed: list[float] = []
    while True:
        with np.errstate(all="ignore"):
            # standard errors only for the final model (the loose fits only start others)
            tight = step_tol <= TIGHT_STEP_TOL
            lines = None if tight else _loose_lines(omega, wn, zeta)
            allowed = None if budget is None else budget.for_fit()
            if lines is None:
                weight, whitening, lags, common = weighting if tight else (None, None, 0, None)
                fit = fit_modes(omega, H, power, wn, zeta, region=None, residual_terms=True, step_tol=step_tol,
                                max_damping=MAX_DAMPING, errors=tight, max_evaluations=allowed,
                                decrement_tol=TIGHT_DECREMENT if tight else LOOSE_DECREMENT,
                                line_weight=weight, whitening=whitening, correlated_lags=lags if tight else 0,
                                relative_error=common, channel_noise=noise)
            else:
                index, line_weight = lines
                fit = fit_modes(omega[index], H[:, index], power, wn, zeta, region=None, residual_terms=True,
                                step_tol=step_tol, max_damping=MAX_DAMPING, errors=False,
                                decrement_tol=LOOSE_DECREMENT, line_weight=line_weight,
                                channel_scale=np.abs(H).max(axis=1), max_evaluations=allowed, channel_noise=noise)
        if budget is not None:
            budget.spend(fit)
            if fit.capped:
                return fit, removed
        # a pole outside the lines may pass through wide ones on its way to a mode there: only where it
        # converges does its damping say it is background
        wide = fit.escaped | (fit.damping_ratio > MAX_DAMPING)
        if not wide.any() or wide.all():
            return fit, removed
        removed += [float(w / TWO_PI) for w in fit.omega_n[wide]]
        wn, zeta = fit.omega_n[~wide], fit.damping_ratio[~wide]


def _refine(omega, H, power, wn0, zeta0, noise, step_tol=LOOSE_STEP_TOL, budget=None,
            weighting=(None, None, 0, None)):
    """Joint refinement of the poles (rad/s, 1) to ``step_tol``, with the significance test at the refined
    poles: the modes that only fit noise are dropped and the others refitted, until none is.

    The search for missing modes refines to 1e-5 relative (:data:`LOOSE_STEP_TOL`), enough to test every
    mode's significance at its refined pole (a pLSCF pole on the tail of a wide mode or near a band edge
    can pass the test at its pLSCF value, then shrink onto a noise spike: 1 channel, 0.1 % noise: 1.9-9
    against 13.8 after refinement); the final model, from there, to 1e-9 relative
    (:data:`TIGHT_STEP_TOL`): far below any standard error the data give (1e-6 at best), far above
    rounding. A collapsing noise mode creeps for tens of iterations (its ζ shrinking by ~20 % each); the
    loose stages stop it early (benchmark case: 53 -> 24 iterations).
    Returns the fit and the frequencies (Hz) of the poles dropped. ``budget``: as for :func:`_fit_within`;
    once it is spent, no mode is tested or dropped. ``weighting``: as for :func:`_fit_within`.
    """
    n_ch = H.shape[0]
    fit, dropped = _fit_within(omega, H, power, wn0, zeta0, step_tol, budget, weighting, noise)
    for _ in range(3):
        if budget is not None and budget.spent:
            break
        statistic = _significance(omega, H, power, fit.omega_n, fit.damping_ratio, noise)
        weak = np.zeros(fit.omega_n.size, bool) if statistic is None else statistic <= _significance_threshold(n_ch)
        if weak.all():
            weak[:] = False  # nothing explains more than the noise: keep the model, its flags say so
        weak = _spare_duplicates(fit.omega_n, weak, statistic)
        if not weak.any():
            break
        dropped += [float(w / TWO_PI) for w in fit.omega_n[weak]]
        fit, removed = _fit_within(omega, H, power, fit.omega_n[~weak], fit.damping_ratio[~weak], step_tol, budget,
                                   weighting, noise)
        dropped += removed
    return fit, dropped


def _line_weighting(frf: FRF, omega_n, damping_ratio):
    """(line weights, :class:`~modal.whitening.LineWhitening`, lags, shared error factor) of every line of ``frf`` for
    the final fit, as the band-wise fits take them (:func:`modal.sdof.bands.line_weight`,
    :func:`~modal.sdof.bands.line_whitening`, :func:`modal.sdof.refine.correlated_lags` at the poles ``omega_n``
    (rad/s), ``damping_ratio``, :func:`~modal.sdof.bands.band_relative_error`): an estimate from time records
    carries its lines' noise shape and their correlation (an exponential window correlates its errors over tens of
    lines), its errors may correlate beyond that over a half-power width (the lag covariance then widens the
    errors of several channels), and the excitation's noise is an error every channel shares, a gain error of
    every line near a mode in the modal constants; None, None, 0, None where the FRF does not carry them (the
    shared error also where its factor on every line exceeds :data:`~modal.shared_error.MAX_FACTOR_BYTES`, each
    channel's share of it)."""
    every = np.ones(frf.n_freq, bool)
    model = frf.noise_model
    common = None if model is None or model.relative_error is None else model.relative_error.factor()
    if common is not None and common.ndim == 2 and common.nbytes * frf.n_channels > MAX_FACTOR_BYTES:
        common = None  # each channel's share of it, in the fit's units, would exceed the memory budget
    return (weight_on_lines(frf, every), whitening_on_lines(frf, every),
            correlated_lags(frf, frf.omega_rad_s, damping_ratio, omega_n), common)


def _poles_above_band(omega, matrix, orders, low_hz, high_hz, taken):
    """Candidate poles above the lines from a low-order pLSCF sweep reaching :data:`ABOVE_BAND` times the highest
    line (its orders ≤ :data:`ABOVE_MAX_ORDER`, at least three), those not within 1 % of a pole in ``taken``."""
    low_orders = sorted({o for o in orders if o <= ABOVE_MAX_ORDER} | set(orders[:3]))
    packs = plscf_poles(omega, matrix, low_orders, beyond=ABOVE_BAND)
    found = outside_band_poles(packs, stabilisation(packs), low_hz, high_hz, taken)
    return [p for p in found if p.omega_n > omega[-1]]


def _lsfd_design(omega, power, wn, zeta):
    """The modes' columns at the poles, then the upper and lower residual terms, (n_freq, n_modes + 2)."""
    kind_factor = (1j * omega) ** power
    return np.hstack([mode_basis(omega, wn, zeta, power).T, kind_factor[:, None], -(kind_factor / omega**2)[:, None]])


def _lsfd(omega, H, power, wn, zeta):
    """One linear fit (LSFD) of every channel at the poles with the residual terms: the coefficients
    (n_modes + 2, n_ch: the modal constants, then the upper and lower residual) and the misfit H − model."""
    design = _lsfd_design(omega, power, wn, zeta)
    norms = np.linalg.norm(design, axis=0)
    norms[norms == 0] = 1.0
    # columns scaled to unit norm: receptance's 1/ω² and the residual terms' 1 differ by 1e16 at 1e8 rad/s
    Q, R = orthonormal_factor(design / norms)
    diagonal = np.abs(np.diag(R))
    if not diagonal.min() > 1e-12 * diagonal.max():  # two poles at one frequency: the least-norm solution
        coef = solve_linear(design, H.T)
        return coef, H - (design @ coef).T
    projected = Q.conj().T @ H.T  # (n_modes + 2, n_ch)
    return np.linalg.solve(R, projected) / norms[:, None], H - (Q @ projected).T


def _residual_peaks(omega, H, misfit, noise, omega_n):
    """Poles (rad/s, ζ) of modes the model misses, from peaks of its residual; empty arrays when none.

    The residual power over the channels in units of each channel's noise variance, Σ_c |r_c|²/σ_c², is
    Gamma(n_ch)-distributed on a line where the model explains all but noise. A candidate is a local
    maximum of it above the 1e-6 quantile of that distribution divided among the lines (so noise alone
    gives one once in 10⁶ fits) and :data:`MISSING_PEAK_RATIO` times its median over the lines, where the
    residual holds at least :data:`MISSING_SHARE` of the data's power over the channels (the model has no
    mode there: a missed mode leaves ~100 % of its peak; the misfit of a linear model near a measured peak,
    real beam, at most 21 % in amplitude, 4 % in power), away from
    the band's ends (an out-of-band mode's tail) and from the model's poles by two line spacings. Its
    damping starts at the width over which the residual power stays above half its peak (a half-power
    bandwidth of at least one line spacing). At most :data:`MISSING_PER_ROUND` candidates, the strongest.
    """
    if not np.all(np.isfinite(noise)) or np.any(noise <= 0) or omega.size < 10:
        return np.zeros(0), np.zeros(0)
    n_ch, n_freq = misfit.shape
    power = np.einsum("cf,c->f", np.abs(misfit) ** 2, 1.0 / noise**2)
    limit = max(gamma_upper_inverse(n_ch, 1e-6 / n_freq), MISSING_PEAK_RATIO * float(np.median(power)))
    share = np.sum(np.abs(misfit) ** 2, axis=0) / np.maximum(np.sum(np.abs(H) ** 2, axis=0), np.finfo(float).tiny)
    inner = power[1:-1]
    peak = np.flatnonzero((inner >= power[:-2]) & (inner > power[2:]) & (inner > limit)) + 1
    peak = peak[share[peak] >= MISSING_SHARE]
    spacing = float(np.median(np.diff(omega)))
    peak = peak[(peak >= 2) & (peak <= n_freq - 3)]
    if omega_n.size:
        peak = peak[np.min(np.abs(omega[peak, None] - omega_n[None, :]), axis=1) > 2 * spacing]
    peak = peak[np.argsort(power[peak])[::-1][:MISSING_PER_ROUND]]
    wn, zeta = [], []
    for k in peak:
        lo, hi = k, k
        while lo > 0 and power[lo - 1] > power[k] / 2:
            lo -= 1
        while hi < n_freq - 1 and power[hi + 1] > power[k] / 2:
            hi += 1
        width = max(omega[hi] - omega[lo], spacing)
        wn.append(omega[k])
        zeta.append(width / (2 * omega[k]))
    return np.array(wn), np.array(zeta)


def _excess_misfit(omega, misfit, noise, omega_n, damping_ratio):
    """Per mode, the misfit power over the channels in units of each one's noise variance, Σ_c |r_c|²/σ_c², beyond
    what noise alone leaves (n_channels a line), summed over the lines near it (:func:`lines_near_mode`)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        power = np.nansum(np.abs(misfit) ** 2 / np.where(noise > 0, noise, np.nan)[:, None] ** 2, axis=0)
    excess = power - misfit.shape[0]
    return np.array([excess[lines_near_mode(omega, wn, z)].sum() for wn, z in zip(omega_n, damping_ratio)])


def _split_candidate(omega, omega_n, excess, r):
    """The mode to try as two for the misfit near mode ``r``: the nearest mode within the lines that leaves more
    misfit near itself than ``r`` does, else ``r``. A peak one pole fits short (an under-resolved peak of real
    data: one pole leaves 2 % of the beam's 958 Hz peak, a pair 0.7 %) spreads its misfit along its skirt onto
    a weak neighbour (the 901 Hz mode, 57 Hz away: 4.3 % misfit near it, 1.5 % with the pair); split, the weak
    mode's two poles leave it for the stronger misfit."""
    inside = (omega_n > omega[0]) & (omega_n < omega[-1]) & (excess > excess[r])
    if not inside.any():
        return r
    others = np.flatnonzero(inside)
    return int(others[np.argmin(np.abs(omega_n[others] - omega_n[r]))])


def _add_missing(omega, H, power, fit, misfit, coef, noise, budget=None):
    """One round of the search for modes the model misses: (fit, misfit, coef, dropped Hz), or the inputs
    with None when no candidate was kept.

    Modes the stabilisation did not show stand in the residual of the fit: an under-resolved peak whose
    damping wanders from order to order, where the model has no mode (:func:`_residual_peaks`), and a
    mode pLSCF merged with its neighbour, where one pole leaves the data near it unexplained (the flags'
    ``model_inadequate`` test: chi-square and relative misfit) and is tried as two, ωn(1 ± ζ). The
    candidates enter the refinement together, and each is kept where the model with it explains the data
    around it (the ``model_inadequate`` test passes there: misfit at the noise or within
    :data:`~modal.flags.RELATIVE_MISFIT` of the data): a residual of real data that one more mode does not
    explain is the model's limit, not a mode, and its candidate is taken out again. ``budget``: as for
    :func:`_refine`.
    """
    wn_new, zeta_new = _residual_peaks(omega, H, misfit, noise, fit.omega_n)
    regions = [np.abs(omega - w) <= 3.5 * float(np.median(np.diff(omega))) for w in wn_new]
    excess = _excess_misfit(omega, misfit, noise, fit.omega_n, fit.damping_ratio)
    near_of = {}  # mode to split -> the lines it must explain: those of the modes whose misfit it stands for
    for r, (wn, zeta) in enumerate(zip(fit.omega_n, fit.damping_ratio)):
        chi2, relative = _local_misfit(omega, H, misfit, noise, wn, zeta)
        if omega[0] < wn < omega[-1] and model_inadequate(chi2, relative):
            q = _split_candidate(omega, fit.omega_n, excess, r)
            if q in near_of or len(near_of) < MISSING_PER_ROUND:
                near_of[q] = near_of.get(q, False) | lines_near_mode(omega, wn, zeta)
    split = np.zeros(fit.omega_n.size, bool)
    split[list(near_of)] = True
    regions += [near_of[q] for q in np.flatnonzero(split)]
    if not regions:
        return fit, misfit, coef, None
    pairs_wn = np.concatenate([fit.omega_n[split] * (1 - fit.damping_ratio[split]),
                               fit.omega_n[split] * (1 + fit.damping_ratio[split])])
    pairs_zeta = np.tile(fit.damping_ratio[split], 2)

    def refit(take_new, take_split):
        keep = ~(split & take_split)
        wn0 = np.concatenate([fit.omega_n[keep], wn_new[take_new], pairs_wn[np.tile(take_split[split], 2)]])
        zeta0 = np.concatenate([fit.damping_ratio[keep], zeta_new[take_new], pairs_zeta[np.tile(take_split[split], 2)]])
        trial, removed = _refine(omega, H, power, wn0, zeta0, noise, budget=budget)
        return (trial, removed, *_lsfd(omega, H, power, trial.omega_n, trial.damping_ratio))

    trial, removed, coef_t, misfit_t = refit(np.ones(wn_new.size, bool), split)
    explained = np.array([not _inadequate(H, misfit_t, noise, near) for near in regions])
    if not explained.any():
        return fit, misfit, coef, None
    if not explained.all():
        split_ok = np.zeros(fit.omega_n.size, bool)
        split_ok[np.flatnonzero(split)] = explained[wn_new.size:]
        trial, removed, coef_t, misfit_t = refit(explained[:wn_new.size], split_ok)
    return trial, misfit_t, coef_t, removed


#: the highest model order the sweep takes by default (``max_order`` lifts it): pLSCF's work grows with the
#: order squared times the lines
MAX_DEFAULT_ORDER = 120


def _default_max_order(frf: FRF, m: int) -> tuple[int, int]:
    """Enough poles for about three times the visible peaks, plus margin, within 10–:data:`MAX_DEFAULT_ORDER`
    orders; and the order the peaks call for (above the cap when it binds)."""
    try:
        peaks = len(find_modes(frf, min_prominence_db=3.0))
    except IdentificationError:
        peaks = 1
    wanted = int(np.ceil((6 * peaks + 20) / m))
    return int(np.clip(wanted, 10, MAX_DEFAULT_ORDER)), wanted


def _warn_caps(src: str, budget: EvaluationBudget, wanted_order: int | None, max_order: int, sweep=None,
               limited=None) -> None:
    """One warning per work cap that bound: the joint refinement's evaluations, the sweep's model order, the
    sweep's work (:func:`modal.global_.sweep.plan_sweep`), the modes the refinement takes (``limited``: the
    modes it took, those proposed, the lines)."""
    from ..errors import QualityWarning, warn_caller

    advice = "fit a cropped band (bands_hz, --band) or fit bands (method nls)"
    if sweep is not None and sweep.capped:
        warn_caller(f"{src}: global: the stabilisation sweep took {sweep.reason}, within its work budget: modes "
                    f"may be missing, and its modes are flagged work_capped; {advice}", QualityWarning)
    if limited is not None:
        warn_caller(f"{src}: global: the refinement took the {limited[0]} most stable of the {limited[1]} modes the "
                    f"sweep proposed, within its work budget on {limited[2]} lines: modes may be missing, and its "
                    f"modes are flagged work_capped; {advice}", QualityWarning)

    if budget.capped:
        warn_caller(f"{src}: global: the joint refinement stopped at its budget of {budget.limit} model evaluations "
                    "before converging; its modes are flagged work_capped; identify(..., max_evaluations=N) or "
                    "--max-evaluations N with N above it lets it go on", QualityWarning)
    if wanted_order is not None:
        warn_caller(f"{src}: global: the stabilisation sweep stopped at model order {max_order} (its default "
                    f"ceiling) where the peaks call for {wanted_order}: modes may be missing; identify(..., "
                    f"max_order={wanted_order}) or --max-order {wanted_order} sweeps further, or fit bands "
                    "(method nls)", QualityWarning)


def identify_global(frf: FRF, *, modes_hz=None, order: int | None = None, max_order: int | None = None,
                    band_hz=None, noise_std=None, driving_point=None,
                    max_evaluations: int | None = None) -> IdentificationResult:
    """Identify every mode of a (multi-reference) FRF with one global model.

    Parameters
    ----------
    frf : FRF
        Channels with ``response_points`` and ``reference_points`` for a
        poly-reference fit (a full outputs × references grid), or any channels
        (treated as one reference).
    modes_hz : sequence of float, optional
        Hints: the modes to keep, Hz (the pole nearest each hint in the highest order).
    order : int, optional
        Use this single model order's physical poles instead of the stabilisation selection.
    max_order : int, optional
        Highest order of the sweep (default from the number of peaks).
    band_hz : (float, float), optional
        Band to fit, Hz (default: all lines above 0 Hz).
    noise_std : float or array_like over channels, optional
        Known noise σ per channel (default: the FRF's own ``noise_std`` or the estimate).
    driving_point : bool, array_like of bool or channel indices, optional
        Declares which channels are driving points (:func:`modal.assemble.driving_points`).
    max_evaluations : int, optional
        Model evaluations the joint refinement may take, all its fits together (default
        :func:`modal.work_budget.default_max_evaluations`, scaled to the size of one). Where they run out
        the refinement stops where it stands: its modes are flagged ``work_capped``, with a warning.
    """
    max_evaluations = checked_max_evaluations(max_evaluations, IdentificationError)
    src = frf.source
    power = KIND_POWER[frf.kind]
    low, high = (0.0, np.inf) if band_hz is None else (float(band_hz[0]), float(band_hz[1]))
    keep = (frf.frequency_hz > max(low, 0.0)) & (frf.frequency_hz <= high)
    if keep.sum() < 10:
        raise IdentificationError(f"{src}: the band holds {int(keep.sum())} lines above 0 Hz; the global method "
                                  "needs at least 10")
    # an exponentially windowed velocity or acceleration: its window's factor out of the data (see .window)
    work, unwindowed = without_window_factor(frf.cropped(float(frf.frequency_hz[keep][0]),
                                                         float(frf.frequency_hz[keep][-1])))
    omega = work.omega_rad_s
    H = work.channels
    n_ch = work.n_channels
    index, references, transposed = channel_grid(work)
    n_out, m = index.shape
    weight = 1.0 / np.sqrt(np.mean(np.abs(H) ** 2, axis=1))  # each channel to RMS 1: the small ones count too
    weight[~np.isfinite(weight)] = 0.0
    matrix = (H * weight[:, None])[index]  # (n_out, m, n_f)
    wanted_order = None  # the order the peaks call for, where the default's ceiling cut it
    if order is not None:
        orders = [int(order) - 1, int(order)] if order > 1 else [int(order)]
    else:
        p_max = max_order
        if not p_max:
            p_max, wanted = _default_max_order(work, m)
            wanted_order = wanted if wanted > p_max else None
        orders = sweep_orders(p_max)
    # on a huge file (or at a high max_order) the sweep takes fewer lines, or lower orders, within its budgets
    asked_order = orders[-1]
    sweep = plan_sweep(orders, omega.size, n_out, m)
    orders = sweep.orders
    swept = omega.size  # the lines the sweep took
    lines = slice(None)  # the lines the sweeps take
    if sweep.capped:
        lines = sweep_lines(np.sum(np.abs(matrix) ** 2, axis=(0, 1)), sweep.n_lines)
        swept = lines.size
    packs = plscf_poles(omega[lines], matrix[..., lines], orders, beyond=BEYOND_BAND)
    diagram = stabilisation(packs)
    if order is not None and modes_hz is None:
        last = packs[-1]
        selected = [SelectedPole(float(w), float(z), l, 1, 1) for w, z, l in
                    zip(last.omega_n, last.damping_ratio, last.participation)]
    else:
        selected = select_poles(packs, diagram, modes_hz=modes_hz)
        if modes_hz is None:
            # above the top line the sweep's basis has no data (up to BEYOND_BAND): the poles there are set by
            # little (the real beam's single files: a chain at 1016 Hz in 4 of 11 orders, kept at 1037 Hz
            # with ζ = 0); the modes above the band come from the low-order sweep (:func:`_poles_above_band`)
            selected = [p for p in selected if p.omega_n <= omega[-1]]
    proposed = len(selected)  # the refinement takes the most stable modes its work budget allows
    selected = most_stable(selected, refinement_mode_limit(omega.size, n_ch))
    limited = len(selected) < proposed
    if not selected:
        cut = (f"; the sweep took {sweep.reason} within its work budget: fit a cropped band or fit bands (method "
               "nls)") if sweep.capped else ""
        raise IdentificationError(f"{src}: no stable pole in the stabilisation diagram (orders {orders[0]}–"
                                  f"{orders[-1]}); give modes_hz hints or a higher max_order{cut}")

    line_noise = work.noise_std  # the band's lines (without the window's factor, as the data)
    if noise_std is not None:
        noise = np.broadcast_to(np.asarray(noise_std, float), (n_ch,)).copy()
    elif line_noise is not None:
        noise = np.sqrt(np.mean(np.atleast_2d(line_noise) ** 2, axis=1))
    else:
        noise = estimate_noise_std(work)
    selected, dropped = _significant(omega, H, power, selected, noise)
    if not selected:
        raise IdentificationError(f"{src}: no pole of the stabilisation diagram explains more than the noise; "
                                  "give modes_hz hints or check the data")
    # modes just outside the lines, weakly seen by pLSCF, enter last, with the modes in the lines in place:
    # their damping is barely determined and, started together with poles still moving, they wandered
    # widely (into the lines as wide poles); the refinement and its significance test decide
    inside = [p for p in selected if omega[0] <= p.omega_n <= omega[-1]] or selected
    outside = [p for p in selected if not any(p is q for q in inside)]
    if modes_hz is None and order is None:
        below = outside_band_poles(packs, diagram, work.frequency_hz[0], work.frequency_hz[-1], selected)
        outside += [p for p in below if p.omega_n < omega[0]]
        outside += _poles_above_band(omega[lines], matrix[..., lines], orders, work.frequency_hz[0],
                                     work.frequency_hz[-1], selected + outside)
    wn0 = np.array([p.omega_n for p in inside])
    zeta0 = np.array([p.damping_ratio for p in inside])
    budget = EvaluationBudget(max_evaluations or default_max_evaluations(omega.size, len(inside) + len(outside), n_ch))
    fit, removed = _refine(omega, H, power, wn0, zeta0, noise, budget=budget)
    dropped += removed
    coef, misfit = _lsfd(omega, H, power, fit.omega_n, fit.damping_ratio)
    # with hints or one order the user chose the modes: none is added
    for _ in range(MISSING_ROUNDS if modes_hz is None and order is None else 0):
        if budget.spent:
            break
        fit, misfit, coef, removed = _add_missing(omega, H, power, fit, misfit, coef, noise, budget)
        if removed is None:
            break
        dropped += removed
    if outside and not budget.spent:
        fit, removed = _refine(omega, H, power, np.concatenate([fit.omega_n, [p.omega_n for p in outside]]),
                               np.concatenate([fit.damping_ratio, [p.damping_ratio for p in outside]]), noise,
                               budget=budget)
        dropped += removed
    fit, removed = _refine(omega, H, power, fit.omega_n, fit.damping_ratio, noise, TIGHT_STEP_TOL, budget,
                           _line_weighting(work, fit.omega_n, fit.damping_ratio))
    dropped += removed
    coef, misfit = _lsfd(omega, H, power, fit.omega_n, fit.damping_ratio)
    residuals = coef[-2:].T  # (n_ch, 2): upper, lower: the residual terms in physical form

    spacing = float(np.median(np.diff(work.frequency_hz)))
    order_of = np.argsort(fit.omega_n)
    # shapes and MPC per column of the pLSCF matrix: per reference, or, transposed by reciprocity
    # (roving hammer), per response point over the hammer points
    ref_of_channel = np.zeros(n_ch, int)
    for r in range(m):
        ref_of_channel[index[:, r]] = r
    single = frf.response.ndim == 1
    pool = inside + outside
    pool_wn = np.array([p.omega_n for p in pool])
    estimates = []
    for r in order_of:
        wn, zeta = float(fit.omega_n[r]), float(fit.damping_ratio[r])
        # the stabilisation's evidence for the mode: the chain of the pole it was started from; a mode found
        # in the residual has none there (its evidence is the significance test and the misfit it removes)
        pole = pool[int(np.argmin(np.abs(pool_wn - wn)))] if pool else None
        if pole is not None and abs(pole.omega_n / wn - 1) > 0.01:
            pole = SelectedPole(wn, zeta, np.full(m, np.nan), 0, 0, found_in_residual=True)
        cov = fit.mode_cov[r]
        const = fit.modal_constant[r]
        flags: set[str] = set()
        if budget.capped:  # a fit of the refinement stopped at the budget: the poles are where it stood
            flags.add("work_capped")
        elif not fit.converged:
            flags.add("did_not_converge")
        if sweep.capped or limited:  # the sweep took fewer lines or orders, or the refinement
            flags.add("work_capped")  # fewer modes than it proposed: some may be missing
        chi2, relative = _local_misfit(omega, H, misfit, noise, wn, zeta)
        # Clean real data (data/real beam: 1-2 % misfit at 170-33 000 times a noise the lines hardly show)
        # is explained as well as a linear model can: the relative misfit keeps it unflagged
        if model_inadequate(chi2, relative):
            flags.add("model_inadequate")
        s_wn = float(np.sqrt(max(cov[0, 0, 0], 0))) if np.isfinite(cov[0, 0, 0]) else np.nan
        s_z = float(np.sqrt(max(cov[0, 1, 1], 0))) if np.isfinite(cov[0, 1, 1]) else np.nan
        weak = pole.n_stable_orders < WEAK_FRACTION * pole.n_orders or (pole.hinted and pole.n_stable_orders < 3)
        if weak and not pole.found_in_residual:
            flags.add("weak_evidence")
        fn = wn / TWO_PI
        # a half-power bandwidth under the line spacing (or about it): the fit still places the pole from the
        # peak's shape, its errors from the Fisher information say how well, but the lines do not resolve it
        if fn < work.frequency_hz[0] + 2 * spacing or fn > work.frequency_hz[-1]:
            flags.add("outside_band")
        elif np.count_nonzero(np.abs(work.frequency_hz - fn) <= zeta * fn) < 3:
            flags.add("resolution_limited")
        later = fit.omega_n[fit.omega_n > wn]
        if later.size and wn < RIGID_BODY_RATIO * later.min():
            flags.add("rigid_body")
        shapes = np.zeros(n_ch, complex)
        values = []
        for q in range(int(ref_of_channel.max()) + 1):
            members = ref_of_channel == q
            group = const[members]
            top = group[np.argmax(np.abs(group))] if group.size else 0
            shapes[members] = group / top if top != 0 else group
            if group.size > 1:
                values.append(mpc(group))
        mode_mpc = float(np.mean(values)) if values else float("nan")
        if np.isfinite(mode_mpc) and mode_mpc < MPC_LIMIT:
            flags.add("complex_shape")
        estimates.append(ModeEstimate(
            wn, zeta, const, cov, s_wn, s_z, (float(work.frequency_hz[0]), float(work.frequency_hz[-1])),
            int(work.n_freq), 2 * zeta * fn / spacing if spacing > 0 else np.nan, flags, chi2=chi2,
            quality=pole.n_stable_orders / max(pole.n_orders, 1), mode_shape=shapes[0] if single else shapes,
            participation=np.asarray(pole.participation), mpc=mode_mpc))
    driving, known = driving_points(work, driving_point)
    # complexity is judged by the shapes' MPC (complex_shape), not by a driving point's phase; an exponential
    # window's damping comes out of every pole as for the band-wise methods (the shift by 1/τ is exact)
    modes = assemble_modes(estimates, method="global", source=src, single=single, driving=driving,
                           driving_known=known, phase_check=False, window_decay_s=frf.exponential_decay_s,
                           window_power=0 if unwindowed else KIND_POWER[frf.kind])
    settings = {"orders": [int(orders[0]), int(orders[-1])], "references": [str(r) for r in references],
                "transposed_by_reciprocity": bool(transposed),
                "band_hz": [float(work.frequency_hz[0]), float(work.frequency_hz[-1])],
                "modes_hz": None if modes_hz is None else [float(f) for f in np.atleast_1d(modes_hz)],
                "order": None if order is None else int(order),
                "dropped_insignificant_hz": dropped,
                "max_evaluations": int(budget.limit), "evaluations": int(budget.used),
                "order_wanted": wanted_order, "sweep_lines": int(swept), "modes_proposed": int(proposed)}
    _warn_caps(src, budget, wanted_order, asked_order, sweep,
               (refinement_mode_limit(omega.size, n_ch), proposed, omega.size) if limited else None)
    return IdentificationResult(tuple(modes), "global", frf.kind, n_ch, noise_std=noise,
                                residuals=residuals, stabilisation=diagram, settings=settings)
