"""The correlation of an H1 estimate's errors between neighbouring lines, measured over its records.

The window's model of the correlation (:mod:`modal.noise_model`: the response noise's window correlation
times the excitation's own) holds where the error is measurement noise. Near a lightly damped resonance
of a continuous random record most of the error is leakage instead: each record's response holds the
tail of the excitation before it and lacks the response to its own last samples, an error that follows
the slope of H across the lines and correlates quite differently. Measured over 100 records of 120 s
(Hann, 8192-sample segments, ζ 2 % and 1.2 %), the errors of neighbouring lines at the two peaks
correlate by −0.00 and −0.12 where the window's model says +0.44, and by −0.09 and −0.13 two lines
apart (model +0.03); away from the peaks the model holds (+0.45 against +0.44). Whitened with the
model, the errors at the peaks keep a lag-one correlation of −0.3 to −0.4.

The estimate knows its own errors record by record: the residual of record i at line k is
R_ik = Y_ik − Ĥ_k X_ik, and Ĥ's error is Σ_i R_ik conj(X_ik) / S_xx,k, so the covariance of the errors
of lines k and k + m is estimated by

    C_km = Σ_i (R_ik conj(X_ik)) conj(R_i,k+m conj(X_i,k+m)) / (S_xx,k S_xx,k+m),

the same estimate as each line's variance (m = 0) carried to its neighbours, and their correlation is
C_km / √(C_kk C_k+m,k+m). With n records it scatters by about 1/√n per line; it is averaged over
neighbouring lines (:data:`SMOOTHING_RECORDS` record-lines at least) before use.
"""
from __future__ import annotations

import numpy as np

from ..noise_model import MEASURED_CORRELATION_RECORDS

__all__ = ["measured_line_correlation", "MIN_RECORDS", "LEAKAGE_LAGS", "SMOOTHING_RECORDS"]

#: the correlation is measured from at least this many records
MIN_RECORDS = MEASURED_CORRELATION_RECORDS
#: lags measured at least (the leakage's correlation reaches beyond a Hann window's two lags; measured
#: above, the third and later are within ±0.02)
LEAKAGE_LAGS = 4
#: the products are averaged over neighbouring lines until they rest on this many record-lines (±0.07 on
#: a correlation near 0), over at most :data:`MAX_SMOOTHING_LINES` lines
SMOOTHING_RECORDS = 200
MAX_SMOOTHING_LINES = 15


def _box(values: np.ndarray, lines: int) -> np.ndarray:
    """Mean over ``lines`` (odd) neighbouring lines along the last axis, fewer at the ends."""
    if lines <= 1:
        return values
    half = lines // 2
    n = values.shape[-1]
    total = np.concatenate([np.zeros(values.shape[:-1] + (1,), values.dtype), np.cumsum(values, axis=-1)], axis=-1)
    index = np.arange(n)
    lo, hi = np.clip(index - half, 0, n), np.clip(index + half + 1, 0, n)
    return (total[..., hi] - total[..., lo]) / (hi - lo)


def measured_line_correlation(products: np.ndarray, frf: np.ndarray, n_records: int) -> np.ndarray | None:
    """Correlation of the errors of line k and k + m (row m − 1), measured over the records (see the module).

    Parameters
    ----------
    products : ndarray, shape (4, n_lags + 1, n_lines)
        :attr:`modal.estimate.spectra.SpectralSums.error_products`.
    frf : ndarray, shape (n_lines,)
        The H1 estimate.
    n_records : int
        Records summed.

    Returns
    -------
    ndarray, shape (n_lags, n_lines), complex, or None
        Zero past the last line; None with fewer than :data:`MIN_RECORDS` records or where the errors'
        variance is not positive on every line.
    """
    if n_records < MIN_RECORDS:
        return None
    n_lags = products.shape[1] - 1
    n_lines = frf.size
    lines = min(MAX_SMOOTHING_LINES, int(np.ceil(SMOOTHING_RECORDS / n_records)) | 1)
    covariance = np.zeros((n_lags + 1, n_lines), complex)
    h = np.asarray(frf, complex)
    for m in range(n_lags + 1):
        end = n_lines - m
        left, right = h[:end], h[m:].conj()
        covariance[m, :end] = (products[0, m, :end] - right * products[1, m, :end] - left * products[2, m, :end]
                               + left * right * products[3, m, :end])
    variance = covariance[0].real.copy()
    if not (np.all(np.isfinite(variance)) and np.all(variance > 0)):
        return None
    variance = _box(variance, lines)
    correlation = np.zeros((n_lags, n_lines), complex)
    for m in range(1, n_lags + 1):
        end = n_lines - m
        # the sums of each lag over the same lines, so the smoothing keeps a correlation within ±1
        smoothed = _box(covariance[m, :end], lines)
        correlation[m - 1, :end] = smoothed / np.sqrt(variance[:end] * variance[m:])
    magnitude = np.abs(correlation)
    return np.where(magnitude > 1, correlation / np.maximum(magnitude, 1e-300), correlation)
