"""The covariance of fitted parameters measured over the records an FRF was estimated from.

An H1 estimate's error is a sum over its records, Ĥ − H = Σ_i ψ_i (each record's influence,
:mod:`modal.estimate.record_influence`). A least-squares fit, linearised at its solution with the Jacobian J
of its (weighted, whitened: W) residual, moves its parameters by

    θ̂ − θ ≈ (JᵀJ)⁻¹ Σ_i s_i,   s_i = Jᵀ W ψ_i   (real-stacked, as the fit is),

so their covariance is measured over the records (the linearised block jackknife):

    V = (JᵀJ)⁻¹ [Σ_i s_i s_iᵀ + Σ_{d=1}^{D} w_d Σ_i (s_i s_{i+d}ᵀ + s_{i+d} s_iᵀ)] (JᵀJ)⁻¹,

D the records each record overlaps (their errors share samples), with Bartlett's weights w_d = 1 − d/(D + 1) (Newey
& West 1987), which keep the sum positive semi-definite: with full weights it was indefinite on some random records
(120 s, Hann, 50 % overlap: negative variances), and a sum with full weights scatters twice as much (its variance
goes as Σ_{|d|≤D} w_d²: 3 against 1.5 for D = 1). The weights leave out (1 − w_d) of a correlation between
neighbours: for half-overlapping Hann records, whose noise terms correlate by ρ² = 0.03, 3 % of the variance; a
rectangular window's, ρ² = 0.25, about a fifth. No lag window over the lines is needed: each s_i holds every line's
error of record i, so the correlation of every line with every other enters. The ψ_i are estimated from the
records' residuals, which sum to zero at every line; for scores uncorrelated beyond the lags that takes n − 1 − 2
Σ_d w_d (n − d)/n of n records' worth from the sum in expectation, which :func:`record_covariance` restores. Its
scatter is that of a variance from a few tens of records (10–20 % on a standard error).
"""
from __future__ import annotations

import numpy as np

__all__ = ["record_covariance", "projected_scores", "channel_scores", "channel_influence_in_fit_units", "misfit_ratio",
           "MIN_EFFECTIVE_RECORDS"]

#: the covariance is measured where the records leave at least this many (after the overlap's and the mean's
#: share, see the module; a standard error from 12 scatters by about 20 %) and outnumber the parameters (else
#: the sum of products is singular)
MIN_EFFECTIVE_RECORDS = 12


def projected_scores(derivatives: np.ndarray, coefficients: np.ndarray, influence: np.ndarray) -> np.ndarray:
    """Each record's score s_i = Jᵀ ψ_i of a variable-projection fit of one channel, (n_theta, n_records).

    Parameters
    ----------
    derivatives : ndarray, shape (n_freq, n_theta), complex
        E, the design's derivatives by the parameters projected off the design (the residual's Jacobian is
        −E_j c_j for parameter j).
    coefficients : ndarray, shape (n_theta,), complex
        c_j, the linear coefficient each derivative multiplies.
    influence : ndarray, shape (n_freq, n_records), complex
        Each record's ψ_i on the fit's lines, transformed as the fit's data are (weighted, whitened, scaled).

    Notes
    -----
    The real-stacked Jᵀδ of a complex perturbation δ is −Re(conj(c_j) E_jᴴ δ); the sign cancels in the
    covariance.
    """
    return np.real(np.conj(coefficients)[:, None] * (derivatives.conj().T @ influence))


def channel_scores(derivatives: np.ndarray, coefficients: np.ndarray, influence: np.ndarray) -> np.ndarray:
    """Each record's score s_i = Σ_c Jᵀ ψ_ic of a variable-projection fit of several channels that weighs them
    alike (the sum of :func:`projected_scores` over the channels), (n_theta, n_records).

    ``coefficients`` (n_theta, n_channels); ``influence`` (n_freq, n_channels, n_records), each channel's ψ_i
    transformed as its data (:func:`channel_influence_in_fit_units`).
    """
    projected = np.einsum("kj,kcr->jcr", derivatives.conj(), influence)  # (n_theta, n_ch, n_records)
    return np.real(np.einsum("jc,jcr->jr", np.conj(coefficients), projected))


def channel_influence_in_fit_units(influence: np.ndarray, inverse_scale: np.ndarray, weight: np.ndarray | None,
                                   whitening) -> np.ndarray:
    """Several channels' records' influences (n_channels, n_records, n_freq), FRF unit, as the fit sees its
    data: each channel over its scale (``inverse_scale``), times the line ``weight`` (n_freq, 1), whitened;
    (n_freq, n_channels, n_records)."""
    out = np.asarray(influence, complex).transpose(2, 0, 1) * inverse_scale[None, :, None]
    if weight is not None:
        out = out * weight[:, :, None]
    if whitening is not None:
        n_freq, n_ch, n_records = out.shape
        out = whitening(np.ascontiguousarray(out.reshape(n_freq, n_ch * n_records))).reshape(n_freq, n_ch, n_records)
    return out


def record_covariance(information: np.ndarray, scores: np.ndarray, overlapping: int = 0) -> np.ndarray | None:
    """V = A M A (see the module), A = ``information``⁻¹, M the scores' weighted sum of products over the records.

    Parameters
    ----------
    information : ndarray, shape (n_theta, n_theta)
        JᵀJ of the fit (real, symmetric positive definite).
    scores : ndarray, shape (n_theta, n_records)
        s_i, in the records' order.
    overlapping : int
        D, the following records each record overlaps (the lags of the sum).

    Returns
    -------
    ndarray, shape (n_theta, n_theta), or None where it cannot be measured: too few records
    (:data:`MIN_EFFECTIVE_RECORDS`), not finite, or not positive definite (the fit's own covariance serves).
    """
    n_theta, n = scores.shape
    weights = 1.0 - np.arange(1, overlapping + 1) / (overlapping + 1.0)
    effective = n - 1 - 2 * sum(w * (n - d) / n for d, w in enumerate(weights, start=1))
    if effective < MIN_EFFECTIVE_RECORDS or n - 1 < n_theta or not np.all(np.isfinite(scores)):
        return None
    products = scores @ scores.T
    for d, w in enumerate(weights, start=1):
        cross = scores[:, :-d] @ scores[:, d:].T
        products += w * (cross + cross.T)
    products *= n / effective
    scale = np.sqrt(np.abs(np.diag(information)))
    if not (np.all(np.isfinite(information)) and np.all(scale > 0)):
        return None
    try:
        inverse = np.linalg.inv(information / np.outer(scale, scale)) / np.outer(scale, scale)
    except np.linalg.LinAlgError:
        return None
    covariance = inverse @ products @ inverse
    covariance = (covariance + covariance.T) / 2
    if not np.all(np.isfinite(covariance)):
        return None
    spread = np.sqrt(np.abs(np.diag(covariance)))
    if not np.all(spread > 0):
        return None
    if np.linalg.eigvalsh(covariance / np.outer(spread, spread))[0] <= 0:
        return None
    return covariance


def _weighted_sum(gram: np.ndarray, overlapping: int) -> float:
    """Σ_i G_ii + Σ_d w_d Σ_i 2 Re G_i,i+d with Bartlett's weights, times n over the records' worth (as
    :func:`record_covariance` sums), for a Gram matrix G of the records' terms."""
    n = gram.shape[0]
    weights = 1.0 - np.arange(1, overlapping + 1) / (overlapping + 1.0)
    effective = n - 1 - 2 * sum(w * (n - d) / n for d, w in enumerate(weights, start=1))
    total = float(np.trace(gram).real)
    for d, w in enumerate(weights, start=1):
        total += 2 * w * float(np.trace(gram, offset=d).real)
    return total * n / effective if effective > 0 else np.nan


def misfit_ratio(residual_power: float, residual_influence: np.ndarray, overlapping: int = 0) -> float:
    """The fit's residual power over what the records' errors account for of it.

    The records measure the random error only: a misfit of the model (the wrong kind of FRF, a mode or a
    background left out) is the same in every record and stays out of their sum, though it moves the
    parameters as well. The Fisher information takes the misfit in through the residual's level; the records'
    covariance is multiplied by this ratio where it exceeds 1 (the residual holds more than the records' errors).

    Parameters
    ----------
    residual_power : float
        ‖r‖², the fit's residual sum of squares (in the fit's units, weighted and whitened as it is).
    residual_influence : ndarray, shape (n_freq, n_records)
        The records' ψ_i in the same units, projected off the design (the part of them the residual keeps).
    overlapping : int
        As for :func:`record_covariance`.
    """
    expected = _weighted_sum(residual_influence.conj().T @ residual_influence, overlapping)
    return residual_power / expected if expected > 0 else np.nan
