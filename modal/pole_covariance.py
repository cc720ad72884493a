"""The poles' covariance of a fit by :func:`modal.nls.fit_modes`, and its modal constants' from it.

:func:`fill_covariance` assembles it from the fit's projected Jacobian: the inverse Fisher information
(:func:`pole_covariance`, NaN where the data do not determine a pole), the sandwich of a cost that weighs
several channels alike (:mod:`modal.channel_covariance`), the variance measured over the records
(:mod:`modal.record_variance`) or the Newey–West lag sum of the lines' scores (:func:`line_scores`,
:func:`lag_covariance`); then each channel's modal constants through their sensitivity to the poles and the
data's noise (:func:`constants_noise`: white, and an error the lines share).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .channel_covariance import channel_sandwich, relative_error_terms, sandwich_product, widened
from .record_variance import channel_scores, misfit_ratio, projected_scores, record_covariance

__all__ = ["FISHER_RCOND", "NULL_WEIGHT", "constants_noise", "fill_covariance", "lag_covariance", "line_scores",
           "pole_covariance"]


#: eigenvalues of the poles' Fisher information (scaled to a unit diagonal) below this fraction of the largest
#: count as zero: directions of the poles the data do not determine (two poles fitted onto one peak, a mode the
#: lines cannot resolve). Its inverse there held rounding noise: variances of either sign, 1e7 times the data's
#: spread, or spuriously small (stress: 8 modes at ζ ≈ 0.3, eigenvalue ratio −5e-17).
FISHER_RCOND = 1e-12
#: a parameter whose weight in such a direction exceeds this (of a unit eigenvector) is not determined: the
#: weights of the determined ones there are rounding, ~eps over the gap to the next eigenvalue
NULL_WEIGHT = 1e-6


def pole_covariance(F: np.ndarray) -> np.ndarray:
    """Covariance of the poles from their Fisher information ``F`` (symmetric, finite): its inverse, with NaN
    rows and columns for the parameters the data do not determine (see :data:`FISHER_RCOND`).

    The plain inverse of ``F`` scaled to a unit diagonal (n parameters) serves when its variances are
    positive and below 1/(n² ``FISHER_RCOND``): then no eigenvalue is below ``FISHER_RCOND`` of the largest
    (the smallest is at least 1/(n · the largest variance), the largest at most n); otherwise the
    eigen-decomposition decides.
    """
    s = np.sqrt(np.abs(np.diag(F)))
    s[s == 0] = 1.0
    scale = np.outer(s, s)
    scaled = F / scale
    try:
        inverse = np.linalg.inv(scaled)
        variance = np.diag(inverse)
        if np.all(variance > 0) and variance.max() * F.shape[0] ** 2 * FISHER_RCOND < 1:
            return inverse / scale
    except np.linalg.LinAlgError:
        pass
    try:
        eigenvalues, vectors = np.linalg.eigh(scaled)
    except np.linalg.LinAlgError:
        return np.full(F.shape, np.nan)
    resolved = eigenvalues > FISHER_RCOND * eigenvalues[-1]
    cov = (vectors[:, resolved] / eigenvalues[resolved]) @ vectors[:, resolved].T
    loose = np.any(np.abs(vectors[:, ~resolved]) > NULL_WEIGHT, axis=1)
    cov[loose, :] = np.nan
    cov[:, loose] = np.nan
    return cov / scale


def line_scores(E, Cm, weights, residual, inverse_scale) -> np.ndarray:
    """Each line's contribution 2 Σ_c w_c Re(conj(∂r/∂θ_j) r) to the gradient of the weighted cost, (n_theta, n_freq)."""
    scaled = residual[:] * inverse_scale[:, None]  # (n_ch, n_freq), the fit's units
    finite = np.where(np.isfinite(weights), weights, 0.0)
    combined = (Cm.conj() * finite) @ scaled  # (n_theta, n_freq): Σ_c w_c conj(C_jc) r_ck
    return 2.0 * np.real(E.conj().T * combined)


def lag_covariance(scores: np.ndarray, lags: int, region) -> np.ndarray:
    """Σ_ℓ (1 − |ℓ|/(L + 1)) Σ_k s_k s_{k+ℓ}ᵀ over |ℓ| ≤ L, pairs of lines in one region only."""
    out = scores @ scores.T
    n = scores.shape[1]
    same = None if region is None else np.asarray(region)
    for lag in range(1, min(lags, n - 1) + 1):
        left, right = scores[:, :-lag], scores[:, lag:]
        if same is not None:
            keep = same[:-lag] == same[lag:]
            left, right = left[:, keep], right[:, keep]
        product = left @ right.T
        out += (1.0 - lag / (lags + 1.0)) * (product + product.T)
    return out


def fill_covariance(mode_cov, dphi, Q, R, Cm, noise_var, correlated_lags=0, residual=None, region=None,
                    inverse_scale=None, records=None, common=None,
                    residual_correlated: Callable[[], bool] | None = None) -> bool:
    """Covariance of (ωn, ζ, Re c, Im c) per mode and channel, in the fit's units, into ``mode_cov``
    (n_modes, n_ch, 4, 4): the poles' from their Fisher information (the Schur complement, by the projected
    Jacobian), the constants' from the linear fit's plus their sensitivity to the poles.

    With ``correlated_lags`` > 0 and a ``residual`` (:class:`modal.nls.RowResidual`, FRF unit; ``inverse_scale``
    takes it to the fit's) whose lines correlate over those lags (several channels, or ``residual_correlated()``
    says so: a Ljung–Box test), the poles' covariance is the Newey–West sandwich F⁻¹ B F⁻¹ instead (see
    :func:`modal.nls.fit_modes`). ``records`` (the records'
    influences in the fit's units, (n_freq, n_records) for one channel or (n_freq, n_channels, n_records) for
    several, and the records each overlaps): the poles' covariance
    measured over the records where it can be (:func:`modal.record_variance.record_covariance`); returns
    whether it was. ``common``: an error the channels share (:func:`modal.channel_covariance.relative_error_terms`)."""
    n_theta = dphi.shape[1]
    n_modes = n_theta // 2
    from_records = False
    E = dphi - Q @ (Q.conj().T @ dphi)
    gram = E.conj().T @ E
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        weights = np.where(noise_var > 0, 1.0 / noise_var, np.inf)
        # a channel fitted exactly (residual 0) has infinite weight: F is then not finite and
        # the covariance is zero (below); inf·0 inside the product is expected, not an error
        F = 2 * np.real(gram * ((Cm.conj() * weights) @ Cm.T))
    cov_theta = np.full((n_theta, n_theta), np.nan)
    several = Cm.shape[1] > 1
    shared = None if common is None else relative_error_terms(
        E, Q, Cm, common, dphi.shape[0] - Q.shape[1] - n_theta / (2 * Cm.shape[1]))
    if np.all(np.isfinite(F)):
        # several channels: the fit weighs every scaled channel alike, not by its noise, so its poles' covariance
        # is the sandwich of that unweighted cost (equal to F⁻¹ where the channels' noise is equal)
        bread = pole_covariance(2 * np.real(gram * (Cm.conj() @ Cm.T))) if several else None
        cov_theta = channel_sandwich(bread, gram, Cm, noise_var, shared) if several else pole_covariance(F)
        measured = None
        by_channel = records is not None and records[0].ndim == 3  # several channels' (n_freq, n_ch, n_records)
        if records is not None and np.all(np.isfinite(cov_theta)):
            scores = channel_scores(E, Cm, records[0]) if by_channel else projected_scores(E, Cm[:, 0], records[0])
            measured = record_covariance(np.real((E.conj().T @ E) * (Cm.conj() @ Cm.T)), scores, records[1])
        if measured is not None:  # widened by a misfit the records do not see (see misfit_ratio)
            influence = records[0].reshape(dphi.shape[0], -1) if by_channel else records[0]
            off = influence - Q @ (Q.conj().T @ influence)
            if by_channel:  # the channels' terms of one record summed in the Gram matrix of the records
                off = off.reshape(records[0].shape).reshape(-1, records[0].shape[2])
            dof = dphi.shape[0] - Q.shape[1] - n_theta / (2 * Cm.shape[1])
            ratio = misfit_ratio(float(np.sum(noise_var)) * dof if by_channel else float(noise_var[0]) * dof, off,
                                 records[1])
            cov_theta, from_records = measured * max(ratio, 1.0) if np.isfinite(ratio) else measured, True
        elif correlated_lags > 0 and np.all(np.isfinite(cov_theta)) and (several or (
                residual_correlated is not None and residual_correlated())):
            n_freq = dphi.shape[0]
            dof = n_freq - Q.shape[1] - n_theta / (2 * Cm.shape[1])
            scores = line_scores(E, Cm, np.ones_like(weights) if several else weights, residual, inverse_scale)
            middle = lag_covariance(scores, correlated_lags, region) * (n_freq / dof if dof > 0 else np.nan)
            sandwich = sandwich_product(bread, middle) if several else cov_theta @ middle @ cov_theta
            if several and np.all(np.isfinite(sandwich)) and np.all(np.diag(cov_theta) > 0):
                cov_theta = widened(cov_theta, sandwich)
            elif np.all(np.isfinite(sandwich)) and np.all(np.diag(sandwich) > 0):
                cov_theta = sandwich
    elif np.all(noise_var == 0):
        cov_theta = np.zeros((n_theta, n_theta))
    # sensitivity of the linear coefficients to the poles: G_j = −Φ⁺ ∂Φ/∂θ_j C
    Rinv = np.linalg.inv(R)
    H = Rinv @ (Q.conj().T @ dphi)  # (n_b, n_theta)
    lin_var = np.sum(np.abs(Rinv) ** 2, axis=1)  # diag (ΦᴴΦ)⁻¹
    white_var, shared_var = constants_noise(Q, Rinv, noise_var, common, None if shared is None else shared[1])
    for r in range(n_modes):
        G = -H[r][:, None] * Cm  # (n_theta, n_ch): ∂c_r/∂θ_j per channel
        g_re, g_im = G.real, G.imag
        blk = mode_cov[r]
        idx = [2 * r, 2 * r + 1]
        blk[:, :2, :2] = cov_theta[2 * r:2 * r + 2, 2 * r:2 * r + 2]
        cross_re = cov_theta[idx] @ g_re  # (2, n_ch)
        cross_im = cov_theta[idx] @ g_im
        blk[:, :2, 2] = cross_re.T
        blk[:, :2, 3] = cross_im.T
        blk[:, 2, :2] = cross_re.T
        blk[:, 3, :2] = cross_im.T
        lin = white_var / 2 * lin_var[r] + shared_var[r] / 2
        blk[:, 2, 2] = lin + np.einsum("jc,jk,kc->c", g_re, cov_theta, g_re)
        blk[:, 3, 3] = lin + np.einsum("jc,jk,kc->c", g_im, cov_theta, g_im)
        blk[:, 2, 3] = blk[:, 3, 2] = np.einsum("jc,jk,kc->c", g_re, cov_theta, g_im)
    return from_records


def constants_noise(Q: np.ndarray, Rinv: np.ndarray, noise_var: np.ndarray, common, shared_power):
    """The linear coefficients' error from the data's noise: (white variance per line, per channel; variance of
    each coefficient from the error the channels share, (n_b, n_ch)).

    The coefficients are c = Φ⁺ h = R⁻¹ Qᴴ h per channel. Independent noise of variance σ² per line gives each
    σ² ‖row of R⁻¹‖²; an error shared over the lines (``common``, (n_ch, n_freq, n_factors): channel c's is
    ``common[c] @ ξ``, E ξξᴴ = I; the excitation noise of a short force window, smooth over the lines, a gain
    error of every line near a mode) moves them by R⁻¹ Qᴴ common[c] ξ, a variance ‖R⁻¹ Qᴴ common[c]‖² per
    coefficient that white noise of the same residual power understates by about the lines per mode (a hammer
    test's constants, and with them k, c, m, scattered 2-5 times their errors on three accelerometers). The
    residual power the shared error leaves (its part off the design, ``shared_power`` per channel:
    :func:`modal.channel_covariance.relative_error_terms`) is taken out of the white part."""
    if common is None:
        return noise_var, np.zeros((Rinv.shape[0], noise_var.shape[0]))
    moved = np.einsum("ab,cbr->car", Rinv, np.einsum("kb,ckr->cbr", Q.conj(), common))  # R⁻¹ Qᴴ common_c
    shared_var = np.einsum("car,car->ac", moved, moved.conj()).real  # (n_b, n_ch)
    return np.maximum(noise_var - shared_power, 0.0), shared_var
