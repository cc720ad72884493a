"""Poly-reference least-squares complex frequency-domain estimator (pLSCF, "PolyMAX").

Right matrix-fraction model of the FRF matrix H (outputs × references) on the
z-domain basis Ω_j(ω) = z^j, z = e^{iωΔt}, Δt = π/ω_max::

    H_o(ω) = B_o(ω) A(ω)⁻¹,   A(ω) = Σ_{j=0}^{p} z^j α_j,   B_o(ω) = Σ_j z^j β_{o,j}

with real m × m matrices α_j (m references) and real 1 × m rows β_{o,j}.
Linearised equation error E_o = B_o − H_o A; the numerator coefficients are
eliminated per output, leaving the reduced normal equations

    M = Σ_o (T_o − S_oᵀ R⁻¹ S_o),   R = Re ΩᴴΩ,  S_o = −Re Ωᴴ(Ω ⊗ H_o),  T_o = Re (Ω ⊗ H_o)ᴴ(Ω ⊗ H_o)

(Guillaume et al., IMAC 2003; Peeters et al., Shock Vib. 11, 2004). All of
R, S, T are Toeplitz in the powers, so they are built from the sums
Σ_f z_f^d (·) for d = −p…p: one matrix product over the lines, whatever the
order, and every lower order is a sub-block. With α_p = I the denominator's
roots are the eigenvalues of the companion matrix; each gives a pole
s = ln(λ)/Δt and, from its eigenvector, the participation vector (m).

When the lines cover only part of the basis' half circle (``beyond`` > 1 leaves the arc between
the highest line and the Nyquist frequency empty; a band starting well above 0 Hz does the same
below), polynomials in z exist that nearly vanish on every line: R and the denominator block of M
then have eigenvalues falling geometrically with the order (real beam, 1–999 Hz, ``beyond`` 1.25:
cond R 1e3 at order 14, 2e9 at 38, 2e14 at 56; with 1.05: 2.6, 34, 370). Those directions are set by
the last bits of the arithmetic, not by the data: with 1.25 a relative perturbation of 1e-12 moved
poles by 10 % and changed a high order's count of physical poles from 8 to 21, so the caller keeps
``beyond`` small for a long sweep (:mod:`modal.global_.identify`). The numerator is eliminated with R's
pseudo-inverse, its directions below :data:`RANK_TOL` of the largest eigenvalue left out (numerator
polynomials zero on the lines to rounding: the projection onto the numerator's span does not need
them). The denominator block is solved as it stands: leaving out its small directions too (the
minimum-norm denominator) cost the geometric convergence on noise-free data (5e-8 instead of 2e-10 in
frequency at order 20), where those directions are the data's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import IdentificationError

__all__ = ["PolePack", "plscf_poles", "MAX_DAMPING"]

#: largest damping ratio of a pole taken as a mode (pLSCF's poles beyond it are dropped; a pole the joint
#: refinement widens beyond it is background, not a resonance)
MAX_DAMPING = 0.3
#: eigenvalues of R below this fraction of the largest are taken as zero (their directions are polynomials zero
#: on the lines to rounding): about 10⁴ times the eigenvalues' own rounding (n·ε·λ_max)
RANK_TOL = 1e-12


@dataclass(frozen=True)
class PolePack:
    """The physical poles of one model order.

    Attributes
    ----------
    order : int
        Polynomial order p (poles per order: p·m).
    omega_n : ndarray, shape (n,)
        Natural frequencies, rad/s.
    damping_ratio : ndarray, shape (n,)
    participation : ndarray, shape (n, m)
        Participation vectors (unit norm, largest component real positive).
    """

    order: int
    omega_n: np.ndarray
    damping_ratio: np.ndarray
    participation: np.ndarray


def _toeplitz_blocks(seq: np.ndarray, order: int) -> np.ndarray:
    """Matrix [seq(k − j)]_{j,k=0..order} from a sequence indexed d = −P…P (centre at P), trailing dims kept."""
    centre = (seq.shape[0] - 1) // 2
    j = np.arange(order + 1)
    return seq[centre + j[None, :] - j[:, None]]


def _pseudo_inverse_factor(matrix: np.ndarray) -> np.ndarray | None:
    """G with GᵀG the pseudo-inverse of a symmetric positive semi-definite ``matrix``, its eigenvalues below
    :data:`RANK_TOL` of the largest left out (see the module docstring); None when it has no positive one."""
    lam, vec = np.linalg.eigh(matrix)
    if not np.all(np.isfinite(lam)) or lam[-1] <= 0:
        return None
    keep = lam > RANK_TOL * lam[-1]
    return (vec[:, keep] / np.sqrt(lam[keep])).T


def plscf_poles(omega: np.ndarray, frf: np.ndarray, orders, max_damping: float = MAX_DAMPING,
                beyond: float = 1.0) -> list[PolePack]:
    """Poles of the pLSCF model for each order in ``orders``.

    Parameters
    ----------
    omega : ndarray, shape (n_lines,)
        Lines used, rad/s (increasing, > 0).
    frf : ndarray, shape (n_outputs, n_references, n_lines)
        FRF matrix on those lines, each output row scaled as the caller wants it weighted.
    orders : iterable of int
        Polynomial orders p to solve (each gives up to p·m poles).
    max_damping : float
        Poles with damping ratio outside (0, max_damping] are dropped.
    beyond : float
        Poles up to ``beyond`` times the highest line are kept (a mode just above the band
        is better modelled by its pole than by a residual term); the basis' Nyquist
        frequency is set there (Δt = π/(beyond·ω_max)). Poles below the lowest line are dropped.

    Returns
    -------
    list of PolePack
        One per order, physical poles only, sorted by frequency.
    """
    orders = sorted({int(p) for p in orders})
    if not orders or orders[0] < 1:
        raise IdentificationError(f"pLSCF orders must be positive integers, got {orders!r}")
    n_out, m, n_f = frf.shape
    p_max = orders[-1]
    if n_f <= p_max:
        raise IdentificationError(f"pLSCF order {p_max} needs more than {p_max} lines; the band holds {n_f}")
    w_max = float(omega.max()) * beyond
    dt = np.pi / w_max
    d = np.arange(-p_max, p_max + 1)
    zd = np.exp(1j * np.outer(d, omega * dt))  # (2P+1, n_f): z^d per line
    # sequences of the Toeplitz blocks: r(d) = Σ z^d, s_or(d) = Σ z^d H_or, t_o,rs(d) = Σ z^d conj(H_or) H_os
    r_seq = zd.sum(axis=1).real  # (2P+1,)
    h = frf.reshape(n_out * m, n_f)
    s_seq = (zd @ h.T).reshape(2 * p_max + 1, n_out, m)
    # only Σ_o T_o enters: sum the products over the outputs per line first (m² rows, not n_out·m²)
    hh = np.einsum("orf,osf->rsf", frf.conj(), frf).reshape(m * m, n_f)
    t_seq = (zd @ hh.T).reshape(2 * p_max + 1, m, m)

    packs = []
    for p in orders:
        n = p + 1
        R = _toeplitz_blocks(r_seq, p)  # (n, n) real
        # S_o[j, (k, r)] = −Re Σ conj(z^j) z^k H_or = −Re s_or(k − j)
        S = -_toeplitz_blocks(s_seq, p).real  # (n, n, n_out, m) [j, k, o, r]
        S = np.transpose(S, (0, 2, 1, 3)).reshape(n, n_out * n * m)  # (j, o·n·m + k·m + r)
        # T_o[(j, r), (k, s)] = Re Σ conj(z^j H_or) z^k H_os = Re t_o,rs(k − j)
        T = _toeplitz_blocks(t_seq, p).real  # (n, n, m, m) [j, k, r, s], already summed over the outputs
        T_sum = np.transpose(T, (0, 2, 1, 3)).reshape(n * m, n * m)  # rows (j, r), cols (k, s)
        # Σ_o S_oᵀ R⁺ S_o = Σ_o (G S_o)ᵀ(G S_o) with R⁺ = GᵀG: one matrix product over the rows (·, o) of
        # G S (BLAS; an einsum over the outputs was 7x slower)
        G = _pseudo_inverse_factor(R)
        if G is None:
            continue
        GS = (G @ S).reshape(-1, n * m)
        M = T_sum - GS.T @ GS
        # α_p = I: the first p·m rows give α_0..α_{p−1} = −M_aa⁺ M_ab
        k = p * m
        try:
            alpha = -np.linalg.solve(M[:k, :k], M[:k, k:])  # (p·m, m)
        except np.linalg.LinAlgError:
            continue
        # companion matrix of A(z) = Σ z^j α_j (α_p = I), for the right eigenvectors: block row −α_jᵀ
        comp = np.zeros((k, k))
        if p > 1:
            comp[m:, :-m] = np.eye(k - m)
        blocks = alpha.reshape(p, m, m)  # α_j
        comp[:m, :] = -np.hstack([blocks[j].T for j in range(p - 1, -1, -1)])
        lam, vec = np.linalg.eig(comp)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.log(lam) / dt
        wn = np.abs(s)
        zeta = -s.real / np.where(wn > 0, wn, np.nan)
        keep = (s.imag > 0) & np.isfinite(zeta) & (zeta > 0) & (zeta <= max_damping) \
            & (wn >= omega.min()) & (wn <= w_max)
        part = vec[:m, keep].T  # the top block of a companion eigenvector is the participation vector
        norm = np.linalg.norm(part, axis=1, keepdims=True)
        part = part / np.where(norm > 0, norm, 1.0)
        lead = np.take_along_axis(part, np.argmax(np.abs(part), axis=1)[:, None], axis=1)
        part = part * (np.abs(lead) / np.where(lead != 0, lead, 1.0))
        order_idx = np.argsort(wn[keep])
        packs.append(PolePack(p, wn[keep][order_idx], zeta[keep][order_idx], part[order_idx]))
    return packs
