"""The poles' covariance of a least-squares fit to several channels that weighs them alike.

:func:`modal.nls.fit_modes` scales each channel to its peak and weighs the scaled
channels alike, not by their noise; its poles' covariance is then the sandwich of that
cost (:func:`channel_sandwich`), and the residual's lag covariance only widens it
(:func:`widened`). One channel keeps the Fisher information's inverse (the two agree there).

An error every channel shares relative to its FRF (a hammer's force noise, H_o η: one η for every output,
smooth across the lines) is no independent noise: carried as a factor of η's covariance
(:mod:`modal.estimate.common_error`), it enters the sandwich's middle as its own term
(:func:`relative_error_terms`, :func:`channel_sandwich`'s ``common``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["channel_sandwich", "relative_error_terms", "relative_in_fit_units", "sandwich_product", "widened"]


def sandwich_product(bread: np.ndarray, middle: np.ndarray) -> np.ndarray:
    """``bread @ middle @ bread`` with the rows and columns of ``bread``'s undetermined parameters (NaN) kept NaN
    and the others' free of them."""
    loose = np.isnan(np.diag(bread))
    clean = np.where(np.isnan(bread), 0.0, bread)
    out = clean @ middle @ clean
    out[loose, :] = np.nan
    out[:, loose] = np.nan
    return out


def widened(model: np.ndarray, measured: np.ndarray) -> np.ndarray:
    """The ``model`` covariance with each parameter's variance raised to the ``measured`` one's where that is
    larger (the correlations kept). The residual's lag covariance (:func:`modal.pole_covariance.lag_covariance`) widens the errors
    where the lines correlate beyond the noise model, but it is biased low over the few lines near a peak that
    carry a pole: the fit leaves a residual orthogonal to its derivatives, so the lines' scores sum to zero and
    their lagged products cancel. Several channels: it only widens (on the multi-channel hammer cells of
    benchmarks/bench_chain.py it made z of fn spread 1.55 where the model alone gave 1.06)."""
    raise_by = np.sqrt(np.maximum(np.diag(measured), np.diag(model)) / np.diag(model))
    return model * np.outer(raise_by, raise_by)


def channel_sandwich(bread: np.ndarray, gram: np.ndarray, Cm: np.ndarray, noise_var: np.ndarray,
                     common: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Covariance of poles fitted by least squares that weighs every (scaled) channel alike while the channels'
    noise variances ``noise_var`` differ: B⁻¹ M B⁻¹ with ``bread`` B⁻¹ the inverse of the unweighted information
    2 Re(Eᴴ E ∘ C̄ Cᵀ) (:func:`modal.pole_covariance.pole_covariance`; ``gram`` Eᴴ E, ``Cm`` C) and M = 2 Re(Eᴴ E ∘ C̄ diag(σ²) Cᵀ) the
    covariance of that cost's gradient. Equal to the Fisher information's inverse where every σ² is equal; with
    unequal ones the Fisher inverse is the covariance of a fit weighing the channels by 1/σ², which this one is
    not (a channel twice as noisy as its scale says counts as much as a quiet one).

    ``common`` (:func:`relative_error_terms`): the shared error's scores G and each channel's residual power it
    accounts for; the middle is then 2 Re(G Gᴴ) plus the independent term with each σ² less that power."""
    if common is not None:
        scores, shared_power = common
        independent = np.maximum(noise_var - shared_power, 0.0)
        meat = 2 * np.real(gram * ((Cm.conj() * independent) @ Cm.T)) + 2 * np.real(scores @ scores.conj().T)
        return sandwich_product(bread, meat)
    meat = 2 * np.real(gram * ((Cm.conj() * noise_var) @ Cm.T))
    return sandwich_product(bread, meat)


def relative_error_terms(E: np.ndarray, Q: np.ndarray, Cm: np.ndarray, shared: np.ndarray,
                       dof: float) -> tuple[np.ndarray, np.ndarray]:
    """The scores of an error every channel shares, and the residual power it leaves in each channel.

    Parameters
    ----------
    E : ndarray, shape (n_freq, n_theta)
        The poles' derivatives projected off the design (in the fit's units: weighted, whitened).
    Q : ndarray, shape (n_freq, n_b)
        Orthonormal basis of the design.
    Cm : ndarray, shape (n_theta, n_ch)
        The coefficient multiplying each derivative, per channel.
    shared : ndarray, shape (n_ch, n_freq, n_factors)
        The shared error's factor in each channel, in the fit's units: channel c's error is ``shared[c] @ ξ``
        with ξ standard complex circular (E ξξᴴ = I), the same ξ for every channel.
    dof : float
        Degrees of freedom of each channel's residual power (its sum of squares over them).

    Returns
    -------
    scores : ndarray, shape (n_theta, n_factors)
        G with the cost's gradient 2 Re(G ξ) from the shared error: G_j = Σ_c conj(C_jc) (Eᴴ shared_c)_j.
    shared_power : ndarray, shape (n_ch,)
        ‖(I − Q Qᴴ) shared_c‖² / dof: the part of each channel's residual power the shared error accounts for.
    """
    projected = np.einsum("kj,ckr->cjr", E.conj(), shared)  # (n_ch, n_theta, n_factors)
    scores = np.einsum("jc,cjr->jr", Cm.conj(), projected)
    off = shared - np.einsum("kb,cbr->ckr", Q, np.einsum("kb,ckr->cbr", Q.conj(), shared))
    shared_power = np.einsum("ckr,ckr->c", off, off.conj()).real / dof if dof > 0 else np.full(shared.shape[0], np.nan)
    return scores, shared_power


def relative_in_fit_units(relative_error: np.ndarray, response: np.ndarray, inverse_scale: np.ndarray,
                        weight: np.ndarray | None, whitening) -> np.ndarray:
    """The relative error's factor ``relative_error`` (n_factors, n_freq, one η = Pᵀ ξ for every channel; or
    (n_ch, n_factors, n_freq), each channel's own over one ξ) carried into each channel as the fit sees it: H_c η scaled by the channel's ``inverse_scale``, times the line ``weight``
    (n_freq, 1) and whitened as the data were; (n_ch, n_freq, n_factors). ``response`` (n_ch, n_freq) stands
    for H (its noise changes the term by its own relative size)."""
    rows = np.atleast_2d(np.asarray(response, complex)) * inverse_scale[:, None]
    factor = np.asarray(relative_error, complex)
    factor = factor.T[None, :, :] if factor.ndim == 2 else factor.transpose(0, 2, 1)  # (1 or n_ch, n_freq, r)
    shared = rows[:, :, None] * factor
    if weight is not None:
        shared = shared * weight[None, :, :]
    if whitening is not None:
        n_ch, n_freq, n_factors = shared.shape
        flat = whitening(np.ascontiguousarray(shared.transpose(1, 0, 2).reshape(n_freq, n_ch * n_factors)))
        shared = flat.reshape(n_freq, n_ch, n_factors).transpose(1, 0, 2)
    return shared
