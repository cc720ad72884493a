"""Poly-reference LSCF on output half-spectra: an estimator independent of SSI, for cross-checks.

The half-spectrum ``S⁺(ω) = ½R₀ + Σ_{k≥1} w_k R_k e^{−iωkΔt}`` of the correlations (outputs ×
references) is a sum of modal terms with the system's poles, as an FRF is (Peeters & Van der
Auweraer, IMAC 2005): the pLSCF of :mod:`modal.global_.plscf` fits its denominator over a sweep of
orders. The exponential lag window ``w_k = e^{−βkΔt}`` (1 % at the last lag) adds exactly β to every
pole's decay rate, which is taken off again. Shapes come from a least-squares fit of the
half-spectra's residues at the chosen poles (z-domain LSFD), the dominant direction of each residue
matrix.

Error bars: each block's deviation of the half-spectra is carried to the poles by the exact linearisation
of the estimator (:mod:`modal.operational.plscf_perturb`), and to the shapes by the residue fit repeated on
the half-spectra and poles moved by it (central differences). Each mode is reported from the upper half of
its chain's orders (the order of smallest frequency error there): over 50 records of the anchor case,
the under-fitted low orders hold poles biased by about one of their (small) standard errors, so that
ranking every order by its error chose them (frequency z means up to +0.84, SDs up to 1.53). The lags span
:data:`PERIODS` periods of the lowest frequency of interest: over 4 periods the window's truncation, at 1 %
of a mode that has not yet decayed, biased the weak mode's damping by +0.4 of its error.
"""
from __future__ import annotations

import numpy as np

from ..global_.plscf import plscf_poles
from .correlations import correlations
from .inputs import MIN_LAGS_IN_RECORD, Prepared
from .modes import error_blocks, estimates_from_clusters
from .plscf_perturb import PlscfPerturbation
from .selection import stabilise
from .ssi import PoleSet

__all__ = ["plscf", "half_spectra"]

#: the lag window falls to this fraction at the last lag
WINDOW_END = 0.01
#: polynomial orders 1…this many (each gives up to order × references poles)
MAX_POLY_ORDER = 24
#: lags of the half-spectra: this many periods of the lowest frequency of interest (at least 4 × the order); at
#: 4 the lag window's truncation biased the damping of slowly decaying modes (see the module docstring)
PERIODS = 8.0


def half_spectra(R: np.ndarray, sample_rate_hz: float, frequency_hz: np.ndarray):
    """Half-spectra (outputs, references, lines) of correlations R (..., lags, outputs, references) and the
    decay rate β (1/s) the lag window adds."""
    n_lags = R.shape[-3]
    dt = 1.0 / sample_rate_hz
    beta = -np.log(WINDOW_END) / (n_lags * dt)
    k = np.arange(n_lags)
    w = np.exp(-beta * k * dt)
    w[0] = 0.5
    kernel = np.exp(-1j * np.outer(2 * np.pi * frequency_hz * dt, k)) * w[None, :]  # (lines, lags)
    S = np.tensordot(kernel, R, axes=([1], [-3]))  # (lines, ..., outputs, references)
    return np.moveaxis(S, 0, -1), beta


def _unwindow(omega_n, zeta, beta):
    """Poles with the window's decay β taken off: (complex poles λ, rad/s)."""
    s = -zeta * omega_n + 1j * omega_n * np.sqrt(np.maximum(1 - zeta**2, 0.0))
    return s + beta


#: each mode's residue is fitted on the lines within this many half-widths of its (windowed) peak, its decay rate
#: ζωn plus the lag window's β
LOCAL_HALF_WIDTHS = 4.0
#: and on at least this many lines on either side (and twice as many lines as the fit has terms)
LOCAL_MIN_LINES = 6
#: the fit holds the terms of the poles within this many times that stretch's half-width of the mode (the
#: farther ones' tails are smooth over the stretch: the residual takes them)
NEAR_HALF_WIDTHS = 2.0


def _lsfd_shapes(S, omega, poles_windowed, dt, n_picked, n_lags):
    """Shapes (outputs, n_picked) from the residues of the half-spectra (of lags 0…``n_lags`` − 1) at the first
    ``n_picked`` of the given (windowed) poles, z-domain.

    Each residue is fitted on the lines around its own mode (:data:`LOCAL_HALF_WIDTHS`), with the terms of the
    given poles near it (:data:`NEAR_HALF_WIDTHS`: a machine tone just outside the stretch has a steep tail)
    and, for the modes farther off, a residual 1, 1/z, 1/z². Fitted over the whole band with one term per pole,
    the misfit of a strong mode whose pole is off by its (large) error took the place of a weak mode's residue:
    on 300 s records of the anchor case (seeds 0-15), the mode excited 10 times less than the others came out
    with a strong neighbour's shape in 9 of 16 records (MAC 0.00-0.05 to its own, with small errors); fitted
    locally, its MAC is 0.96-1.00 in all 16. A mode of (windowed)
    discrete pole μ adds φ gᵀ Σ_{k=1}^{N−1} μ^{k−1} z^{−k} = φ gᵀ (1 − (μ/z)^{N−1}) / (z − μ) to a half-spectrum
    of N lags, the factor in brackets the truncation at the last lag.
    """
    z = np.exp(1j * omega * dt)
    mu = np.exp(poles_windowed * dt)
    truncated = n_lags - 1
    n_out, m, n_f = S.shape
    flat = S.reshape(n_out * m, n_f).T
    spacing = omega[1] - omega[0] if omega.size > 1 else 1.0
    half_width = np.maximum(LOCAL_HALF_WIDTHS * np.abs(poles_windowed.real), LOCAL_MIN_LINES * spacing)

    def term(pole, at):  # the pole's term on the lines ``at`` (their z)
        return (1.0 - (pole / at) ** truncated) / (at - pole)

    shapes = np.empty((n_out, n_picked), complex)
    for r in range(n_picked):
        centre = abs(poles_windowed[r].imag)
        inside = [r] + [q for q in range(mu.size) if q != r and abs(abs(poles_windowed[q].imag) - centre)
                        <= NEAR_HALF_WIDTHS * half_width[r]]
        distance = np.abs(omega - centre)
        n_lines = max(int(np.count_nonzero(distance <= half_width[r])), 2 * (2 * len(inside) + 3))
        lines = np.sort(np.argsort(distance, kind="stable")[:n_lines])
        zl = z[lines]
        basis = np.column_stack([term(mu[q], zl) for q in inside] + [term(mu[q].conj(), zl) for q in inside]
                                + [np.ones_like(zl), 1.0 / zl, 1.0 / zl**2])
        coef, *_ = np.linalg.lstsq(basis, flat[lines], rcond=None)
        u, _, _ = np.linalg.svd(coef[0].reshape(n_out, m), full_matrices=False)
        shapes[:, r] = u[:, 0]
    lead = np.argmax(np.abs(shapes), axis=0)
    return shapes / shapes[lead, np.arange(n_picked)][None, :]


def _with_shapes(estimates, S, omega, beta, dt, blocks_dS, scale, n_lags):
    """The estimates with shapes from one residue fit at all their poles together (LSFD: only the poles the
    stabilisation kept, so that no spurious pole of an order takes a share of a mode's residue), and the
    shapes' errors from the fit repeated on the half-spectra and poles moved by each block's deviation."""
    from dataclasses import replace

    from .modes import _physical_shape

    if not estimates:
        return estimates
    poles = np.array([e.pole for e in estimates])
    unit = _lsfd_shapes(S, omega, poles - beta, dt, poles.size, n_lags)
    d_unit = None
    if blocks_dS is not None and all(e.pole_deviation is not None for e in estimates):
        d_pole = np.column_stack([e.pole_deviation for e in estimates])  # (blocks, modes)
        d_unit = np.empty((d_pole.shape[0],) + unit.shape, complex)
        for b in range(d_pole.shape[0]):
            plus = _lsfd_shapes(S + blocks_dS[b], omega, poles + d_pole[b] - beta, dt, poles.size, n_lags)
            minus = _lsfd_shapes(S - blocks_dS[b], omega, poles - d_pole[b] - beta, dt, poles.size, n_lags)
            d_unit[b] = (plus - minus) / 2
    out = []
    for r, estimate in enumerate(estimates):
        shape, shape_std = _physical_shape(unit[:, r], None if d_unit is None else d_unit[:, :, r], scale)
        out.append(replace(estimate, shape=shape, std_shape=shape_std))
    return out


def _poles_of_order(omega, S, order, beta):
    packs = plscf_poles(omega, S, [order], max_damping=0.5)
    if not packs:
        return np.zeros(0, complex), np.zeros((S.shape[1], 0), complex)
    pack = packs[0]
    return _unwindow(pack.omega_n, pack.damping_ratio, beta), pack.participation.T


def plscf(prepared: Prepared, refs, max_order=None, workers: int = 1):
    """Poles over the polynomial orders, stabilisation, clusters and estimates (see the module docstring).

    Returns the same tuple as the SSI path of :func:`modal.operational.oma`; the record's blocks are shared among
    ``workers`` threads.
    """
    fs = prepared.sample_rate_hz
    low, high = prepared.band_hz
    m = len(refs)
    top = int(min(MAX_POLY_ORDER, max(16, np.ceil(2 * (max_order or 80) / m))))
    n_lags = int(max(np.ceil(PERIODS * fs / max(low, high / 10)), 4 * top))
    n_samples = prepared.n_samples
    if n_samples < MIN_LAGS_IN_RECORD * n_lags:
        from ..errors import ParameterError

        raise ParameterError(f"{prepared.source}: the record lasts {n_samples / fs:.4g} s; the half-spectra over "
                             f"{n_lags} lags need at least {MIN_LAGS_IN_RECORD * n_lags / fs:.4g} s")
    corr = correlations(prepared.signals, fs, refs, n_lags - 1, mean=prepared.mean, scale=prepared.scale,
                        workers=workers)
    spacing = fs / (2 * n_lags)
    lines = np.arange(max(low, spacing), high + spacing / 2, spacing)
    omega = 2 * np.pi * lines
    S, beta = half_spectra(corr.mean, fs, lines)
    orders = list(range(1, top + 1))
    sets = []
    for p in orders:
        poles, participation = _poles_of_order(omega, S, p, beta)
        sets.append(PoleSet(p, poles, participation))
    flat, stable, clusters = stabilise(sets, low, high)
    perturb, blocks_dS = None, None
    if clusters:
        medians = np.array([np.median(flat.pole[c.members]) for c in clusters])
        n_blocks = error_blocks(prepared.duration_s, medians, corr.blocks.shape[0])
        if n_blocks >= 2:
            blocks, weights = corr.grouped(n_blocks)
            w = weights / weights.sum()
            scale = w * np.sqrt(n_blocks / (n_blocks - 1.0))
            blocks_dS = (half_spectra(blocks, fs, lines)[0] - S[None]) * scale[:, None, None, None]

            sensitivity = PlscfPerturbation(omega, S, blocks_dS, top)

            def perturb_poles(order, indices):
                base_poles, _ = _poles_of_order(omega, S, order, beta)
                picked = base_poles[np.asarray(indices, int)]
                windowed, d_windowed = sensitivity.at(order)  # the window's β is a constant: same deviations
                match = np.argmin(np.abs(windowed[None, :] + beta - picked[:, None]), axis=1)
                return {"pole": d_windowed[:, match], "shape": None}

            perturb = perturb_poles
    # the poles' participation vectors, their shapes until the residue fit below, lie on the references
    estimates, chosen, kept = estimates_from_clusters(flat, clusters, perturb, len(orders),
                                                      prepared.scale[np.asarray(refs, int)],
                                                      representative="upper_half", workers=workers)
    estimates = _with_shapes(estimates, S, omega, beta, 1.0 / fs, blocks_dS, prepared.scale, n_lags)
    settings = {"orders": [orders[0], orders[-1]], "lags": n_lags, "window_decay_per_s": float(beta)}
    return estimates, chosen, kept, flat, stable, corr, settings
