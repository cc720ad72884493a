"""One-mode rational fit of a band: a pole in a few linear solves (a start for the least squares).

In a band around one mode the FRF of kind power p is, to the order that matters
for a start, ``H(ω) ≈ N(s) / D(s)`` with ``s = iω``, ``D(s) = s² + a1 s + a0``
(the pole: ``a0 = ωn²``, ``a1 = 2ζωn``) and ``N`` a complex quadratic: the mode's
``A s^p`` plus an offset times ``D``. Multiplying out, ``H D − N = 0`` is linear
in (a0, a1, N): Levy's fit. Its equations weigh each line by ``|D|``, which
favours the lines away from the peak; Sanathanan–Koerner passes (``SK_PASSES``)
divide that weight out again (each pass weighs the lines by ``1/|D|`` of the
previous pole), so the pole approaches the least-squares one. Every channel has its own
numerator and all share the denominator; the numerators are projected out, so
the pole comes from one 2×2 real system whatever the channel count.

This costs a few small QR factorisations instead of a half-power and a circle
fit with its own iterations: the least-squares refinement
(:func:`modal.nls.fit_modes`) starting here converges in the same few steps.
"""
from __future__ import annotations

import numpy as np

__all__ = ["rational_pole"]

#: Sanathanan–Koerner re-weighting passes after Levy's fit
SK_PASSES = 1
#: relative size (of squared norms) below which a column or the 2x2 system counts as rank-deficient:
#: rounding of the projection is ~1e-16 relative in norm, 1e-32 in square; a pole needs far more
RANK_TOL = 1e-20


def rational_pole(omega: np.ndarray, response: np.ndarray, noise_std=None,
                  passes: int = SK_PASSES) -> tuple[float, float] | None:
    """(ωn [rad/s], ζ) of the one mode a band holds, or None when the fit gives no stable pole.

    Parameters
    ----------
    omega : ndarray, shape (n_freq,)
        Lines of the band, rad/s (at least 4).
    response : ndarray, shape (n_channels, n_freq) or (n_freq,)
        FRF on those lines, any kind (the numerator's quadratic covers receptance,
        mobility and accelerance).
    noise_std : array_like, shape (n_channels,), optional
        Each channel's noise σ: channels are weighed by 1/σ (default: equally).
    passes : int
        Sanathanan–Koerner passes after Levy's fit.

    Returns
    -------
    (omega_n, damping_ratio) or None
        None when the denominator is not that of a damped oscillation
        (``a0 ≤ 0``, ``a1 ≤ 0`` or not finite) or the band has too few lines.
    """
    omega = np.asarray(omega, float)
    h = np.atleast_2d(np.asarray(response, complex))
    if omega.size < 4:
        return None
    if noise_std is not None:
        sigma = np.asarray(noise_std, float)
        h = h / np.where(sigma > 0, sigma, 1.0)[:, None]
    # frequencies scaled to the band's middle keep the columns 1, s, s² comparable
    w_ref = float(omega[omega.size // 2]) or float(np.max(np.abs(omega))) or 1.0
    s = 1j * omega / w_ref
    basis = np.stack([np.ones_like(s), s, s * s], axis=1)  # (n_freq, 3)
    # columns H·1, H·s and the right-hand side −H·s² of every channel side by side: (n_freq, 3 n_ch), so
    # that projecting out the numerators is two matrix products
    hs = h * s
    columns = np.concatenate([h, hs, -hs * s]).T
    n_ch = h.shape[0]
    weight = np.ones(omega.size)
    a0 = a1 = np.nan
    for _ in range(passes + 1):
        q, _r = np.linalg.qr(basis * weight[:, None])
        weighted = columns * weight[:, None]
        projected = weighted - q @ (q.conj().T @ weighted)
        # the 3x3 Gram matrix of the three kinds of column, summed over lines and channels
        kinds = projected.reshape(omega.size, 3, n_ch).transpose(1, 0, 2).reshape(3, -1)
        gram = np.real(kinds.conj() @ kinds.T)
        before = np.real(np.einsum("ij,ij->j", weighted.conj(), weighted)).reshape(3, n_ch).sum(axis=1)
        # a response the numerators alone explain (no pole: a constant, a slope) leaves only
        # rounding in the denominator's columns: no pole to report
        if not np.all(gram.diagonal()[:2] > RANK_TOL * before[:2]):
            return None
        # the 2x2 normal equations by Cramer's rule
        det = gram[0, 0] * gram[1, 1] - gram[0, 1] * gram[1, 0]
        if not det > RANK_TOL * gram[0, 0] * gram[1, 1]:
            return None
        with np.errstate(divide="ignore", invalid="ignore"):
            a0 = (gram[0, 2] * gram[1, 1] - gram[0, 1] * gram[1, 2]) / det
            a1 = (gram[0, 0] * gram[1, 2] - gram[1, 0] * gram[0, 2]) / det
        if not (np.isfinite(a0) and np.isfinite(a1) and a0 > 0):
            return None
        denominator = np.abs(a0 + a1 * s + s * s)
        if not np.all(denominator > 0):
            return None
        weight = 1.0 / denominator
    if not (a0 > 0 and a1 > 0):
        return None
    omega_n = float(np.sqrt(a0))
    return omega_n * w_ref, float(a1 / (2 * omega_n))
