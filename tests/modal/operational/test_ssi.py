"""SSI-cov: the order sweep from one SVD and one QR, and the first-order deviations of the poles."""
from __future__ import annotations

import numpy as np

from modal.operational.correlations import correlations
from modal.operational.ssi import Perturbation, hankel, poles_at, subspace_model
from modal.synthetic import ambient_modal_response
from support.ambient import anchor_shapes

FS = 100.0


def _model(block_rows=20, max_order=30, n=60_000, seed=1):
    rec = ambient_modal_response([5.0, 12.0, 21.0], [0.02, 0.015, 0.01], anchor_shapes(4)[:, :3], FS, n,
                                 noise=0.1, seed=seed)
    y = rec.signals - rec.signals.mean(axis=1, keepdims=True)
    corr = correlations(y, FS, [0, 1, 2, 3], 2 * block_rows, max_blocks=12)
    return rec, corr, subspace_model(corr.mean, block_rows, max_order, FS)


def test_each_order_equals_its_own_least_squares():
    # the shared QR gives, for every order n, the least-squares A of the first n singular vectors
    _, _, model = _model()
    l = model.n_outputs
    for n in (6, 14, 30):
        U = model.U[:, :n]
        A, *_ = np.linalg.lstsq(U[: l * model.block_rows], U[l:], rcond=None)
        direct = np.sort_complex(np.log(np.linalg.eigvals(A).astype(complex)) * FS)
        assert np.allclose(np.sort_complex(poles_at(model, n).poles), direct, rtol=1e-9, atol=1e-9)


def test_true_order_poles_are_the_modes():
    rec, _, model = _model(n=100_000)
    poles = poles_at(model, 6).poles
    found = np.sort(np.abs(poles[poles.imag > 0])) / (2 * np.pi)
    # 1000 s of record: frequencies to well within 0.2 % (their errors here are ~0.05 %)
    assert np.allclose(found, rec.natural_frequency_hz, rtol=2e-3)


def test_first_order_deviations_match_finite_differences():
    # each block's deviation carried through SVD, least squares and eigenvalues to first order, against the
    # poles recomputed from the perturbed Hankel matrix (step 1e-4 of the block's deviation)
    _, corr, model = _model()
    blocks, weights = corr.grouped(6)
    order = 10
    ps = poles_at(model, order)
    picks = np.flatnonzero((ps.poles.imag > 0) & (np.abs(ps.poles) < 2 * np.pi * 30))
    dev = Perturbation(model, blocks, weights).at(order, picks)
    scale = weights / weights.sum() * np.sqrt(6 / 5)
    step = 1e-4
    for b in range(blocks.shape[0]):
        R = corr.mean + step * (blocks[b] - np.tensordot(weights / weights.sum(), blocks, axes=1))
        moved = poles_at(subspace_model(R, model.block_rows, model.max_order, FS), order)
        for j, i in enumerate(picks):
            k = np.argmin(np.abs(moved.poles - ps.poles[i]))
            numeric = (moved.poles[k] - ps.poles[i]) / step * scale[b]
            assert abs(numeric - dev["pole"][b, j]) < 1e-3 * abs(dev["pole"][b, j]) + 1e-9
            # the normalised shape too
            lead = np.argmax(np.abs(ps.shapes[:, i]))
            assert abs(moved.shapes[lead, k] - 1) < 1e-12  # the same lead entry
            d_shape = (moved.shapes[:, k] - ps.shapes[:, i]) / step * scale[b]
            assert np.allclose(d_shape, dev["shape"][b, :, j], rtol=1e-3, atol=1e-3 * np.abs(d_shape).max())


def test_hankel_blocks():
    R = np.arange(7 * 2 * 1, dtype=float).reshape(7, 2, 1)  # lags 0..6, 2 outputs, 1 reference
    H = hankel(R, 3)
    assert H.shape == (8, 3)
    for a in range(4):
        for b in range(3):
            assert np.array_equal(H[2 * a:2 * a + 2, b], R[a + b + 1, :, 0])


def test_hankel_blocks_of_many_records_with_more_lags_than_used():
    # a stack of 3 blocks' correlations, 3 outputs × 2 references, p = 2 block rows and q = 4 block columns:
    # block (a, b) holds lag a + b + 1 of its own record; the lags beyond p + q are not used
    R = np.random.default_rng(0).standard_normal((3, 12, 3, 2))
    H = hankel(R, 2, 4)
    assert H.shape == (3, 9, 8)
    for blk in range(3):
        for a in range(3):
            for b in range(4):
                assert np.array_equal(H[blk, 3 * a:3 * a + 3, 2 * b:2 * b + 2], R[blk, a + b + 1])


def _plain_deviations(model, blocks, weights, order, picks):
    """The first-order deviations of the poles ``picks`` of ``order`` and of their shapes, block by block in double
    precision as the formulas read: ΔU₁ = U₂ X + (I − U Uᵀ) ΔH V₁ / σ₁ formed whole, ΔA from the least squares,
    the eigenvalues' and eigenvectors' first-order changes from W = Ψ⁻¹ ΔA Ψ."""
    l, rows, n = model.n_outputs, model.n_outputs * model.block_rows, order
    U, V, sv = model.U, model.V, model.singular_values
    U1, U2, V1, V2, s1, s2 = U[:, :n], U[:, n:], V[:, :n], V[:, n:], sv[:n], sv[n:]
    Rn, Qn = model.R[:n, :n], model.Q[:, :n]
    A = np.linalg.solve(Rn, model.QtU_down[:n, :n])
    mu, psi = np.linalg.eig(A)
    w = weights / weights.sum()
    scale = w * np.sqrt(len(w) / (len(w) - 1.0))
    dH = hankel(blocks - np.tensordot(w, blocks, axes=1)[None], model.block_rows, model.block_cols)
    C = U1[:l]
    raw = C @ psi[:, picks]
    lead = np.argmax(np.abs(raw), axis=0)
    value = raw[lead, np.arange(len(picks))]
    poles, shapes = [], []
    for b in range(dH.shape[0]):
        X = ((U2.T @ dH[b] @ V1) * s1[None, :] + s2[:, None] * (U1.T @ dH[b] @ V2).T) / (s1[None] ** 2 - s2[:, None] ** 2)
        dU1 = U2 @ X + (dH[b] @ V1 - U @ (U.T @ dH[b] @ V1)) / s1[None, :]
        dO_up, dO_down = dU1[:rows], dU1[l:]
        dA = np.linalg.solve(Rn, Qn.T @ (dO_down - dO_up @ A)
                             + np.linalg.solve(Rn.T, dO_up.T @ (U1[l:] - U1[:rows] @ A)))
        W = np.linalg.solve(psi, dA @ psi)
        d_pole, d_shape = [], []
        for j, i in enumerate(picks):
            gap = mu[i] - mu
            gap[i] = np.inf
            d_psi = psi @ (W[:, i] / gap)
            d_raw = dU1[:l] @ psi[:, i] + C @ d_psi
            shape = raw[:, j] / value[j]
            d_shape.append((d_raw - shape * d_raw[lead[j]]) / value[j] * scale[b])
            d_pole.append(W[i, i] / mu[i] * model.sample_rate_hz * scale[b])
        poles.append(d_pole)
        shapes.append(np.array(d_shape).T)
    return np.array(poles), np.array(shapes)


def test_deviations_equal_the_plain_formulas_to_single_precision_rounding():
    # Perturbation forms the blocks' deviations once for all orders and carries them in single precision, with
    # ΔA only through the columns of the poles asked for; the formulas evaluated whole, block by block, in
    # double precision give the same deviations to the rounding of single-precision products: sums of up to
    # k (the Hankel matrix's columns, 80 here) terms, each rounded at 6e-8 of its size, so ~k·eps32 = 5e-6 of
    # the deviations' size, amplified by the eigenvectors' coupling 1/(μ_i − μ_k); 1e-4 leaves room for that
    _, corr, model = _model()
    blocks, weights = corr.grouped(8)
    perturbation = Perturbation(model, blocks, weights)
    for order in (6, 12, 24):
        ps = poles_at(model, order)
        picks = np.flatnonzero((ps.poles.imag > 0) & (np.abs(ps.poles) < 2 * np.pi * 30))
        fast = perturbation.at(order, picks)
        d_pole, d_shape = _plain_deviations(model, blocks, weights, order, picks)
        assert np.abs(fast["pole"] - d_pole).max() <= 1e-4 * np.abs(d_pole).max()
        for j in range(picks.size):
            assert np.abs(fast["shape"][:, :, j] - d_shape[:, :, j]).max() <= 1e-4 * np.abs(d_shape[:, :, j]).max()


def test_deviations_do_not_depend_on_the_number_of_threads():
    # each thread forms the deviations' products of a contiguous share of the blocks, as one loop would
    _, corr, model = _model()
    blocks, weights = corr.grouped(8)
    one = Perturbation(model, blocks, weights, workers=1)
    three = Perturbation(model, blocks, weights, workers=3)
    for name in ("inside", "E_C", "QtE_down", "QtE_up", "EtU_down", "EtU_up"):
        assert np.array_equal(getattr(one, name), getattr(three, name)), name
    ps = poles_at(model, 12)
    picks = np.flatnonzero(ps.poles.imag > 0)
    assert np.array_equal(one.at(12, picks)["pole"], three.at(12, picks)["pole"])
