"""First-order deviations of the pLSCF poles of output half-spectra, for many deviations of the half-spectra at once.

The poles of polynomial order p are the eigenvalues of the companion matrix of the right matrix-fraction
denominator (:func:`modal.global_.plscf.plscf_poles`). Its coefficients solve the reduced normal equations
``M α = 0`` (α_p = I), ``M = T − Σ_o S_oᵀ R⁻¹ S_o``, where ``R`` does not depend on the data, ``S_o`` is linear
and ``T`` quadratic in the half-spectra. A deviation ``ΔS`` of the half-spectra moves them to first order by

    ΔM = ΔT − (X + Xᵀ),  X = Σ_o ΔS_oᵀ R⁻¹ S_o,  Δα = −M_aa⁻¹ (ΔM_ab + ΔM_aa α),

which changes only the companion matrix's first block row; each eigenvalue μ then moves by
``Δμ = wᴴ ΔC v / wᴴ v`` (right and left eigenvectors v, w) and each pole s = ln(μ)/Δt by Δμ/(μ Δt). The
Toeplitz sequences of ``R``, ``S`` and ``T`` are summed over the lines once for the highest order (every lower
order uses a sub-block), and once per deviation for their changes: one matrix product for all deviations.
This is the exact linearisation of the estimator, where recomputing the poles from the moved half-spectra
(central differences) costs two eigenvalue problems per deviation and order.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import eig

__all__ = ["PlscfPerturbation"]


def _toeplitz(seq: np.ndarray, order: int, centre: int) -> np.ndarray:
    """[seq(k − j)]_{j,k = 0…order} of a sequence indexed d = −centre…centre along axis 0 (trailing dims kept)."""
    j = np.arange(order + 1)
    return seq[centre + j[None, :] - j[:, None]]


class PlscfPerturbation:
    """Poles of any polynomial order with their first-order deviations for a set of half-spectrum deviations.

    Parameters
    ----------
    omega : ndarray, shape (n_lines,)
        Lines, rad/s, as given to :func:`modal.global_.plscf.plscf_poles` (``beyond`` = 1: the basis' Nyquist
        frequency is the highest line).
    S : ndarray, shape (n_outputs, n_references, n_lines)
        Half-spectra.
    dS : ndarray, shape (n_deviations, n_outputs, n_references, n_lines)
        Deviations of the half-spectra (e.g. each block's, scaled).
    max_order : int
        The highest polynomial order asked for.
    """

    def __init__(self, omega: np.ndarray, S: np.ndarray, dS: np.ndarray, max_order: int):
        self.n_out, self.m, n_f = S.shape
        self.n_dev = dS.shape[0]
        self.P = int(max_order)
        self.dt = np.pi / float(omega.max())
        d = np.arange(-self.P, self.P + 1)
        zd = np.exp(1j * np.outer(d, omega * self.dt))  # (2P+1, lines)
        m, n_out = self.m, self.n_out
        self.r_seq = zd.sum(axis=1).real
        self.s_seq = (zd @ S.reshape(n_out * m, n_f).T).reshape(2 * self.P + 1, n_out, m)
        hh = np.einsum("orf,osf->rsf", S.conj(), S).reshape(m * m, n_f)
        self.t_seq = (zd @ hh.T).reshape(2 * self.P + 1, m, m)
        # changes: Δs (linear), Δt = Σ_o conj(ΔH) H + conj(H) ΔH
        flat_dS = np.moveaxis(dS.reshape(self.n_dev, n_out * m, n_f), 2, 1)  # (dev, lines, o·r)
        self.ds_seq = (zd @ flat_dS).reshape(self.n_dev, 2 * self.P + 1, n_out, m)
        dhh = np.einsum("borf,osf->brsf", dS.conj(), S) + np.einsum("orf,bosf->brsf", S.conj(), dS)
        self.dt_seq = (zd @ np.moveaxis(dhh.reshape(self.n_dev, m * m, n_f), 2, 1)).reshape(
            self.n_dev, 2 * self.P + 1, m, m)

    def _normal_matrices(self, order: int):
        """(M, ΔM per deviation) of one order."""
        p, m, n_out, P = order, self.m, self.n_out, self.P
        n = p + 1
        R = _toeplitz(self.r_seq, p, P)
        S = -_toeplitz(self.s_seq, p, P).real  # (n, n, o, m) [j, k, o, r]
        S = np.moveaxis(S, 2, 0).reshape(n_out, n, n * m)  # (o, j, k·m + r)
        T = np.transpose(_toeplitz(self.t_seq, p, P).real, (0, 2, 1, 3)).reshape(n * m, n * m)
        RinvS = np.linalg.solve(R, np.moveaxis(S, 0, 1).reshape(n, n_out * n * m)).reshape(n, n_out, n * m)
        RinvS = np.moveaxis(RinvS, 1, 0).reshape(n_out * n, n * m)  # rows (o, j)
        M = T - S.reshape(n_out * n, n * m).T @ RinvS
        dS = -np.moveaxis(_toeplitz(np.moveaxis(self.ds_seq, 0, -1), p, P).real, -1, 0)  # (dev, j, k, o, r)
        dS = np.moveaxis(dS, 3, 1).reshape(self.n_dev, n_out * n, n * m)  # rows (o, j), cols (k, r)
        dT = np.moveaxis(_toeplitz(np.moveaxis(self.dt_seq, 0, -1), p, P).real, -1, 0)  # (dev, j, k, r, s)
        dT = np.transpose(dT, (0, 1, 3, 2, 4)).reshape(self.n_dev, n * m, n * m)
        X = np.swapaxes(dS, 1, 2) @ RinvS  # (dev, n·m, n·m)
        return M, dT - X - np.swapaxes(X, 1, 2)

    def at(self, order: int):
        """All eigenvalues of the order's companion matrix as continuous poles s (rad/s, before any window
        correction), and their deviations (n_deviations, n_poles)."""
        p, m = order, self.m
        M, dM = self._normal_matrices(order)
        k = p * m
        Maa = M[:k, :k]
        alpha = -np.linalg.solve(Maa, M[:k, k:])  # (p·m, m)
        d_alpha = -np.linalg.solve(Maa[None], dM[:, :k, k:] + dM[:, :k, :k] @ alpha[None])  # (dev, p·m, m)
        comp = np.zeros((k, k))
        if p > 1:
            comp[m:, :-m] = np.eye(k - m)
        # first block row: −[α_{p−1}ᵀ … α_0ᵀ]
        comp[:m, :] = -alpha.reshape(p, m, m)[::-1].transpose(0, 2, 1).transpose(1, 0, 2).reshape(m, k)
        d_top = -d_alpha.reshape(self.n_dev, p, m, m)[:, ::-1].transpose(0, 3, 1, 2).reshape(self.n_dev, m, k)
        mu, left, right = eig(comp, left=True, right=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.log(mu.astype(complex)) / self.dt
            norm = np.einsum("ij,ij->j", left.conj(), right)  # wᴴ v per eigenvalue
            d_mu = np.einsum("ai,bak,ki->bi", left[:m].conj(), d_top, right) / norm[None, :]
            d_s = d_mu / (mu[None, :] * self.dt)
        return s, d_s
