"""Covariance-driven stochastic subspace identification (SSI-cov) over a sweep of model orders, with
first-order error bars.

The correlations ``R_k = C A^{k−1} G`` of the outputs with the references fill a block Hankel
matrix ``H = O Γ`` (``s + 1`` block rows of lags 1…2s): its leading left singular vectors span the
observability matrix O, whose shift invariance ``O_down = O_up A`` gives the system matrix A of any
order ``n`` by least squares. One SVD serves every order, and so does one QR: the first ``n``
columns of ``U_up`` are ``Q[:, :n] R[:n, :n]`` for the QR of all its columns, so that
``A_n = R[:n, :n]⁻¹ (Qᵀ U_down)[:n, :n]`` costs an n × n solve per order. Lag 0, where white
measurement noise lives, is not used.

Error bars (Reynders, Pintelon & De Roeck 2008; Döhler & Mevel 2013): the record is cut into
blocks whose Hankel matrices scatter about the record's; each block's deviation is carried to
first order through the SVD (only the part leaving the signal subspace changes the eigenvalues),
the least squares and the eigenvalue problem. The covariance of any result is the sample
covariance of these linear images over the blocks.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import IdentificationError

__all__ = ["SubspaceModel", "PoleSet", "subspace_model", "hankel", "poles_at", "Perturbation", "continuous"]


@dataclass(frozen=True)
class PoleSet:
    """The poles of one model order.

    Attributes
    ----------
    order : int
        Model order (states).
    poles : ndarray, shape (n,)
        Continuous-time poles λ, rad/s (all eigenvalues of the order, conjugates included).
    shapes : ndarray, shape (n_outputs, n), complex
        Observed shape of each pole, largest-magnitude entry 1.
    participation : ndarray, shape (n_references, n) or None
        The reference side of each pole (for the stability check of methods without shapes).
    """

    order: int
    poles: np.ndarray
    shapes: np.ndarray
    participation: np.ndarray | None = None


@dataclass(frozen=True)
class SubspaceModel:
    """The SVD of the Hankel matrix and the QR of its upper block rows, for every order up to ``max_order``."""

    U: np.ndarray
    singular_values: np.ndarray
    V: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    QtU_down: np.ndarray
    n_outputs: int
    block_rows: int
    sample_rate_hz: float
    max_order: int
    hankel: np.ndarray
    block_cols: int | None = None


def hankel(R: np.ndarray, block_rows: int, block_cols: int | None = None) -> np.ndarray:
    """Block Hankel matrix of lags 1…p+q: block (a, b) = R[a + b + 1], a = 0…p, b = 0…q−1, with p
    ``block_rows`` and q ``block_cols`` (default p).

    ``R`` has shape (..., lags, n_outputs, n_references); the result (..., n_outputs (p+1), n_references q).
    """
    p = block_rows
    q = block_rows if block_cols is None else block_cols
    # a view (..., p+1, l, r, q) of lags a+1…a+q for block row a, put in order and copied once by the reshape
    windows = np.lib.stride_tricks.sliding_window_view(R[..., 1:p + q + 1, :, :], q, axis=-3)
    lead = R.shape[:-3]
    l, r = R.shape[-2:]
    return np.swapaxes(windows, -2, -1).reshape(*lead, (p + 1) * l, q * r)


def subspace_model(R: np.ndarray, block_rows: int, max_order: int, sample_rate_hz: float,
                   block_cols: int | None = None) -> SubspaceModel:
    """SVD of the Hankel matrix of ``R`` (lags, outputs, references) and the QR its orders share (block rows
    of the outputs ``block_rows``, of the references ``block_cols``, default the same)."""
    l = R.shape[1]
    H = hankel(R, block_rows, block_cols)
    p, q = H.shape
    max_order = int(min(max_order, q, l * block_rows))
    if max_order < 2:
        raise IdentificationError(f"the Hankel matrix ({p} × {q}) supports no model order above 1")
    U, sv, Vt = np.linalg.svd(H, full_matrices=False)
    Q, Rr = np.linalg.qr(U[: l * block_rows, :max_order])
    return SubspaceModel(U, sv, Vt.T, Q, Rr, Q.T @ U[l:, :max_order], l, block_rows, float(sample_rate_hz),
                         max_order, H, block_cols)


def continuous(mu: np.ndarray, sample_rate_hz: float) -> np.ndarray:
    """Continuous poles λ = ln(μ)·fs of discrete eigenvalues μ."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.log(mu.astype(complex)) * sample_rate_hz


def _system(model: SubspaceModel, order: int):
    """(A, eigenvalues μ, right eigenvectors Ψ) of one order, in the basis of the first ``order`` left singular
    vectors."""
    n = order
    A = np.linalg.solve(model.R[:n, :n], model.QtU_down[:n, :n])
    mu, psi = np.linalg.eig(A)
    return A, mu, psi


def _normalised(shapes: np.ndarray):
    """Shapes (columns) scaled so that the largest-magnitude entry is 1; returns (shapes, lead index, lead value)."""
    lead = np.argmax(np.abs(shapes), axis=0)
    value = shapes[lead, np.arange(shapes.shape[1])]
    value = np.where(value != 0, value, 1.0)
    return shapes / value[None, :], lead, value


def poles_at(model: SubspaceModel, order: int) -> PoleSet:
    """All poles and observed shapes of one order."""
    _, mu, psi = _system(model, order)
    shapes, _, _ = _normalised(model.U[: model.n_outputs, :order] @ psi)
    return PoleSet(order, continuous(mu, model.sample_rate_hz), shapes)


class Perturbation:
    """First-order deviations of the poles and shapes of any order, one per block of the record.

    The block Hankel deviations enter only through ``ΔH V`` and ``Uᵀ ΔH V``, computed once for all orders;
    each order then costs products of the size of its subspace.

    Parameters
    ----------
    model : SubspaceModel
        Built from the weighted mean of ``block_R``.
    block_R : ndarray, shape (n_blocks, lags, n_outputs, n_references)
        Each block's correlations.
    weights : ndarray, shape (n_blocks,)
        Samples per block.
    """

    def __init__(self, model: SubspaceModel, block_R: np.ndarray, weights: np.ndarray, max_order: int | None = None):
        self.model = model
        n_blocks = block_R.shape[0]
        if n_blocks < 2:
            raise IdentificationError("error bars need at least 2 blocks of the record")
        w = weights / weights.sum()
        self.scale = w * np.sqrt(n_blocks / (n_blocks - 1.0))  # var of the weighted mean from the blocks' scatter
        top = int(min(max_order or model.max_order, model.max_order))
        self.top = top
        # the deviations are formed in double precision and carried through these products in single: their
        # rounding (1e-7 of the deviations) lies far below the deviations' own scatter, which is what they measure
        U, V = model.U.astype(np.float32), model.V.astype(np.float32)
        # ΔH is the Hankel matrix of the correlations' deviations (it is linear in them), built in single
        # precision from deviations formed in double
        d_R = (block_R - np.tensordot(w, block_R, axes=1)[None]).astype(np.float32)
        dH = hankel(d_R, model.block_rows, model.block_cols)
        G = dH @ V[:, :top]  # (blocks, p, top): ΔH V₁ for every order up to top
        B_right = np.swapaxes(U.T @ G, 1, 2)  # (blocks, top, k): (Uᵀ ΔH V₁)ᵀ
        self.B_right = B_right  # kept in single precision, as are the products of each order with it
        E = G - U @ np.swapaxes(B_right, 1, 2)  # the part of ΔH V₁ outside the range of H
        self.B_left = (np.swapaxes(U[:, :top], 0, 1) @ dH) @ V  # (blocks, top, k): U₁ᵀ ΔH V
        # E enters every order only through its first l rows and these projections, whose leading n × n
        # blocks are those of order n: formed once for all orders
        l, rows = model.n_outputs, model.n_outputs * model.block_rows
        Q = model.Q[:, :top].astype(np.float32)
        E_up, E_down = E[:, :rows], E[:, l:]
        self.E_C = E[:, :l].astype(float)  # (blocks, l, top)
        self.QtE_down = (Q.T @ E_down).astype(float)  # (blocks, top, top): Qᵀ E_down
        self.QtE_up = (Q.T @ E_up).astype(float)
        E_up_t = np.swapaxes(E_up, 1, 2)
        self.EtU_down = (E_up_t @ U[l:, :top]).astype(float)  # E_upᵀ U_down
        self.EtU_up = (E_up_t @ U[:rows, :top]).astype(float)  # E_upᵀ U_up

    def at(self, order: int, indices) -> dict[str, np.ndarray]:
        """Deviations of the poles ``indices`` of :func:`poles_at` (``order``).

        Returns
        -------
        dict
            ``"pole"`` (n_blocks, n_poles) complex, rad/s; ``"shape"`` (n_blocks, n_outputs, n_poles) complex,
            of the shapes normalised as in :func:`poles_at`. For any real function g of the results,
            var g ≈ Σ_b (∂g · δ_b)² over these samples δ_b.
        """
        model = self.model
        idx = np.asarray(indices, int)
        n, l = order, model.n_outputs
        if n > self.top:
            raise IdentificationError(f"perturbations were prepared up to order {self.top}, not {n}")
        U, sv = model.U, model.singular_values
        s1, s2 = sv[:n], sv[n:]
        # U₂ᵀ ΔH V₁ and (U₁ᵀ ΔH V₂)ᵀ, each (blocks, k − n, n)
        left = np.swapaxes(self.B_right[:, :n, n:], 1, 2)
        right = np.swapaxes(self.B_left[:, :n, n:], 1, 2)
        single = np.float32
        with np.errstate(divide="ignore", invalid="ignore"):
            # the gaps in double precision (close singular values), the rest in single, as the deviations
            inverse_gap = (1.0 / (s1[None, :] ** 2 - s2[:, None] ** 2)).astype(single)  # (k − n, n)
            inside = (left * s1[None, None, :].astype(single) + s2[None, :, None].astype(single) * right) \
                * inverse_gap
        inside = np.where(np.isfinite(inside), inside, single(0.0))
        # each perturbed singular vector's part outside the signal subspace, ΔU₁ = U₂ inside + E/σ₁ (the
        # part inside only rotates the basis, which leaves the eigenvalues and the observed shapes as they
        # are). ΔU₁ enters only projected: Qᵀ ΔO_down, Qᵀ ΔO_up, ΔO_upᵀ (O_down − O_up A) and its first l
        # rows (ΔC), so U₂ is projected once per order rather than ΔU₁ formed per block
        # (outside = E₁/σ₁, its products taken from the projections formed once for all orders)
        A, mu, psi = _system(model, order)
        Rn, Qn = model.R[:n, :n], model.Q[:, :n]
        rows = l * model.block_rows
        U1, U2 = U[:, :n], U[:, n:]
        resid = U1[l:] - U1[:rows] @ A
        per_column = s1[None, None, :]
        # the products with `inside` (blocks × (k − n) × n each) in single precision, their sums in double
        q_down = (Qn.T @ U2[l:]).astype(single) @ inside + self.QtE_down[:, :n, :n] / per_column  # Qᵀ ΔO_down
        q_up = (Qn.T @ U2[:rows]).astype(single) @ inside + self.QtE_up[:, :n, :n] / per_column  # Qᵀ ΔO_up
        up_resid = np.swapaxes(inside, 1, 2) @ (U2[:rows].T @ resid).astype(single) \
            + (self.EtU_down[:, :n, :n] - self.EtU_up[:, :n, :n] @ A) / s1[None, :, None]  # ΔO_upᵀ (O_down − O_up A)
        d_C = U2[:l].astype(single) @ inside + self.E_C[:, :, :n] / per_column  # (blocks, l, n)
        # ΔA = R⁻¹ [Qᵀ (ΔO_down − ΔO_up A) + R⁻ᵀ ΔO_upᵀ (O_down − O_up A)], R upper triangular: two
        # triangular solves for all blocks at once
        from scipy.linalg import solve_triangular

        n_blocks = inside.shape[0]

        def flat(x):  # (blocks, n, m) -> (n, blocks·m)
            return np.swapaxes(x, 0, 1).reshape(n, -1)

        def unflat(x):
            return np.swapaxes(x.reshape(n, n_blocks, -1), 0, 1)

        inner = unflat(solve_triangular(Rn, flat(up_resid), trans="T"))
        dA = unflat(solve_triangular(Rn, flat(q_down - q_up @ A + inner)))
        # W = Ψ⁻¹ ΔA Ψ, only its columns of the poles asked for: (blocks, n, picks)
        Wm = np.linalg.inv(psi) @ (dA @ psi[:, idx])
        picks = np.arange(idx.size)
        d_mu = Wm[:, idx, picks]
        d_lam = d_mu / mu[idx][None, :] * model.sample_rate_hz
        # eigenvectors: Δψ_i = Σ_{k≠i} ψ_k W_ki / (μ_i − μ_k)
        with np.errstate(divide="ignore", invalid="ignore"):
            coupling = Wm / (mu[idx][None, None, :] - mu[None, :, None])  # (blocks, n, picks)
        coupling[:, idx, picks] = 0.0
        coupling = np.where(np.isfinite(coupling), coupling, 0.0)
        C = U1[:l]
        raw = C @ psi[:, idx]
        d_raw = d_C @ psi[:, idx] + C @ (psi @ coupling)  # (blocks, l, picks)
        shapes, lead, value = _normalised(raw)
        d_shape = (d_raw - shapes[None] * d_raw[:, lead, picks][:, None, :]) / value[None, None, :]
        return {"pole": d_lam * self.scale[:, None], "shape": d_shape * self.scale[:, None, None]}
