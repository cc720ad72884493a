"""The viscous mode model shared by every method, and the Cramér–Rao bound.

For an FRF of kind with power p (receptance 0, mobility 1, accelerance 2) a
mode r contributes ``A_r φ_r(ω)`` with

    φ_r(ω) = (iω)**p / (ω_r² − ω² + 2iζ_r ω_r ω)

and A_r the (complex) receptance modal constant. Fitting in the FRF's own kind
keeps the measurement noise white.
"""
from __future__ import annotations

import numpy as np

__all__ = ["mode_basis", "mode_basis_derivatives", "fisher_information", "cramer_rao_sdof", "solve_linear"]


def mode_basis(omega: np.ndarray, wn, zeta, power: int) -> np.ndarray:
    """φ_r(ω) for every mode: shape (n_modes, n_freq)."""
    wn = np.atleast_1d(wn)[:, None]
    zeta = np.atleast_1d(zeta)[:, None]
    denom = wn**2 - omega[None, :] ** 2 + 2j * zeta * wn * omega[None, :]
    return (1j * omega[None, :]) ** power / denom


def mode_basis_derivatives(omega: np.ndarray, wn, zeta, power: int):
    """∂φ_r/∂ω_r and ∂φ_r/∂ζ_r, each of shape (n_modes, n_freq)."""
    wn = np.atleast_1d(wn)[:, None]
    zeta = np.atleast_1d(zeta)[:, None]
    w = omega[None, :]
    denom = wn**2 - w**2 + 2j * zeta * wn * w
    num = (1j * w) ** power / denom**2
    return -num * (2 * wn + 2j * zeta * w), -num * (2j * wn * w)


def fisher_information(omega, wn, zeta, modal_constant, power: int, noise_std,
                       offset: bool = False) -> np.ndarray:
    """Fisher information of (ω_1, ζ_1, Re A_1, Im A_1, ω_2, …[, Re B, Im B]).

    Slepian–Bangs form for circular complex Gaussian noise with E|n|² = σ²:
    ``F = 2 Re(Jᴴ J) / σ²``.

    Parameters
    ----------
    omega : ndarray
        Lines used, rad/s.
    wn, zeta, modal_constant : array_like, one per mode
    power : int
        Kind power p.
    noise_std : float
        σ, in the unit of the FRF.
    offset : bool
        Append a complex constant offset (the estimator's residual term).
    """
    wn = np.atleast_1d(np.asarray(wn, float))
    zeta = np.atleast_1d(np.asarray(zeta, float))
    A = np.atleast_1d(np.asarray(modal_constant, complex))
    phi = mode_basis(omega, wn, zeta, power)
    d_wn, d_zeta = mode_basis_derivatives(omega, wn, zeta, power)
    cols = []
    for r in range(wn.size):
        cols += [A[r] * d_wn[r], A[r] * d_zeta[r], phi[r], 1j * phi[r]]
    if offset:
        one = np.ones_like(omega, dtype=complex)
        cols += [one, 1j * one]
    J = np.stack(cols, axis=1)
    return 2.0 * np.real(J.conj().T @ J) / noise_std**2


def cramer_rao_sdof(omega, wn, zeta, modal_constant, power, noise_std, offset=False):
    """Standard deviations bound (CRLB) of (ωn, ζ, Re A, Im A[, Re B, Im B]).

    Inverts the Fisher information after scaling its columns (ωn, ζ, |A|).
    """
    F = fisher_information(omega, wn, zeta, modal_constant, power, noise_std, offset)
    scale = np.sqrt(np.diag(F))
    cov = np.linalg.inv(F / np.outer(scale, scale)) / np.outer(scale, scale)
    return np.sqrt(np.diag(cov))


def solve_linear(design: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of ``design @ coef ≈ rhs`` with the columns scaled first.

    Mode columns (iω)^p/(ωr² − ω² + 2iζωrω) and offset columns of ones differ by
    ω^{2−p}: 1e16 at ω ≈ 1e8 rad/s in receptance, which is past the rank cut-off
    of an unscaled ``lstsq`` (the mode columns were dropped, and results depended
    on the frequency unit). Scaling every column to unit norm removes that.
    """
    norms = np.linalg.norm(design, axis=0)
    norms[norms == 0] = 1.0
    coef, *_ = np.linalg.lstsq(design / norms, rhs, rcond=None)
    return coef / (norms[:, None] if coef.ndim == 2 else norms)
