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

from dataclasses import dataclass, field

import numpy as np

from ..errors import IdentificationError
from ..parallel import split_over_threads

__all__ = ["SubspaceModel", "PoleSet", "subspace_model", "hankel", "poles_at", "Perturbation", "continuous"]

#: the error bars' terms are formed this many blocks at a time: the blocks' Hankel deviations and their products
#: (about 1 MB a block for 64 outputs) then stay in the processor's cache, and no temporary is large enough for the
#: allocator to map it afresh from the system on every call (a 50-block Hankel deviation of 64 outputs: 35-45 MB)
TERM_BLOCKS = 4


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
    #: each order's (A, μ, Ψ) once computed (:func:`_system`): the order sweep computes them all, and the error
    #: bars take those of a few orders again
    systems: dict = field(default_factory=dict, init=False, repr=False, compare=False)


def hankel(R: np.ndarray, block_rows: int, block_cols: int | None = None) -> np.ndarray:
    """Block Hankel matrix of lags 1…p+q: block (a, b) = R[a + b + 1], a = 0…p, b = 0…q−1, with p
    ``block_rows`` and q ``block_cols`` (default p).

    ``R`` has shape (..., lags, n_outputs, n_references); the result (..., n_outputs (p+1), n_references q).
    """
    p = block_rows
    q = block_rows if block_cols is None else block_cols
    lead = R.shape[:-3]
    l, r = R.shape[-2:]
    # the lags 1…p+q output by output, (..., l, p+q, r): row o of block row a is then the q·r numbers from lag
    # a+1 on, one stretch of memory. A view (..., p+1, l, q·r) of those stretches, copied once by the reshape
    # (stretches of q·r numbers, not of r: several times faster for few references)
    by_output = np.ascontiguousarray(np.swapaxes(R[..., 1:p + q + 1, :, :], -3, -2))
    *lead_strides, output_stride, lag_stride, ref_stride = by_output.strides
    rows = np.lib.stride_tricks.as_strided(by_output, shape=(*lead, p + 1, l, q * r),
                                           strides=(*lead_strides, lag_stride, output_stride, ref_stride),
                                           writeable=False)
    return rows.reshape(*lead, (p + 1) * l, q * r)


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
    vectors (computed once per model and order)."""
    n = order
    if n not in model.systems:
        A = np.linalg.solve(model.R[:n, :n], model.QtU_down[:n, :n])
        mu, psi = np.linalg.eig(A)
        model.systems[n] = (A, mu, psi)
    return model.systems[n]


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
    max_order : int, optional
        The highest order whose deviations are asked for (default: the model's).
    workers : int, optional
        Threads over which the blocks are shared (default: every usable core); the deviations are the same,
        bit for bit, whatever their number.
    """

    def __init__(self, model: SubspaceModel, block_R: np.ndarray, weights: np.ndarray, max_order: int | None = None,
                 workers=None):
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
        d_R = np.subtract(block_R, np.tensordot(w, block_R, axes=1), out=np.empty(block_R.shape, np.float32),
                          casting="same_kind")
        # each perturbed singular vector's part outside the signal subspace of order n is ΔU₁ = U₂ X + E/σ₁, with
        # X (k − n, n) = (U₂ᵀ ΔH V₁ σ₁ + σ₂ (U₁ᵀ ΔH V₂)ᵀ) / (σ₁² − σ₂²) elementwise (the part inside only rotates
        # the basis, which leaves the eigenvalues and the observed shapes as they are). Entry (i, j) of X, i ≥ n > j,
        # is the same for every order: X of order n is the block [n:, :n] of one matrix (blocks, k, top), formed
        # once, in single precision as the deviations, from the gaps in double (close singular values); a gap of
        # zero (equal singular values) contributes nothing
        sv = model.singular_values
        with np.errstate(divide="ignore", invalid="ignore"):
            inverse_gap = 1.0 / (sv[None, :top] ** 2 - sv[:, None] ** 2)  # (k, top)
        inverse_gap[~np.isfinite(inverse_gap)] = 0.0
        gap_right = (sv[None, :top] * inverse_gap).astype(np.float32)
        gap_left = (sv[:, None] * inverse_gap).astype(np.float32)
        # E = (I − U Uᵀ) ΔH V₁, the part of ΔH V₁ outside the range of H, enters every order only through its
        # first l rows and the projections Qᵀ E_down, Qᵀ E_up, E_upᵀ U_down, E_upᵀ U_up, whose leading n × n
        # blocks are those of order n: formed once for all orders
        l, rows = model.n_outputs, model.n_outputs * model.block_rows
        Q = model.Q[:, :top]
        Q32 = Q.astype(np.float32)

        k = U.shape[1]
        # every array an order slices is kept as (rows, blocks, columns): an order's rows and columns of all the
        # blocks are then one matrix ((rows · blocks) × columns, or rows × (blocks · columns)), and each product
        # with them one call; the blocks' terms are written straight into them
        self.inside = np.empty((k, n_blocks, top), np.float32)
        self.E_C = np.empty((l, n_blocks, top))  # E's first rows
        self.QtE_down = np.empty((top, n_blocks, top))  # Qᵀ E_down
        self.QtE_up = np.empty((top, n_blocks, top))
        self.EtU_down = np.empty((top, n_blocks, top))  # E_upᵀ U_down
        self.EtU_up = np.empty((top, n_blocks, top))  # E_upᵀ U_up

        def block_terms(first: int, stop: int) -> None:
            """The terms of blocks first…stop − 1, :data:`TERM_BLOCKS` at a time (their Hankel matrices and
            products then stay in cache)."""
            for start in range(first, stop, TERM_BLOCKS):
                end = min(start + TERM_BLOCKS, stop)
                dH = hankel(d_R[start:end], model.block_rows, model.block_cols)
                G = dH @ V[:, :top]  # (blocks, p, top): ΔH V₁ for every order up to top
                UtG = U.T @ G  # (blocks, k, top): Uᵀ ΔH V₁
                inside = UtG * gap_right
                inside += (V.T @ (np.swapaxes(dH, 1, 2) @ U[:, :top])) * gap_left
                E = G - U @ UtG
                E_up, E_down = E[:, :rows], E[:, l:]
                E_up_t = np.swapaxes(E_up, 1, 2)
                for target, term in ((self.inside, inside), (self.E_C, E[:, :l]), (self.QtE_down, Q32.T @ E_down),
                                     (self.QtE_up, Q32.T @ E_up), (self.EtU_down, E_up_t @ U[l:, :top]),
                                     (self.EtU_up, E_up_t @ U[:rows, :top])):
                    target[:, start:end] = np.swapaxes(term, 0, 1)

        # the blocks are independent: shared among threads (:mod:`modal.parallel`), each share's products those
        # of one loop
        split_over_threads(block_terms, n_blocks, workers)
        # U₂'s projections of order n (Qₙᵀ U₂ down and up) and U_upᵀ U_down, U_upᵀ U_up, whose blocks [n:, :n]
        # give U₂ᵀ (O_down − O_up A): slices of these
        self.QtU_down = Q.T @ model.U[l:]  # (top, k)
        self.QtU_up = Q.T @ model.U[:rows]
        self.UtU_down = model.U[:rows].T @ model.U[l:, :top]  # (k, top)
        self.UtU_up = model.U[:rows].T @ model.U[:rows, :top]

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
        s1 = model.singular_values[:n]
        inside = self.inside[n:, :, :n]  # (k − n, blocks, n): ΔU₁ = U₂ inside + E/σ₁
        n_blocks = inside.shape[1]
        # ΔU₁ enters only projected: Qᵀ ΔO_down, Qᵀ ΔO_up, ΔO_upᵀ (O_down − O_up A) and its first l rows (ΔC); and
        # ΔA only through ΔA Ψ_p, Ψ_p the eigenvectors of the poles asked for. So `inside` is multiplied first by
        # Ψ_p and A Ψ_p (a few columns each) and only then by U₂'s projections (2n + l rows), in single precision
        # as the deviations
        A, mu, psi = _system(model, order)
        P = psi[:, idx]  # (n, p)
        AP = A @ P
        p = idx.size
        single = np.float32

        def spread(x):  # ((k − n) · blocks, m) -> (k − n, blocks · m)
            return x.reshape(-1, n_blocks * x.shape[-1])

        flat_inside = inside.reshape(-1, n)  # ((k − n) · blocks, n), a view
        in_P = spread(_real_columns(flat_inside, P, single))  # (k − n, blocks · 2p): inside Ψ_p, real and imaginary
        in_AP = spread(_real_columns(flat_inside, AP, single))
        scaled_P, scaled_AP = P / s1[:, None], AP / s1[:, None]  # E/σ₁: the columns of E divided by σ₁

        def rows_of(x, m):  # (m, blocks · 2p) real -> (m, blocks, p) complex
            x = x.reshape(m, n_blocks, 2 * p).astype(float)
            return x[..., :p] + 1j * x[..., p:]

        def e_part(E_rows, columns):  # (m, blocks, top) sliced to n columns, times complex columns: (m, blocks, p)
            m = E_rows.shape[0]
            x = _real_columns(E_rows[:, :, :n].reshape(-1, n), columns).reshape(m, n_blocks, 2 * p)
            return x[..., :p] + 1j * x[..., p:]

        # Qᵀ ΔO_down Ψ_p, Qᵀ ΔO_up A Ψ_p, ΔO_upᵀ (O_down − O_up A) Ψ_p, ΔC Ψ_p: (n or l, blocks, p)
        q_down = rows_of(self.QtU_down[:n, n:].astype(single) @ in_P, n) + e_part(self.QtE_down[:n], scaled_P)
        q_up = rows_of(self.QtU_up[:n, n:].astype(single) @ in_AP, n) + e_part(self.QtE_up[:n], scaled_AP)
        d_C = rows_of(model.U[:l, n:].astype(single) @ in_P, l) + e_part(self.E_C, scaled_P)
        resid = self.UtU_down[n:, :n] - self.UtU_up[n:, :n] @ A  # (k − n, n): U₂ᵀ (O_down − O_up A)
        rp = resid @ P
        # insideᵀ U₂ᵀ (O_down − O_up A) Ψ_p: (blocks, n, 2p) → (n, blocks, p)
        in_resid = np.transpose(inside, (1, 2, 0)) @ np.concatenate([rp.real, rp.imag], axis=1).astype(single)
        in_resid = np.swapaxes(in_resid.astype(float), 0, 1)
        up_resid = in_resid[..., :p] + 1j * in_resid[..., p:] \
            + (e_part(self.EtU_down[:n], P) - e_part(self.EtU_up[:n], AP)) / s1[:, None, None]
        # ΔA Ψ_p = R⁻¹ [Qᵀ (ΔO_down − ΔO_up A) Ψ_p + R⁻ᵀ ΔO_upᵀ (O_down − O_up A) Ψ_p], R upper triangular: two
        # triangular solves for all blocks at once
        from scipy.linalg import solve_triangular

        Rn = model.R[:n, :n]

        def flat(x):  # complex (n, blocks, p) -> real (n, 2·blocks·p)
            x = x.reshape(n, -1)
            return np.concatenate([x.real, x.imag], axis=1)

        def unflat(x):
            half = x.shape[1] // 2
            return x[:, :half] + 1j * x[:, half:]  # (n, blocks · p)

        inner = unflat(solve_triangular(Rn, flat(up_resid), trans="T", check_finite=False)).reshape(n, n_blocks, p)
        dAP = unflat(solve_triangular(Rn, flat(q_down - q_up + inner), check_finite=False))
        # W = Ψ⁻¹ ΔA Ψ, only its columns of the poles asked for: (blocks, n, picks)
        Wm = np.swapaxes((np.linalg.inv(psi) @ dAP).reshape(n, n_blocks, p), 0, 1)
        picks = np.arange(p)
        d_mu = Wm[:, idx, picks]
        d_lam = d_mu / mu[idx][None, :] * model.sample_rate_hz
        # eigenvectors: Δψ_i = Σ_{k≠i} ψ_k W_ki / (μ_i − μ_k)
        with np.errstate(divide="ignore", invalid="ignore"):
            coupling = Wm / (mu[idx][None, None, :] - mu[None, :, None])  # (blocks, n, picks)
        coupling[:, idx, picks] = 0.0
        coupling = np.where(np.isfinite(coupling), coupling, 0.0)
        C = model.U[:l, :n]
        raw = C @ P
        d_raw = np.swapaxes(d_C, 0, 1) + C @ (psi @ coupling)  # (blocks, l, picks)
        shapes, lead, value = _normalised(raw)
        d_shape = (d_raw - shapes[None] * d_raw[:, lead, picks][:, None, :]) / value[None, None, :]
        return {"pole": d_lam * self.scale[:, None], "shape": d_shape * self.scale[:, None, None]}


def _real_columns(real: np.ndarray, columns: np.ndarray, dtype=np.float64) -> np.ndarray:
    """``real @ columns`` for a real (a, b) matrix and complex (b, c) columns, as one real product (in ``dtype``):
    (a, 2c), the real parts' columns first, then the imaginary parts'."""
    return real @ np.concatenate([columns.real, columns.imag], axis=1).astype(dtype)

