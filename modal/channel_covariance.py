"""The poles' covariance of a least-squares fit to several channels that weighs them alike.

:func:`modal.nls.fit_modes` scales each channel to its peak and weighs the scaled
channels alike, not by their noise; its poles' covariance is then the sandwich of that
cost (:func:`channel_sandwich`), and the residual's lag covariance only widens it
(:func:`widened`). One channel keeps the Fisher information's inverse (the two agree there).
"""
from __future__ import annotations

import numpy as np

__all__ = ["channel_sandwich", "sandwich_product", "widened"]


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
    larger (the correlations kept). The residual's lag covariance (:func:`modal.nls._lag_covariance`) widens the errors
    where the lines correlate beyond the noise model, but it is biased low over the few lines near a peak that
    carry a pole: the fit leaves a residual orthogonal to its derivatives, so the lines' scores sum to zero and
    their lagged products cancel. Several channels: it only widens (on the multi-channel hammer cells of
    benchmarks/bench_chain.py it made z of fn spread 1.55 where the model alone gave 1.06)."""
    raise_by = np.sqrt(np.maximum(np.diag(measured), np.diag(model)) / np.diag(model))
    return model * np.outer(raise_by, raise_by)


def channel_sandwich(bread: np.ndarray, gram: np.ndarray, Cm: np.ndarray, noise_var: np.ndarray) -> np.ndarray:
    """Covariance of poles fitted by least squares that weighs every (scaled) channel alike while the channels'
    noise variances ``noise_var`` differ: B⁻¹ M B⁻¹ with ``bread`` B⁻¹ the inverse of the unweighted information
    2 Re(Eᴴ E ∘ C̄ Cᵀ) (:func:`modal.nls._pole_covariance`; ``gram`` Eᴴ E, ``Cm`` C) and M = 2 Re(Eᴴ E ∘ C̄ diag(σ²) Cᵀ) the
    covariance of that cost's gradient. Equal to the Fisher information's inverse where every σ² is equal; with
    unequal ones the Fisher inverse is the covariance of a fit weighing the channels by 1/σ², which this one is
    not (a channel twice as noisy as its scale says counts as much as a quiet one)."""
    meat = 2 * np.real(gram * ((Cm.conj() * noise_var) @ Cm.T))
    return sandwich_product(bread, meat)
