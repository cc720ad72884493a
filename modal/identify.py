"""``identify``: from an FRF to every mode's ωn, ζ, modal constant and k, c, m."""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from .checks import (find_missing_mode, fit_residual, fit_residual_noise_std, residual_noise_std, residual_structure,
                     restart_pole)
from .circlefit import circle_fit_curve
from .assemble import ModeEstimate, assemble_modes, driving_points
from .errors import IdentificationError
from .flags import BIAS_LIMIT, GRID_FLAGS, REL_STD_LIMIT, lines_near_mode, model_inadequate
from .frf import FRF, KIND_POWER, line_spacing
from .halfpower import half_power_curve
from .model import mode_basis, solve_linear
from .nls import fit_modes, truncation_shift
from .rational import rational_pole
from .propagate import combine_poles, constant_covariance, magnitude_to_complex
from .peaks import ModeBand, _indicator_and_peak, bands_from_hz, channel_sample, estimate_noise_std, find_modes
from .results import IdentificationResult
from .units import TWO_PI

__all__ = ["identify", "METHODS"]

#: the band-wise methods (one band per mode) and all methods
BANDWISE_METHODS = ("nls", "circle", "halfpower")
METHODS = BANDWISE_METHODS + ("global",)
#: channels (strongest first) used for the NLS start values
START_CHANNELS = 8
#: relative precision of the refinement's poles (the stopping rule of :func:`modal.nls.fit_modes`)
REFINEMENT_PRECISION = 1e-13
#: half-power and circle fits: the pole comes from at most this many strongest channels;
#: the other channels' modal constants are solved linearly with that pole
POLE_CHANNELS = 32
#: a fit whose residual variance is more than this many times its line-to-line noise
#: (checks.residual_structure) has a smooth misfit: its truncation shift is measured
STRUCTURED_RATIO = 4.0


def _combine(values, stds, weights):
    """Robust combination over channels: weighted median, and its standard error.

    Channels whose estimate failed (NaN) are ignored. The weighted median keeps
    one poor channel (a node of the mode, a peak outside the band) from
    dragging the shared pole.
    """
    values, stds, weights = (np.asarray(a, float) for a in (values, stds, weights))
    ok = np.isfinite(values) & np.isfinite(weights) & (weights > 0)
    if not ok.any():
        ok = np.isfinite(values)
        weights = np.ones_like(values)
    if not ok.any():
        return np.nan, np.nan
    v, w, s = values[ok], weights[ok], stds[ok]
    order = np.argsort(v)
    v, w = v[order], w[order]
    # midpoint weighted median: each value sits at the middle of its weight; one channel
    # gives its own value, two give a weighted mean, many the robust median
    position = (np.cumsum(w) - w / 2) / np.sum(w)
    median = float(np.interp(0.5, position, v))
    good = np.isfinite(s)
    if not good.any():
        return median, np.nan
    # inverse-variance combination of the channel errors, times the median's 1.25 efficiency
    # loss from three channels on; scaled by the smallest error so that no square under- or overflows
    smallest = float(np.min(s[good]))
    if smallest <= 0:
        return median, 0.0
    efficiency = 1.2533 if v.size >= 3 else 1.0
    std = float(efficiency * smallest / np.sqrt(np.sum((smallest / s[good]) ** 2)))
    return median, std


def _linear_constants(omega, h, power, wn, zeta):
    """Modal constant per channel for a given pole, with a band offset; and its variance."""
    phi = mode_basis(omega, wn, zeta, power)[0]
    Phi = np.column_stack([phi, np.ones_like(phi)])
    coef = solve_linear(Phi, h.T)
    res = h.T - Phi @ coef
    dof = max(omega.size - 2, 1)
    noise_var = np.sum(np.abs(res) ** 2, axis=0) / dof
    gram_inv = np.linalg.inv(Phi.conj().T @ Phi)
    return coef[0], noise_var * np.real(gram_inv[0, 0]), float(np.linalg.norm(res) ** 2)


def _constants_all_poles(frf, bands, power, omega_n, damping_ratio):
    """Modal constants of every channel for known poles: one linear least-squares solve
    (all modes together, one complex offset per band region) over the lines of the bands."""
    omega, response, region = _band_data(frf, bands)
    ok = np.isfinite(omega_n) & np.isfinite(damping_ratio)
    phi = mode_basis(omega, np.asarray(omega_n)[ok], np.asarray(damping_ratio)[ok], power).T
    offsets = np.zeros((omega.size, region.max() + 1), dtype=complex)
    offsets[np.arange(omega.size), region] = 1.0
    coef = solve_linear(np.hstack([phi, offsets]), response.T)
    out = np.full((len(bands), frf.n_channels), np.nan, dtype=complex)
    out[ok] = coef[:ok.sum()]
    return out


def _band_mask(frf, band: ModeBand) -> np.ndarray:
    """The lines of a band (bool over the FRF's lines)."""
    return (frf.frequency_hz >= band.low_hz) & (frf.frequency_hz <= band.high_hz)


def _band_run(omega: np.ndarray, band: ModeBand) -> slice:
    """A band's lines on the lines ``omega`` (rad/s) of the bands' :func:`_band_data`, where they are a run
    (every line between its edges is in it; the edges lie halfway between lines,
    :func:`modal.peaks._edges_between_lines`, so no rounding of 2π f moves a line across one)."""
    lines = np.flatnonzero((omega >= TWO_PI * band.low_hz) & (omega <= TWO_PI * band.high_hz))
    return slice(lines[0], lines[-1] + 1) if lines.size else slice(0, 0)


def _mode_arrays(frf, band: ModeBand):
    keep = _band_mask(frf, band)
    return frf.omega_rad_s[keep], frf.channels[:, keep]


def _sdof_estimates(frf, band, power, noise, method, channels=None, errors=True):
    """Per-channel half-power or circle estimates, combined into one pole.

    ``channels`` restricts the pole estimate to a subset (the modal constants
    of the others stay NaN); by default every channel is used.

    Returns (ωn, ζ, std ωn, std ζ, constants (n_ch,), flags, quality, errors) where
    ``errors`` holds the pole's covariance ``"cov"`` (2, 2), how each channel's lines
    enter it ``"rows"`` (n_ch, 2, 2, n_band: ∂θ/∂(Re h, Im h), the channel's gain in the
    combination applied) and, for the circle, each channel's own covariance of
    (ωn, ζ, Re A, Im A) ``"own"`` (n_ch, 4, 4) with the combined pole's cross terms.
    """
    omega, h = _mode_arrays(frf, band)
    n_ch, n = h.shape
    use = range(n_ch) if channels is None else channels
    theta = np.full((n_ch, 2), np.nan)
    cov = np.full((n_ch, 2, 2), np.nan)
    rows = np.zeros((n_ch, 2, 2, n))
    own = np.full((n_ch, 4, 4), np.nan)
    systematic = np.zeros((n_ch, 2, 2))
    const = np.full(n_ch, np.nan, dtype=complex)
    flags: set[str] = set()
    quality = []
    for ch in use:
        if method == "halfpower":
            est = half_power_curve(omega, h[ch], power, noise[ch], errors)
            quality.append(est.n_above)  # constants: solved afterwards with all the poles
            lin = np.full((2, 2), np.nan)
            if est.jacobian is not None:
                jac = magnitude_to_complex(est.jacobian, h[ch])  # (2, 2, n)
                lin = (noise[ch] ** 2 / 2) * np.einsum("akn,bkn->ab", jac, jac)
                rows[ch] = jac
        else:
            positive = omega > 0 if power == 2 else np.ones(omega.size, bool)
            omega_c, h_c = omega[positive], h[ch][positive]
            factor = (1j * omega_c) ** (1 - power)  # to mobility, line by line
            try:
                est = circle_fit_curve(omega_c, h_c * factor, noise[ch] * np.abs(factor), errors)
            except ValueError:
                flags.add("too_few_points")
                continue
            const[ch] = est.modal_constant
            quality.append(est.damping_pair_spread)
            lin = np.full((2, 2), np.nan)
            if est.jacobian is not None:
                # ∂/∂(Re Y, Im Y) with Y = f h: ∂/∂Re h = a f_r + b f_i, ∂/∂Im h = −a f_i + b f_r
                a_, b_ = est.jacobian[:, 0], est.jacobian[:, 1]
                jac = np.stack([a_ * factor.real + b_ * factor.imag, -a_ * factor.imag + b_ * factor.real], axis=1)
                rows[ch][:, :, positive] = jac[:2]
                own[ch] = (noise[ch] ** 2 / 2) * np.einsum("akn,bkn->ab", jac, jac)
                lin = own[ch][:2, :2]
        theta[ch] = est.omega_n, est.damping_ratio
        # the estimate's own error beyond its noise linearisation (interpolation, quantisation
        # of an unresolved peak): systematic, it does not scale with the noise
        extra = np.maximum(np.array([est.std_omega_n, est.std_damping_ratio]) ** 2 - np.diag(lin), 0.0)
        cov[ch] = lin
        systematic[ch] = np.diag(np.nan_to_num(extra))
        flags.update(est.flags)
    q = float(np.nanmedian(quality)) if len(quality) and np.isfinite(quality).any() else np.nan
    raw = {"theta": theta, "cov": cov, "systematic": systematic, "rows": rows, "own": own, "weights": _channel_weights(frf, band, noise),
           "circle": method == "circle"}
    return _combine_channels(omega, h, raw, const, flags, q)


def _combine_channels(omega, h, raw, const, flags, q, scale=None):
    """The pole of one band from the channels' estimates (``raw`` of :func:`_sdof_estimates`).

    ``scale`` (n_ch,): factors on each channel's noise variance (the noise as the fit's
    residual shows it, :func:`_rescaled`); every covariance is linear in it.
    """
    theta, cov, rows, own = raw["theta"], raw["cov"], raw["rows"], raw["own"]
    if scale is not None:
        cov = cov * scale[:, None, None]
        own = own * scale[:, None, None]
    cov = cov + raw["systematic"]
    own = own.copy()
    own[:, :2, :2] = cov
    (wn_c, z_c), cov_c, gain = combine_poles(theta, cov, raw["weights"])
    rows = np.einsum("cij,cjkn->cikn", gain, rows)
    if raw["circle"]:  # cov(θ, A_c) of a channel's own constant: through its gain
        own = own.copy()
        own[:, :2, 2:] = np.einsum("cij,cjb->cib", gain, np.nan_to_num(own[:, :2, 2:]))
        own[:, 2:, :2] = own[:, :2, 2:].transpose(0, 2, 1)
        own[:, :2, :2] = cov_c
    flags = set(flags)
    if not np.isfinite(wn_c):
        # nothing usable: report the peak line, flagged
        wn_c = float(omega[np.argmax(np.abs(h).max(axis=0))])
        z_c = float(np.min(np.diff(omega)) / (2 * wn_c)) if omega.size > 1 else np.nan
        flags.add("too_few_points")
    if flags & GRID_FLAGS and omega.size > 1:
        # grid quantisation is the same on every channel: it does not average down
        spacing = float(np.min(np.diff(omega)))
        floor = np.array([spacing / np.sqrt(12), spacing / (2 * wn_c)])
        diag = np.diag(cov_c)
        raised = np.where(np.isfinite(diag), np.maximum(diag, floor**2), floor**2)
        cov_c = np.where(np.isfinite(cov_c), cov_c, 0.0)
        cov_c[[0, 1], [0, 1]] = raised
    s_wn_c, s_z_c = (float(np.sqrt(v)) if np.isfinite(v) else np.nan for v in np.diag(cov_c))
    return wn_c, z_c, s_wn_c, s_z_c, const, flags, q, {"cov": cov_c, "rows": rows, "own": own, "raw": raw,
                                                       "args": (omega, h, const, flags, q)}


def _rescaled(frf, bands, power, poles, noise, refined_var=None):
    """The poles again with each channel's errors for the noise the fit's residual shows.

    The raw-data noise estimate takes in the resonances' curvature (8 % high at 12 lines
    per half-power band) and is a median over the lines (±10 %). The residual variance
    of the least-squares refinement of the same modes (``refined_var``, rss/dof, as the
    refinement's own errors use it: ±5 % at 100 lines) has neither; on channels the
    refinement did not use, the residual of the constants solved with these poles.
    """
    omega, response, region = _band_data(frf, bands)
    wn = np.array([p[0] for p in poles], float)
    zeta = np.array([p[1] for p in poles], float)
    ok = np.isfinite(wn) & np.isfinite(zeta) & (wn > 0)
    phi = mode_basis(omega, wn[ok], zeta[ok], power).T
    offsets = np.zeros((omega.size, region.max() + 1), dtype=complex)
    offsets[np.arange(omega.size), region] = 1.0
    design = np.hstack([phi, offsets])
    dof = omega.size - design.shape[1] - ok.sum()  # complex unknowns, and the two real pole parameters
    if dof < 5:
        return poles
    coef = solve_linear(design, response.T)
    variance = np.sum(np.abs(response.T - design @ coef) ** 2, axis=0) / dof
    if refined_var is not None:
        variance = np.where(np.isfinite(refined_var), refined_var, variance)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = variance / np.asarray(noise, float) ** 2
    scale = np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)
    out = []
    for p in poles:
        omega_b, h_b, const, flags, q = p[7]["args"]
        out.append(_combine_channels(omega_b, h_b, p[7]["raw"], const, flags, q, scale))
    return out


def _channel_weights(frf, band, noise):
    """Signal-to-noise power of each channel at the mode's peak line."""
    i = int(np.argmin(np.abs(frf.frequency_hz - band.peak_hz)))
    peak = np.abs(frf.channels[:, i])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(noise > 0, (peak / noise) ** 2, peak**2)


def _strongest_channels(frf, band, noise, count: int) -> np.ndarray:
    """The ``count`` channels of highest :func:`_channel_weights` in a band, strongest first."""
    return np.argsort(_channel_weights(frf, band, noise))[::-1][:count]


def _regions(bands: list[ModeBand], freq):
    """Lines in any band, and a region index per line (overlapping bands merge)."""
    keep = np.zeros(freq.size, bool)
    for b in bands:
        keep |= (freq >= b.low_hz) & (freq <= b.high_hz)
    idx = np.flatnonzero(keep)
    region = np.zeros(idx.size, int)
    breaks = np.flatnonzero(np.diff(idx) > 1)
    for br in breaks:
        region[br + 1:] += 1
    return keep, region


def _band_data(frf, bands, channels=None):
    """Lines of the bands (rad/s), the FRF there (all or some channels) and each line's region."""
    keep, region = _regions(bands, frf.frequency_hz)
    rows = slice(None) if channels is None else channels
    lines = np.flatnonzero(keep)
    starts = np.concatenate([[0], np.flatnonzero(np.diff(lines) > 1) + 1, [lines.size]])
    response = frf.channels[rows]
    # each band's run of lines copied as a block (half the time of a masked copy of every channel)
    runs = [response[:, lines[a]:lines[b - 1] + 1] for a, b in zip(starts[:-1], starts[1:]) if b > a]
    return frf.omega_rad_s[keep], (np.concatenate(runs, axis=1) if runs else response[:, keep]), region


def _band_peaks(bands, data) -> np.ndarray:
    """max |H| of each channel on each band's lines, (n_bands, n_channels), from the bands' :func:`_band_data`
    (|H| of every channel once: the fit scales each channel by its largest, the misfit check ranks by them)."""
    omega, response, _ = data
    magnitude = np.abs(response)
    out = np.zeros((len(bands), response.shape[0]))
    for b, band in enumerate(bands):
        run = _band_run(omega, band)
        if run.stop > run.start:
            out[b] = magnitude[:, run].max(axis=1)
    return out


def _start_pole(frf, band, power, noise):
    """Best start of (ωn, ζ) among half-power and circle, by residual with A solved linearly."""
    omega, h = _mode_arrays(frf, band)
    strongest = _strongest_channels(frf, band, noise, START_CHANNELS)
    candidates = []
    for method in ("halfpower", "circle"):
        with np.errstate(all="ignore"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                wn, zeta, *_ = _sdof_estimates(frf, band, power, noise, method, channels=strongest, errors=False)
        if np.isfinite(wn) and np.isfinite(zeta) and wn > 0 and zeta > 0:
            candidates.append((wn, zeta))
    if not candidates:
        i = np.argmax(np.abs(h).max(axis=0))
        candidates.append((omega[i], max(np.min(np.diff(omega)) / omega[i], 1e-6)))
    best = min(candidates, key=lambda c: _linear_constants(omega, h[strongest], power, *c)[2])
    return best


def _principal_start(frf, band, power, noise):
    """:func:`_start_pole` of a many-channel band on one curve: the principal combination of its
    ``START_CHANNELS`` strongest channels.

    Any linear combination of the channels is an FRF with the same poles. The channels,
    each divided by its noise σ, are combined with the first left singular vector of
    their band (the combination of most energy, unit norm: its noise σ is 1), and the
    start is searched on that one curve (:func:`_start_pole` of a one-channel FRF): two
    single-channel estimates per band instead of two per channel.
    """
    keep = _band_mask(frf, band)
    strongest = _strongest_channels(frf, band, noise, START_CHANNELS)
    sigma = np.asarray(noise, float)[strongest]
    usable = np.isfinite(sigma) & (sigma > 0)
    if not usable.any():
        sigma = np.ones_like(sigma)
    else:  # a channel without a noise level counts as the quietest one
        sigma = np.where(usable, sigma, np.min(sigma[usable]))
    h = frf.channels[strongest][:, keep] / sigma[:, None]
    try:
        u, _, _ = np.linalg.svd(h, full_matrices=False)
    except np.linalg.LinAlgError:
        return _start_pole(frf, band, power, noise)
    curve = u[:, 0].conj() @ h
    if not np.all(np.isfinite(curve)):
        return _start_pole(frf, band, power, noise)
    one = FRF(frf.frequency_hz[keep], curve, kind=frf.kind, source=frf.source)
    wn, zeta = _start_pole(one, band, power, np.ones(1))
    return wn, zeta


def _quick_start(frf, band, power, noise):
    """(ωn, ζ) of a band's one-mode rational fit (:func:`modal.rational.rational_pole`) on its
    strongest channels, or None when it gives no pole inside the band."""
    keep = _band_mask(frf, band)
    omega, h = frf.omega_rad_s[keep], frf.channels
    if h.shape[0] > START_CHANNELS:  # the strongest channels first: no copy of every channel's band
        strongest = _strongest_channels(frf, band, noise, START_CHANNELS)
        h, noise = h[strongest], np.asarray(noise)[strongest]
    h = h[:, keep]
    with np.errstate(all="ignore"):
        pole = rational_pole(omega, h, noise)
    if pole is None or not (TWO_PI * band.low_hz <= pole[0] <= TWO_PI * band.high_hz and 0 < pole[1] < 1):
        return None
    return pole


def _doubtful(fit, bands) -> bool:
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


def _nls_fit(frf, bands, power, noise, data=None, band_peak=None):
    """The band-wise NLS fit of every band's mode, from the cheapest start that serves.

    Each band starts from its one-mode rational fit (a few linear solves); a band where
    that gives no pole, or a fit that looks doubtful (:func:`_doubtful`), takes the
    half-power and circle starts of :func:`_start_pole` as well (of :func:`_principal_start`,
    one curve per band, for many channels), and the fit with the lower residual is kept.
    ``data``: the :func:`_band_data` of the bands, when the caller has it; ``band_peak``: its
    :func:`_band_peaks`.
    """
    quick = [_quick_start(frf, band, power, noise) for band in bands]
    if all(q is not None for q in quick):
        fit = _fit_bands(frf, bands, power, [q[0] for q in quick], [q[1] for q in quick], data=data,
                         band_peak=band_peak)
        if not _doubtful(fit, bands):
            return fit
    else:
        fit = None
    start = _principal_start if frf.n_channels > 1 else _start_pole
    starts = [start(frf, band, power, noise) for band in bands]
    careful = _fit_bands(frf, bands, power, [s[0] for s in starts], [s[1] for s in starts], data=data,
                         band_peak=band_peak)
    if fit is None or _fit_cost(careful) <= _fit_cost(fit):
        return careful
    return fit


def _fit_cost(fit) -> float:
    """Residual of a band-wise fit summed over channels, each scaled by its largest value."""
    if not np.all(np.isfinite(fit.noise_var)):
        return np.inf
    scale = np.where(fit.channel_scale > 0, fit.channel_scale, 1.0)  # max |H| of each channel on the lines
    return float(np.sum(fit.noise_var / scale**2))


def _bandwise_covariance(frf, bands, power, poles, noise, own_constants=None):
    """Covariance (n_modes, n_ch, 4, 4) of (ωn, ζ, Re A, Im A) of the half-power or circle result.

    The poles' covariances come with each estimate (:func:`_sdof_estimates`); the
    constants solved linearly with all the poles get theirs from
    :func:`modal.propagate.constant_covariance`; a circle's own constants
    (``own_constants``, (n_modes, n_ch) bool) keep the circle's covariance.
    """
    omega, response, region = _band_data(frf, bands)
    keep, _ = _regions(bands, frf.frequency_hz)
    keep_idx = np.flatnonzero(keep)
    n_modes, n_ch = len(bands), frf.n_channels
    pole_rows = np.zeros((n_modes, n_ch, 2, 2, omega.size))
    for r, band in enumerate(bands):
        lines = np.flatnonzero(_band_mask(frf, band))
        pole_rows[r][..., np.searchsorted(keep_idx, lines)] = poles[r][7]["rows"]
    pole_cov = np.array([p[7]["cov"] for p in poles])
    wn = np.array([p[0] for p in poles], float)
    zeta = np.array([p[1] for p in poles], float)
    with np.errstate(all="ignore"):
        cov = constant_covariance(omega, region, power, wn, zeta, response, np.asarray(noise, float), pole_cov,
                                  pole_rows)
    if own_constants is not None:
        for r in range(n_modes):
            own = poles[r][7]["own"]
            cov[r][own_constants[r]] = own[own_constants[r]]
    return cov


def _without_neighbours(frf, bands, power, noise, poles):
    """Half-power poles again, each on the data less the other identified modes.

    The magnitude of a mode's band carries its neighbours' tails (an offset and a
    slope across the band), which bend the −3 dB crossings: at 1 % noise a neighbour
    at 2.5× the frequency biased ωn by −0.4 of its error (SD of z 1.25, issue 21). The
    other modes, with the first pass's poles and their constants solved with all the
    poles, are subtracted on every line and each mode is estimated again.
    """
    wn = np.array([p[0] for p in poles], float)
    zeta = np.array([p[1] for p in poles], float)
    if not (np.all(np.isfinite(wn)) and np.all(np.isfinite(zeta)) and np.all(wn > 0) and np.all(zeta > 0)):
        return poles
    consts = _constants_all_poles(frf, bands, power, wn, zeta)  # (n_modes, n_ch)
    if not np.all(np.isfinite(consts)):
        return poles
    phi = mode_basis(frf.omega_rad_s, wn, zeta, power)  # (n_modes, n_freq)
    each = consts[:, :, None] * phi[:, None, :]  # (n_modes, n_ch, n_freq)
    total = each.sum(axis=0)
    out = []
    for r, band in enumerate(bands):
        isolated = frf.channels - (total - each[r])
        frf_r = dataclasses.replace(frf, response=isolated[0] if frf.response.ndim == 1 else isolated)
        strongest = None
        if frf.n_channels > POLE_CHANNELS:
            strongest = _strongest_channels(frf, band, noise, POLE_CHANNELS)
        out.append(_sdof_estimates(frf_r, band, power, noise, "halfpower", strongest))
    return out


def _refinement_check(frf, bands, power, poles, consts, noise, estimated_noise, known_noise=False, residual=None):
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
    """
    n_modes = len(bands)

    def no_reference(chi2):
        return (0.0, 0.0, np.zeros(frf.n_channels, complex), chi2, 0.0, 0.0)

    # the refinement starts from the method's poles; a pole the method could not give (ζ ≤ 0
    # or non-finite: half-power under heavy noise) starts from its band instead, so that it
    # does not take the check away from the other modes (stress finding 25)
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
    keep, _ = _regions(bands, frf.frequency_hz)
    strongest = np.argsort(np.max(np.abs(frf.channels[:, keep]) / np.where(noise > 0, noise, 1.0)[:, None],
                                  axis=1))[::-1][:POLE_CHANNELS]
    fit = _fit_bands(frf, bands, power, wn0, z0, strongest)
    if residual is not None:
        residual["noise_var"] = np.full(frf.n_channels, np.nan)
        residual["noise_var"][strongest] = fit.noise_var
    # the noise as the fit's residual shows it (the raw estimate takes in curvature on coarse axes)
    chi2 = _chi2(fit.noise_var, _fit_noise(frf, bands, power, fit.omega_n, fit.damping_ratio,
                                           estimated_noise, strongest, known_noise, fit=fit))
    # the refinement may return the modes in another order (two close poles crossing)
    order = np.argsort(fit.omega_n)
    omega_n, damping_ratio = fit.omega_n[order], fit.damping_ratio[order]
    std_ref = np.sqrt(np.abs(fit.mode_cov[order][:, 0, [0, 1], [0, 1]]))  # (n_modes, 2)
    shift = _truncation(frf, bands, power, fit, strongest)
    if shift is not None:  # the refinement's own truncation bias (finding 26) widens its errors
        std_ref = np.hypot(std_ref, shift[0][order])
    # an unconverged refinement still serves: a mode below the noise crawling along a flat
    # valley keeps LM from stopping while the other poles are long settled; the check only
    # adds flags and widens errors
    if not (np.all(np.isfinite(omega_n)) and np.all(damping_ratio > 0)):
        return [no_reference(chi2)] * n_modes, None
    missing = _missing_mode(frf, bands, power, omega_n, damping_ratio, estimated_noise)
    const_ref = _constants_all_poles(frf, bands, power, omega_n, damping_ratio)
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


def _chi2(residual_var, noise_std) -> float:
    """Median over channels of the residual variance over the estimated noise variance."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = residual_var / np.where(noise_std > 0, noise_std, np.nan) ** 2
    if not np.isfinite(ratio).any():
        return np.nan
    kept = ratio[~np.isnan(ratio)]  # the nan-median, without its cost on one channel
    return float(kept[0]) if kept.size == 1 else float(np.median(kept))


def _band_noise(frf, bands, line_noise):
    """Per channel, the RMS over the bands' lines of a known noise per line."""
    line_noise = np.atleast_2d(np.asarray(line_noise, float))
    lines, _ = _regions(bands, frf.frequency_hz)
    return np.sqrt(np.mean(line_noise[:, lines] ** 2, axis=1))


def _constant_distance(difference: np.ndarray, cov: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """Per channel, the distance of a complex difference of modal constants in standard errors: the
    Mahalanobis distance of (Re, Im) under their 2×2 covariance ``cov`` (n_ch, 2, 2), each part's error
    at least ``floor`` (the refinement's own precision: on exact data the errors are rounding, and so
    is the difference).

    k, c, m depend on |A|, and a half-power or circle constant's covariance is often long across
    A and short along it: the difference divided by the total error sqrt(var Re + var Im) let a
    bias 10 of its errors along |A| pass as 1.9 (docs/stress.md, finding 33). Where the covariance
    is singular, that total error is used.
    """
    a, b, c = cov[:, 0, 0] + floor**2, cov[:, 0, 1], cov[:, 1, 1] + floor**2
    x, y = difference.real, difference.imag
    with np.errstate(divide="ignore", invalid="ignore"):
        det = a * c - b * b
        squared = (c * x * x - 2 * b * x * y + a * y * y) / det
        total = np.abs(difference) / np.sqrt(a + c)
    return np.where((det > 0) & (squared >= 0), np.sqrt(np.maximum(squared, 0)), total)


def _local_misfit(frf, bands, power, omega_n, damping_ratio, data=None, band_peak=None) -> np.ndarray:
    """Per mode, the misfit near it relative to the data there (RMS over the strongest channels, at most
    ``POLE_CHANNELS``).

    In each band every fitted mode and a complex offset are solved linearly at the
    fitted poles; the residual is taken on the lines within ±3 half-power widths
    (at least ±3 lines) of the band's mode. ``data``: the :func:`_band_data` of the bands
    (each band is a run of its lines); ``band_peak``: its :func:`_band_peaks`.
    """
    out = np.full(len(bands), np.nan)
    if data is None:
        omega_all, response = frf.omega_rad_s, frf.channels
    else:
        omega_all, response, _ = data
    many = response.shape[0] > POLE_CHANNELS
    for b, (band, wn, zeta) in enumerate(zip(bands, omega_n, damping_ratio)):
        run = _band_run(omega_all, band)  # a view: no copy of every channel
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


def _fit_noise(frf, bands, power, omega_n, damping_ratio, estimated_noise, channels=None, known=False, residual=None,
               fit=None, data=None):
    """:func:`modal.checks.residual_noise_std` on the lines of the bands (all or some channels).

    ``known``: the noise came with the FRF (an estimate from time data) and is taken as it is.
    ``residual``: the fit's residual on those lines and channels, if the caller has it.
    ``fit``: an unweighted :func:`_fit_bands` fit of these poles on the same lines and channels,
    whose own residual is then used; ``data``: :func:`_band_data` of them.
    """
    rows = slice(None) if channels is None else channels
    if known:
        return np.asarray(estimated_noise, float)[rows]
    if fit is not None:
        omega = frf.omega_rad_s[_regions(bands, frf.frequency_hz)[0]] if data is None else data[0]
        with np.errstate(all="ignore"):
            return fit_residual_noise_std(omega, fit, np.asarray(estimated_noise, float)[rows])
    omega, response, region = _band_data(frf, bands, channels) if data is None else data
    with np.errstate(all="ignore"):
        return residual_noise_std(omega, response, power, region, omega_n, damping_ratio, estimated_noise[rows],
                                  residual)


def _line_weight(frf, bands):
    """Weights σ_ref/σ_line of the bands' lines for an FRF that carries its noise per line, else None.

    σ_line is the RMS over channels of the FRF's ``noise_std`` and σ_ref its RMS over the lines, so the
    weighted noise variance is σ_ref² on every line: the noise level :func:`_band_noise` gives the fit.
    An estimate's noise spikes at the zeros of the force spectrum (a 1 ms hammer pulse: 1, 2, 3 kHz);
    unweighted, those few lines pulled the 1450 and 2600 Hz poles of a hammer test to 1500 and 2500 Hz.
    A line claimed quieter than 1e-3 σ_ref counts as 1e-3 σ_ref (no line weighs more than 1000).
    """
    line_noise = getattr(frf, "noise_std", None)
    if line_noise is None:
        return None
    keep, _ = _regions(bands, frf.frequency_hz)
    sigma = np.sqrt(np.mean(np.atleast_2d(np.asarray(line_noise, float))[:, keep] ** 2, axis=0))
    ref = float(np.sqrt(np.mean(sigma**2))) if sigma.size else 0.0
    if not (np.all(np.isfinite(sigma)) and ref > 0):
        return None
    return ref / np.maximum(sigma, 1e-3 * ref)


def _fit_bands(frf, bands, power, omega_n0, damping_ratio0, channels=None, data=None, band_peak=None):
    """:func:`modal.nls.fit_modes` of every band's mode together, with collapsed modes reseated.

    A weak mode whose start lies on a noise spike can collapse there inside the
    joint fit (ζ shrinking to the spike's width, its error larger than a tenth
    of it) while its neighbour absorbs the real mode: finding 29 of
    docs/stress.md, a neighbour 5.4 errors off, unflagged, with the collapsed
    mode formally still in the model. Such a mode (relative error of ζ above
    ``REL_STD_LIMIT``, or ζ ≥ 1) restarts where the residual of the other
    modes peaks in its band (:func:`modal.checks.restart_pole`), and the joint
    fit runs again. The restart is kept only when its residual is lower: the
    reported fit is the better least-squares optimum of the same model. ``data``: the
    :func:`_band_data` of these bands and channels, when the caller has it; ``band_peak``: its
    :func:`_band_peaks`.
    """
    omega, response, region = _band_data(frf, bands, channels) if data is None else data
    weight = _line_weight(frf, bands)
    scale = None if band_peak is None else band_peak.max(axis=0)  # max |H| of each channel on the lines
    with np.errstate(all="ignore"):
        fit = fit_modes(omega, response, power, omega_n0, damping_ratio0, region=region, line_weight=weight,
                        channel_scale=scale)
    if len(bands) < 2:
        return fit
    for r in range(len(bands)):
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
                                channel_scale=scale)
        if _fit_cost(restart) < _fit_cost(fit):
            fit = restart
    return fit


def _truncation(frf, bands, power, fit, channels=None, residual=None, data=None):
    """Shift of the fit when the band backgrounds gain a slope and a curvature, or None.

    Measured only where the residual is smooth across the lines (ratio of
    :func:`modal.checks.residual_structure` above ``STRUCTURED_RATIO``): there
    the noise is below the misfit of the plain offset, and the shift is the
    truncation bias of the modes outside the bands (:func:`modal.nls.truncation_shift`).
    With white residuals the shift would be noise only and is not measured.
    Returns (pole shift (n_modes, 2), constant shift (n_modes, n_channels)) in
    the fit's order of modes. ``residual``: the fit's residual, if the caller has it; ``data``: the
    :func:`_band_data` of these bands and channels.
    """
    omega, response, region = _band_data(frf, bands, channels) if data is None else data
    with np.errstate(all="ignore"):
        structure = residual_structure(omega, response, power, region, fit.omega_n, fit.damping_ratio, residual,
                                       peak=fit.channel_scale)
    if not structure > STRUCTURED_RATIO:
        return None
    return truncation_shift(omega, response, power, region, fit)


def _with_shift(cov, pole_shift, constant_shift):
    """Covariance (n_ch, 4, 4) of one mode plus the outer product of its shift per channel."""
    d = np.column_stack([np.broadcast_to(pole_shift, (constant_shift.size, 2)),
                         constant_shift.real, constant_shift.imag])
    return cov + d[:, :, None] * d[:, None, :]


def _missing_mode(frf, bands, power, omega_n, damping_ratio, estimated_noise, residual=None, residual_noise=None,
                  data=None, peak=None):
    """:func:`modal.checks.find_missing_mode` on the lines of the bands (``residual`` and ``residual_noise``:
    the fit's residual and its :func:`modal.checks.residual_noise_std`, if known; ``data``: the bands'
    :func:`_band_data`; ``peak``: max |H| of each channel there)."""
    omega, response, region = _band_data(frf, bands) if data is None else data
    bands_rad = [(TWO_PI * b.low_hz, TWO_PI * b.high_hz) for b in bands]
    with np.errstate(all="ignore"):
        return find_missing_mode(omega, response, power, region, omega_n, damping_ratio, estimated_noise,
                                 bands_rad, residual, residual_noise, peak)


#: automatic choice: the global method for a poly-reference grid or at least this many peaks
AUTO_GLOBAL_PEAKS = 5


def choose_method(frf: FRF, bands_hz=None, min_prominence_db: float = 6.0) -> str:
    """The method ``identify(frf, "auto")`` runs: ``"global"`` for a poly-reference test (an outputs ×
    references grid with several references) or at least :data:`AUTO_GLOBAL_PEAKS` peaks (a many-mode
    measurement, where band-wise fits each see their neighbours only as an offset), else ``"nls"``
    (one to a few well-separated modes, where it is the Cramér–Rao-efficient choice). Bands given
    explicitly keep the band-wise method.
    """
    return _auto_choice(frf, bands_hz, min_prominence_db)[0]


def _auto_choice(frf: FRF, bands_hz, min_prominence_db: float,
                 indicator=None, noise=None) -> tuple[str, list | None]:
    """:func:`choose_method`'s choice and the peaks' bands it found (None when it did not search), so that
    identify does not search twice (``indicator``: :func:`modal.peaks._indicator_and_peak`, and ``noise``,
    the raw noise per channel, when the caller has them)."""
    if bands_hz is not None:
        return "nls", None
    from .global_ import channel_grid

    index, _, transposed = channel_grid(frf)
    if index.shape[1] > 1:
        return "global", None
    noise = estimate_noise_std(frf) if noise is None else noise
    try:  # the peaks identify itself would fit: the same noise-aware test (an estimate's noise per line)
        bands = find_modes(frf, min_prominence_db=min_prominence_db, noise_std=noise,
                           line_noise_std=getattr(frf, "noise_std", None), indicator=indicator)
    except IdentificationError:
        return "nls", None
    return ("global" if len(bands) >= AUTO_GLOBAL_PEAKS else "nls"), bands


def identify(frf: FRF, method: str = "auto", bands_hz=None, *, noise_std=None, driving_point=None,
             min_prominence_db: float = 6.0, max_modes: int | None = None, **global_options) -> IdentificationResult:
    """Identify every mode of an FRF.

    Parameters
    ----------
    frf : FRF
        One or many channels (poles are shared by all channels).
    method : {"auto", "nls", "circle", "halfpower", "global"}
        ``"auto"`` (default): ``"global"`` for poly-reference or many-mode
        data, else ``"nls"`` (:func:`choose_method`); ``result.method`` says
        which ran.
        ``"nls"``: complex nonlinear least squares of all modes
        together, each band started from its one-mode rational fit
        (:func:`modal.rational.rational_pole`; from the better of half-power and
        circle fit where that gives no pole or a doubtful fit).
        ``"global"``: poly-reference LSCF (PolyMAX) poles with a stabilisation
        diagram, then a joint refinement of all poles, modal constants and
        residual terms over the whole band (:func:`modal.global_.identify_global`;
        its options ``modes_hz``, ``order``, ``max_order`` pass through
        ``**global_options``; ``bands_hz`` gives the band by its extremes).
        ``"circle"``: Kennedy–Pancu circle fit on the mobility.
        ``"halfpower"``: half-power bandwidth with exact inversion.
    bands_hz : list of (f_low, f_high), optional
        One band per mode, Hz. Default: found from the peaks, each ±3
        half-power widths, clipped halfway to its neighbours.
    noise_std : float or array_like over channels, optional
        Known noise σ (E|n|² = σ²) in the FRF's unit; default estimated from
        each line's misfit to its neighbours (:func:`modal.peaks.neighbour_noise_std`).
    driving_point : bool or array_like of bool, optional
        Overrides which channels are driving points (k, c, m defined).
    min_prominence_db : float
        Peak detection threshold when ``bands_hz`` is not given.
    max_modes : int, optional
        Keep at most this many (strongest) peaks.

    Returns
    -------
    IdentificationResult
        ``result.modes[i]`` has ``natural_frequency_hz``, ``damping_ratio``,
        ``modal_constant``, ``stiffness_n_per_m``, ``damping_n_s_per_m``,
        ``mass_kg``, ``std`` (standard errors under the same names) and
        ``flags``; arrays over channels for multi-channel FRFs.

    Warns
    -----
    ResolutionWarning
        An estimate is resolution-limited (fewer than 3 lines above −3 dB, a
        missing crossing); it is returned flagged.
    QualityWarning
        Any other flag (band-edge peak, poor model fit, large uncertainty).
    """
    if not isinstance(frf, FRF):
        raise TypeError(f"identify() expects a modal.FRF, got {type(frf).__name__}")
    if global_options and method not in ("global", "auto"):
        raise TypeError(f"identify() got options {', '.join(sorted(global_options))} that only method='global' takes")
    if method not in METHODS and method != "auto":
        raise IdentificationError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    from .scaling import scale_exponent, scaled_frf, unscale_result

    # |H| once: the mode indicator and each channel's max |H|, and (but for the global method, which measures
    # its own) the raw noise per channel from the same read of the data
    if method == "global":
        indicator, raw = _indicator_and_peak(frf), None
    else:
        mode_indicator, channel_peak, raw = _indicator_and_peak(frf, noise=True)
        indicator = (mode_indicator, channel_peak)
    exponent = scale_exponent(frf, peak=indicator[1])
    if exponent:  # values near over- or underflow: fit 2**e H (exact) and scale the results back
        gain = 2.0**exponent
        result = identify(scaled_frf(frf, exponent), method, bands_hz,
                          noise_std=None if noise_std is None else np.asarray(noise_std, float) * gain,
                          driving_point=driving_point, min_prominence_db=min_prominence_db, max_modes=max_modes,
                          **global_options)
        return unscale_result(result, gain)
    found = None  # peak bands the automatic choice already searched
    if method == "auto":  # chosen on the (possibly rescaled) data, so the choice never overflows
        method, found = (("global", None) if global_options
                         else _auto_choice(frf, bands_hz, min_prominence_db, indicator, raw))
    if method == "global":
        from .global_ import identify_global

        band = None if bands_hz is None else (min(b[0] for b in bands_hz), max(b[1] for b in bands_hz))
        return identify_global(frf, band_hz=band, noise_std=noise_std, driving_point=driving_point, **global_options)
    power = KIND_POWER[frf.kind]
    n_ch = frf.n_channels
    estimated_noise = raw  # the raw noise per channel, from the indicator's read of the data
    # an FRF estimated from time data carries its own calibrated noise per line (modal.estimate_frf)
    line_noise = getattr(frf, "noise_std", None)
    if bands_hz is not None:
        bands = bands_from_hz(frf, bands_hz, indicator=indicator[0])
    elif found is not None and max_modes is None:  # the automatic choice's search, with the same arguments
        bands = found
    else:
        bands = find_modes(frf, min_prominence_db=min_prominence_db, max_modes=max_modes, noise_std=estimated_noise,
                           line_noise_std=line_noise, indicator=indicator)
    known_noise = noise_std is None and line_noise is not None
    if known_noise:
        estimated_noise = _band_noise(frf, bands, line_noise)
    if noise_std is None:
        noise = estimated_noise
    else:
        noise = np.broadcast_to(np.asarray(noise_std, float), (n_ch,)).copy()
        if not np.all(np.isfinite(noise)) or np.any(noise < 0):
            raise IdentificationError(f"noise_std must be finite and >= 0, got {noise_std!r}")
    per_mode = []  # (wn, zeta, const (n_ch,), cov (n_ch,4,4) or None, std_wn, std_z, flags, quality, chi2)
    if method in ("halfpower", "circle"):
        poles = []
        for band in bands:
            strongest = None
            if n_ch > POLE_CHANNELS:
                strongest = _strongest_channels(frf, band, noise, POLE_CHANNELS)
            poles.append(_sdof_estimates(frf, band, power, noise, method, strongest))
        if method == "halfpower" and len(bands) > 1:
            poles = _without_neighbours(frf, bands, power, noise, poles)
        consts = np.array([p[4] for p in poles])  # (n_modes, n_ch)
        missing = ~np.isfinite(consts)
        if method == "halfpower":
            # half-power gives poles only: every constant from one solve with all the poles
            # (a peak-height constant ignores the neighbours' contribution)
            missing[:] = True
        if missing.any():
            filled = _constants_all_poles(frf, bands, power, [p[0] for p in poles], [p[1] for p in poles])
            consts[missing] = filled[missing]
        refined = {}
        check, missing_mode = _refinement_check(frf, bands, power, poles, consts, noise, estimated_noise,
                                                known_noise, refined)
        if noise_std is None and not known_noise:
            poles = _rescaled(frf, bands, power, poles, noise, refined.get("noise_var"))
        errors = _bandwise_covariance(frf, bands, power, poles, noise, ~missing if method == "circle" else None)
        # the misfit near each mode of the refined model (the model whose chi-square is tested)
        refined_poles = np.array([[p[0] - c[0], p[1] - c[1]] for p, c in zip(poles, check)], float)
        usable = np.all(np.isfinite(refined_poles), axis=1) & np.all(refined_poles > 0, axis=1)
        relative = np.full(len(bands), np.nan)
        if usable.all():
            relative = _local_misfit(frf, bands, power, refined_poles[:, 0], refined_poles[:, 1])
        for b, (band, (wn, zeta, s_wn, s_z, _, flags, q, _e), const, cov, reference) in enumerate(zip(
                bands, poles, consts, errors, check)):
            d_wn, d_z, d_const, chi2, bound_wn, bound_z = reference
            if model_inadequate(chi2, relative[b]):
                flags.add("model_inadequate")
            # the difference from the refinement has at most the variance of the two errors
            # together (equality when they are independent; less when both see the same noise)
            scale_wn = np.hypot(np.nan_to_num(s_wn), bound_wn)
            scale_z = np.hypot(np.nan_to_num(s_z), bound_z)
            pole_biased = abs(d_wn) > BIAS_LIMIT * scale_wn or abs(d_z) > BIAS_LIMIT * scale_z
            noise_cov = cov.copy()  # k, c, m take the bias exactly (see modal.assemble.physical_with_flags), not through it
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
                z_const = _constant_distance(d_const, cov[:, 2:, 2:], REFINEMENT_PRECISION * np.abs(const - d_const))
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
            per_mode.append((wn, zeta, const, cov, s_wn, s_z, flags, q, chi2, reference))
    else:
        data = _band_data(frf, bands)  # the lines of the bands, taken out once
        band_peak = _band_peaks(bands, data)
        fit = _nls_fit(frf, bands, power, noise, data, band_peak)
        # the checks all measure the residual of the same modes on the same lines: the fit's own when it is
        # unweighted (no second solve), else computed once
        own = fit.residual is not None and not fit.line_weighted
        if own:
            residual = fit.residual
        else:
            with np.errstate(all="ignore"):
                residual = fit_residual(data[0], data[1], power, data[2], fit.omega_n, fit.damping_ratio)
        # χ² is a median over the channels: many channels are sampled (peaks.channel_sample)
        rows = channel_sample(n_ch)
        if known_noise:
            fit_noise = estimated_noise[rows]
        elif own:
            with np.errstate(all="ignore"):
                fit_noise = fit_residual_noise_std(data[0], fit, estimated_noise[rows], rows)
        else:
            fit_noise = _fit_noise(frf, bands, power, fit.omega_n, fit.damping_ratio, estimated_noise,
                                   residual=residual, data=data)[rows]
        chi2 = _chi2(fit.noise_var[rows], fit_noise)
        # the check's noise is the residual's own (of every channel, when at hand; else it measures its own)
        missing_mode = _missing_mode(frf, bands, power, fit.omega_n, fit.damping_ratio, estimated_noise, residual,
                                     None if known_noise or isinstance(rows, np.ndarray) else fit_noise, data,
                                     fit.channel_scale)
        # near-exact data: the offset's truncation (modes outside the bands) biases the poles
        # beyond their white-noise errors; its measured shift is added to them (finding 26)
        shift = _truncation(frf, bands, power, fit, residual=residual, data=data)
        order = np.argsort(fit.omega_n)  # two close poles may cross during the fit
        relative = _local_misfit(frf, bands, power, fit.omega_n[order], fit.damping_ratio[order], data, band_peak)
        for b, (band, r) in enumerate(zip(bands, order)):
            flags: set[str] = set()
            if not fit.converged:
                flags.add("did_not_converge")
            if not np.all(np.isfinite(fit.noise_var)):
                flags.add("too_few_points")  # no lines left over for a residual: no errors
            elif not np.all(np.isfinite(fit.mode_cov[r])):
                flags.add("high_uncertainty")  # errors undetermined: the data do not determine a pole (nls.FISHER_RCOND)
            if model_inadequate(chi2, relative[b]):
                flags.add("model_inadequate")
            cov = fit.mode_cov[r] if shift is None else _with_shift(fit.mode_cov[r], shift[0][r], shift[1][r])
            s_wn = float(np.sqrt(max(cov[0, 0, 0], 0))) if np.isfinite(cov[0, 0, 0]) else np.nan
            s_z = float(np.sqrt(max(cov[0, 1, 1], 0))) if np.isfinite(cov[0, 1, 1]) else np.nan
            wn, zeta = float(fit.omega_n[r]), float(fit.damping_ratio[r])
            if not (band.low_hz <= wn / TWO_PI <= band.high_hz):
                flags.add("band_edge_peak")
            per_mode.append((wn, zeta, fit.modal_constant[r], cov, s_wn, s_z, flags, chi2, chi2, None))

    estimates = []
    for index, (band, (wn, zeta, const, cov, s_wn, s_z, flags, quality, chi2, reference)) in enumerate(
            zip(bands, per_mode)):
        flags = set(flags)
        detail = {}
        if missing_mode is not None and (missing_mode.band == index or index in missing_mode.moved_bands):
            flags.add("missing_mode")
            detail["missing_mode"] = f" (near {missing_mode.frequency_hz:.6g} Hz, zeta {missing_mode.damping_ratio:.3g})"
        omega_b = frf.omega_rad_s[_band_mask(frf, band)]
        spacing = line_spacing(omega_b) if omega_b.size > 1 else np.nan
        if any(b is not band and band.low_hz < b.peak_hz < band.high_hz for b in bands):
            flags.add("close_modes")  # another mode's peak inside this mode's band
        estimates.append(ModeEstimate(
            wn, zeta, np.asarray(const, complex), cov, s_wn, s_z, (band.low_hz, band.high_hz), int(omega_b.size),
            2 * zeta * wn / spacing if spacing > 0 else np.nan, flags, detail, chi2, quality, reference))
    driving, assumed = driving_points(frf, driving_point)
    modes = assemble_modes(estimates, method=method, source=frf.source, single=frf.response.ndim == 1,
                           driving=driving, driving_assumed=assumed,
                           window_decay_s=getattr(frf, "exponential_decay_s", None))
    return IdentificationResult(tuple(modes), method, frf.kind, n_ch, noise_std=estimated_noise)
