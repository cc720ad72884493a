"""Standard errors of the single-mode methods (half-power, circle fit), propagated to first order.

Each channel's estimate is a function of that channel's lines; its linearisation
(:attr:`modal.sdof.halfpower.HalfPowerEstimate.jacobian`,
:attr:`modal.sdof.circlefit.CircleEstimate.jacobian`) times the noise of the lines
(white circular noise σ: σ²/2 on the real and on the imaginary part of each line,
independent) gives the covariance of that estimate. Here the channels' poles are
combined and the modal constants that are solved linearly with the poles get
their covariance, including the part they share with the pole (the same noise
enters both).

Real Jacobians are over ``(part, line)``: part 0 the real, part 1 the imaginary part
of the FRF on a line.
"""
from __future__ import annotations

import numpy as np

from ..model import mode_basis, mode_basis_derivatives

__all__ = ["magnitude_to_complex", "combine_poles", "constant_covariance"]

#: a channel whose pole lies further than this many standard errors (its own and the
#: median's) from the weighted median of the channels is left out of the combination
OUTLIER_LIMIT = 4.0
#: standard error of a median over that of the mean of normal values (√(π/2))
MEDIAN_EFFICIENCY = 1.2533


def magnitude_to_complex(jac_mag: np.ndarray, h: np.ndarray) -> np.ndarray:
    """A Jacobian over |h| per line (p, n) as one over (Re h, Im h): shape (p, 2, n)."""
    mag = np.abs(h)
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = np.where(mag > 0, h / mag, 0.0)
    return np.stack([jac_mag * unit.real, jac_mag * unit.imag], axis=1)


def _weighted_median(values, weights):
    order = np.argsort(values)
    v, w = values[order], weights[order]
    position = (np.cumsum(w) - w / 2) / np.sum(w)
    return float(np.interp(0.5, position, v))


def combine_poles(theta: np.ndarray, cov: np.ndarray, weights: np.ndarray):
    """Combine per-channel poles (ωn, ζ) into one, with its covariance.

    The inverse-covariance weighted mean of the channels, θ = (Σ P_c)⁻¹ Σ P_c θ_c with
    P_c = cov_c⁻¹, whose covariance is exactly (Σ P_c)⁻¹ for independent channels. A
    channel further than :data:`OUTLIER_LIMIT` errors from the weighted median (a node of
    the mode, a neighbour's peak) is left out first, so that one poor channel does not
    drag the shared pole.

    Parameters
    ----------
    theta : ndarray, shape (n_ch, 2)
        Per-channel (ωn, ζ); NaN where the channel gave none.
    cov : ndarray, shape (n_ch, 2, 2)
        Their covariances.
    weights : ndarray, shape (n_ch,)
        Weights of the median (signal-to-noise power at the peak).

    Returns
    -------
    theta, cov, gain
        Combined pole (2,), its covariance (2, 2) and each channel's gain (n_ch, 2, 2):
        dθ = Σ_c gain_c dθ_c. NaN pole when no channel gave one.
    """
    n_ch = theta.shape[0]
    gain = np.zeros((n_ch, 2, 2))
    finite = np.all(np.isfinite(theta), axis=1)
    if not finite.any():
        return np.full(2, np.nan), np.full((2, 2), np.nan), gain
    good_cov = finite & np.all(np.isfinite(cov), axis=(1, 2)) & (cov[:, 0, 0] > 0) & (cov[:, 1, 1] > 0)
    good_cov &= np.linalg.det(np.where(good_cov[:, None, None], cov, np.eye(2))) > 0
    if not good_cov.any():
        # no usable errors: the weighted median of the values, without an error
        w = np.where(np.isfinite(weights) & (weights > 0), weights, 0.0)
        w = np.where(finite, w if np.any(w[finite] > 0) else 1.0, 0.0)
        values = np.array([_weighted_median(theta[finite, k], w[finite]) for k in range(2)])
        return values, np.full((2, 2), np.nan), gain
    use = np.flatnonzero(good_cov)
    if use.size >= 3:
        w = np.where(np.isfinite(weights[use]) & (weights[use] > 0), weights[use], 1.0)
        median = np.array([_weighted_median(theta[use, k], w) for k in range(2)])
        var = cov[use][:, [0, 1], [0, 1]]
        var_median = MEDIAN_EFFICIENCY**2 / np.sum(1.0 / var, axis=0)
        z = np.abs(theta[use] - median) / np.sqrt(var + var_median)
        kept = use[np.all(z <= OUTLIER_LIMIT, axis=1)]
        use = kept if kept.size else use
    # a correlation of ±1 to rounding (a pole fixed by one line pair) would make the
    # precision singular: the diagonal is raised by 1e-9 of itself
    sub = cov[use] + 1e-9 * cov[use][:, [0, 1], [0, 1]][:, :, None] * np.eye(2)
    try:
        precision = np.linalg.inv(sub)
        total = np.linalg.inv(np.sum(precision, axis=0))
    except np.linalg.LinAlgError:  # no usable weights: each component on its own
        precision = np.eye(2)[None] / sub[:, [0, 1], [0, 1]][:, :, None]
        total = np.linalg.inv(np.sum(precision, axis=0))
    gain[use] = total @ precision
    combined = np.einsum("cij,cj->i", gain[use], theta[use])
    return combined, total, gain


def _real_rows(coefficients: np.ndarray) -> np.ndarray:
    """Re and Im of Σ_j l_j dh_j as real rows over (part, line): shape (2, 2, n)."""
    l_re, l_im = coefficients.real, coefficients.imag
    return np.array([[l_re, -l_im], [l_im, l_re]])


def constant_covariance(omega, region, power, omega_n, damping_ratio, response, noise, pole_cov, pole_rows):
    """Covariance of (ωn, ζ, Re A, Im A) of every mode and channel when the modal constants
    are solved linearly with the poles (all modes together, one offset per band region).

    A_c = Φ⁺ h_c, so dA_c = Φ⁺ dh_c + Σ_s ∂A_c/∂θ_s dθ_s: the linear solve's own error,
    the poles' errors carried through it, and their covariance through the lines that
    the pole estimate and the solve share.

    Parameters
    ----------
    omega : ndarray (n,)
        Lines of all the bands (rad/s); ``region`` their band region.
    response : ndarray (n_ch, n)
        The FRF on those lines.
    omega_n, damping_ratio : ndarray (n_modes,)
        The poles the constants are solved with.
    noise : ndarray (n_ch,)
        σ of the complex noise per channel (white).
    pole_cov : ndarray (n_modes, 2, 2)
        Covariance of each pole (poles of different modes are independent: disjoint bands).
    pole_rows : ndarray (n_modes, n_ch, 2, 2, n)
        ∂θ_s/∂(Re h_c, Im h_c) on the lines ``omega``: how each channel's data enters each
        pole (zero for channels that did not take part).

    Returns
    -------
    ndarray (n_modes, n_ch, 4, 4)
    """
    n_modes, n_ch = pole_rows.shape[:2]
    wn0 = np.asarray(omega_n, float)
    z0 = np.asarray(damping_ratio, float)
    ok = np.isfinite(wn0) & np.isfinite(z0) & (wn0 > 0)
    if not ok.all():  # modes without a pole get no constants (NaN), the others are solved alone
        out = np.full((n_modes, n_ch, 4, 4), np.nan)
        if ok.any():
            out[ok] = constant_covariance(omega, region, power, wn0[ok], z0[ok], response, noise,
                                          np.asarray(pole_cov)[ok], np.asarray(pole_rows)[ok])
        return out
    offsets = np.zeros((omega.size, region.max() + 1), dtype=complex)
    offsets[np.arange(omega.size), region] = 1.0

    def pinv_of(wn, zeta):
        basis = np.hstack([mode_basis(omega, wn, zeta, power).T, offsets])
        norms = np.linalg.norm(basis, axis=0)
        norms[norms == 0] = 1.0
        return np.linalg.pinv(basis / norms) / norms[:, None]

    full = pinv_of(wn0, z0)  # (n_modes + regions, n)
    pinv = full[:n_modes]  # (n_modes, n)
    # ∂A_{r,c}/∂θ_{s,j} (n_modes, n_ch, n_modes, 2) of the least-squares solve x = Φ⁺h: with column s of Φ moved
    # by d_s, dx = −Φ⁺ d_s x_s + (ΦᴴΦ)⁻¹ e_s d_sᴴ r (r = h − Φx, the solve's residual; (ΦᴴΦ)⁻¹ = Φ⁺Φ⁺ᴴ)
    basis = np.hstack([mode_basis(omega, wn0, z0, power).T, offsets])  # (n, p)
    solution = full @ response.T  # (p, n_ch)
    residual = response.T - basis @ solution  # (n, n_ch)
    gram_inverse = full @ full.conj().T  # (p, p)
    slope = np.empty((n_modes, n_ch, n_modes, 2), complex)
    for j, derivative in enumerate(mode_basis_derivatives(omega, wn0, z0, power)):  # each (n_modes, n)
        moved = (full @ derivative.T)[:n_modes]  # (n_modes, n_modes): Φ⁺ d_s in column s
        against = derivative.conj() @ residual  # (n_modes, n_ch): d_sᴴ r_c
        slope[:, :, :, j] = (-moved[:, None, :] * solution[:n_modes].T[None, :, :]
                             + gram_inverse[:n_modes, :n_modes][:, None, :] * against.T[None, :, :])
    # real form: K (n_modes, n_ch, 2 [Re, Im], 2 n_modes)
    K = np.stack([slope.real, slope.imag], axis=2).reshape(n_modes, n_ch, 2, 2 * n_modes)
    theta_cov = np.zeros((2 * n_modes, 2 * n_modes))
    for s in range(n_modes):
        theta_cov[2 * s:2 * s + 2, 2 * s:2 * s + 2] = np.nan_to_num(pole_cov[s])
    var = np.asarray(noise, float) ** 2 / 2  # (n_ch,)
    out = np.zeros((n_modes, n_ch, 4, 4))
    for r in range(n_modes):
        L = _real_rows(pinv[r])  # (2, 2, n): Re A, Im A over (part, line)
        Kr = K[r]  # (n_ch, 2, 2 n_modes)
        own = var[:, None, None] * np.einsum("akn,bkn->ab", L, L)[None]
        carried = np.einsum("cap,pq,cbq->cab", Kr, theta_cov, Kr)
        # cov(solve part of A_c, θ) through the lines both use: (n_ch, 2, 2 n_modes)
        shared = var[:, None, None] * np.einsum("akn,scpkn->casp", L, pole_rows).reshape(n_ch, 2, 2 * n_modes)
        cross = np.einsum("cap,cbp->cab", shared, Kr)
        out[r, :, 2:, 2:] = own + carried + cross + cross.transpose(0, 2, 1)
        # cov(θ_r, A_c): the pole's covariance through ∂A/∂θ, and the shared lines
        pole_part = np.einsum("ip,cbp->cib", theta_cov[2 * r:2 * r + 2], Kr) + shared[:, :, 2 * r:2 * r + 2].transpose(0, 2, 1)
        out[r, :, :2, 2:] = pole_part
        out[r, :, 2:, :2] = pole_part.transpose(0, 2, 1)
        out[r, :, :2, :2] = pole_cov[r]
    return out
