"""Whitening of FRF errors correlated between neighbouring lines (a windowed, overlapped estimate's),
for the generalised least-squares fits of :mod:`modal.nls`."""
from __future__ import annotations

import numpy as np

__all__ = ["LineWhitening", "CORRELATION_RIDGE"]


#: a line correlation matrix that is not positive definite even when tapered (a correlation carried over a few
#: lags only, or measured from few records) is blended towards the identity, (R + εI)/(1 + ε), ε from this up
CORRELATION_RIDGE = 0.01


class LineWhitening:
    """Whitening of errors correlated between neighbouring lines: W = L⁻¹ for the banded Cholesky factor L
    of their correlation matrix R = L Lᴴ (W R Wᴴ = I); ``whitening(X)`` is W X for X (n_lines, k).

    Parameters
    ----------
    band : ndarray, shape (bandwidth + 1, n_lines)
        R in LAPACK's lower banded storage, ``band[d, j] = R[j + d, j]``
        (:meth:`modal.noise_model.NoiseModel.correlation_band`).
    """

    def __init__(self, band: np.ndarray):
        from scipy.linalg import cholesky_banded

        nonzero = np.flatnonzero(np.any(np.abs(band[1:]) > 0, axis=1))
        bandwidth = int(nonzero[-1]) + 1 if nonzero.size else 0
        band = np.asarray(band[:bandwidth + 1], complex)
        # the correlation as carried comes first: where it holds every lag between the lines (a band narrower
        # than the lags carried) it is the errors' own, and the whitened errors are white with the lines'
        # variance (a taper there is an error of its own: on an exponential window's correlation, ~1/m over 40
        # lines, it leaves them at 0.76 of that variance with a lag-1 correlation of 0.17). A
        # correlation cut off after fewer lags than the lines span may be indefinite: then it is tapered
        # (1 − d/(b + 1), which keeps a stationary correlation positive definite), and blended towards the
        # identity if need be
        taper = 1.0 - np.arange(bandwidth + 1)[:, None] / (bandwidth + 1.0)
        attempts = [(band, 0.0), (band * taper, 0.0)]
        attempts += [(band * taper, CORRELATION_RIDGE * 4.0**k) for k in range(8)]
        for trial, ridge in attempts:
            try:
                shifted = trial.copy()
                shifted[0] += ridge
                self._factor = cholesky_banded(shifted / (1.0 + ridge), lower=True, check_finite=False)
                break
            except np.linalg.LinAlgError:
                continue
        else:
            raise np.linalg.LinAlgError("the lines' correlation matrix is far from positive definite")
        self.bandwidth = bandwidth
        self.ridge = ridge
        self._lu = None  # LAPACK's band LU of the factor, formed at the first whitening

    def __call__(self, values: np.ndarray) -> np.ndarray:
        if self.bandwidth == 0:
            return values / self._factor[0][:, None] if values.ndim == 2 else values / self._factor[0]
        if self._factor.shape[1] == 1:  # one line: scipy's solve_banded divides by the diagonal
            from scipy.linalg import solve_banded

            return solve_banded((self.bandwidth, 0), self._factor, values)
        # solve_banded (LAPACK gbsv) factors the band afresh on every call; gbsv is gbtrf then gbtrs, so the
        # factorisation is kept and gbtrs alone solves each call: the same numbers, without the refactoring
        from scipy.linalg import get_lapack_funcs

        values = np.asarray_chkfinite(values)  # as solve_banded checks its right-hand side
        gbtrf, gbtrs = get_lapack_funcs(("gbtrf", "gbtrs"), (self._factor, values))
        if self._lu is None or self._lu[0].dtype != gbtrf.dtype:
            stored = np.zeros((2 * self.bandwidth + 1, self._factor.shape[1]), dtype=gbtrf.dtype)
            stored[self.bandwidth:] = self._factor
            lu, pivots, info = gbtrf(stored, self.bandwidth, 0, overwrite_ab=True)
            self._lu = (lu, pivots, info)
        lu, pivots, info = self._lu
        if info > 0:
            raise np.linalg.LinAlgError("singular matrix")
        solved, info = gbtrs(lu, self.bandwidth, 0, values.reshape(values.shape[0], -1), pivots)
        if info != 0:
            raise ValueError(f"illegal value in {-info}-th argument of internal gbtrs")
        return solved.reshape(values.shape)
