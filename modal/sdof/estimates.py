"""Half-power and circle-fit estimates of each band's mode: per channel, then combined into one pole.

:func:`sdof_estimates` runs :func:`~modal.sdof.halfpower.half_power_curve` or
:func:`~modal.sdof.circlefit.circle_fit_curve` on each channel of a band and
combines the channels' poles (:func:`~modal.sdof.propagate.combine_poles`) with
their propagated errors; :func:`rescaled` recombines them with the noise the fit's
residual shows, :func:`without_neighbours` repeats half-power on the data less the
other modes, and :func:`bandwise_covariance` gives the covariance of every
mode's pole and modal constants.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..flags import GRID_FLAGS
from ..model import mode_basis, solve_linear
from .bands import (POLE_CHANNELS, band_data, band_lines, band_mask, channel_weights, constants_at_poles, regions,
                    strongest_channels)
from .circlefit import circle_fit_curve
from .halfpower import half_power_curve
from .propagate import combine_poles, constant_covariance, magnitude_to_complex

__all__ = ["sdof_estimates", "combine_channels", "rescaled", "without_neighbours", "bandwise_covariance"]

def sdof_estimates(frf, band, power, noise, method, channels=None, errors=True):
    """Per-channel half-power or circle estimates, combined into one pole.

    ``channels`` restricts the pole estimate to a subset (the modal constants
    of the others stay NaN); by default every channel is used.

    Returns (ωn, ζ, std ωn, std ζ, constants (n_ch,), flags, quality, errors) where
    ``errors`` holds the pole's covariance ``"cov"`` (2, 2), how each channel's lines
    enter it ``"rows"`` (n_ch, 2, 2, n_band: ∂θ/∂(Re h, Im h), the channel's gain in the
    combination applied) and, for the circle, each channel's own covariance of
    (ωn, ζ, Re A, Im A) ``"own"`` (n_ch, 4, 4) with the combined pole's cross terms.
    """
    omega, h = band_lines(frf, band)
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
    raw = {"theta": theta, "cov": cov, "systematic": systematic, "rows": rows, "own": own, "weights": channel_weights(frf, band, noise),
           "circle": method == "circle"}
    return combine_channels(omega, h, raw, const, flags, q)


def combine_channels(omega, h, raw, const, flags, q, scale=None):
    """The pole of one band from the channels' estimates (``raw`` of :func:`sdof_estimates`).

    ``scale`` (n_ch,): factors on each channel's noise variance (the noise as the fit's
    residual shows it, :func:`rescaled`); every covariance is linear in it.
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


def rescaled(frf, bands, power, poles, noise, refined_var=None):
    """The poles again with each channel's errors for the noise the fit's residual shows.

    The raw-data noise estimate takes in the resonances' curvature (8 % high at 12 lines
    per half-power band) and is a median over the lines (±10 %). The residual variance
    of the least-squares refinement of the same modes (``refined_var``, rss/dof, as the
    refinement's own errors use it: ±5 % at 100 lines) has neither; on channels the
    refinement did not use, the residual of the constants solved with these poles.
    """
    omega, response, region = band_data(frf, bands)
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
        out.append(combine_channels(omega_b, h_b, p[7]["raw"], const, flags, q, scale))
    return out


def without_neighbours(frf, bands, power, noise, poles):
    """Half-power poles again, each on the data less the other identified modes.

    The magnitude of a mode's band carries its neighbours' tails (an offset and a
    slope across the band), which bend the −3 dB crossings: at 1 % noise a neighbour
    at 2.5× the frequency biased ωn by −0.4 of its error (SD of z 1.25). The
    other modes, with the first pass's poles and their constants solved with all the
    poles, are subtracted on every line and each mode is estimated again.
    """
    wn = np.array([p[0] for p in poles], float)
    zeta = np.array([p[1] for p in poles], float)
    if not (np.all(np.isfinite(wn)) and np.all(np.isfinite(zeta)) and np.all(wn > 0) and np.all(zeta > 0)):
        return poles
    consts = constants_at_poles(frf, bands, power, wn, zeta)  # (n_modes, n_ch)
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
            strongest = strongest_channels(frf, band, noise, POLE_CHANNELS)
        out.append(sdof_estimates(frf_r, band, power, noise, "halfpower", strongest))
    return out


def bandwise_covariance(frf, bands, power, poles, noise, own_constants=None):
    """Covariance (n_modes, n_ch, 4, 4) of (ωn, ζ, Re A, Im A) of the half-power or circle result.

    The poles' covariances come with each estimate (:func:`sdof_estimates`); the
    constants solved linearly with all the poles get theirs from
    :func:`modal.sdof.propagate.constant_covariance`; a circle's own constants
    (``own_constants``, (n_modes, n_ch) bool) keep the circle's covariance.
    """
    omega, response, region = band_data(frf, bands)
    keep, _ = regions(bands, frf.frequency_hz)
    keep_idx = np.flatnonzero(keep)
    n_modes, n_ch = len(bands), frf.n_channels
    pole_rows = np.zeros((n_modes, n_ch, 2, 2, omega.size))
    for r, band in enumerate(bands):
        lines = np.flatnonzero(band_mask(frf, band))
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
