"""Complex nonlinear least squares of the mode model (the reported estimate).

All modes of an FRF are fitted together over the union of their bands, poles
(ωr, ζr) shared by every channel, with the modal constants and one complex
offset per band region (the residual of modes outside the model) eliminated
by variable projection. Levenberg–Marquardt runs on the 2·n_modes pole
parameters only, with the exact projected (Kaufman) Jacobian, which here is an
outer product per parameter: the normal equations cost a few matrix products
whatever the channel count. Standard errors come from the Fisher information
with the residual noise estimate; for the poles the projected Jacobian gives
exactly the Schur complement, i.e. the Cramér–Rao covariance of the full model.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .channel_covariance import relative_in_fit_units
from .pole_covariance import fill_covariance
from .record_variance import channel_influence_in_fit_units
from .whitening import LineWhitening

__all__ = ["NLSFit", "RowResidual", "fit_modes", "orthonormal_factor", "truncation_shift"]


@dataclass(frozen=True)
class NLSFit:
    """Result of :func:`fit_modes` (SI units: rad/s, receptance modal constants 1/kg).

    Attributes
    ----------
    omega_n, damping_ratio : ndarray, shape (n_modes,)
    modal_constant : ndarray, shape (n_modes, n_channels)
    offsets : ndarray, shape (n_regions · n_background_powers, n_channels)
        Complex background coefficients of each band region (the offset first,
        then the higher powers, region by region within each), in the FRF's unit.
    mode_cov : ndarray, shape (n_modes, n_channels, 4, 4)
        Covariance of (ωn, ζ, Re A, Im A) per mode and channel.
    noise_var : ndarray, shape (n_channels,)
        Residual estimate of E|n|² per channel.
    converged : bool
    n_iter : int
    residual : RowResidual, optional
        Residual of the fit in the FRF's unit (each line times its weight, for a weighted fit),
        formed for the channels asked: ``residual[rows]``, shape (n_rows, n_freq).
    channel_scale : ndarray, shape (n_channels,), optional
        max |H| of each channel over the lines, FRF unit (the fit works on each channel over it,
        or over 1 where it is 0).
    line_weighted : bool
        The fit weighted or whitened its lines (``line_weight`` or ``whitening`` given): ``residual`` is the
        weighted (whitened) one.
    escaped : ndarray of bool, shape (n_modes,)
        The poles within the lines whose damping ratio grew past ``max_damping`` (the fit stopped there,
        not converged).
    n_evaluations : int
        Evaluations of the model (a design and its projection) after the start's.
    capped : bool
        The fit stopped at ``max_evaluations`` before converging: the poles are where it stood then.
    record_errors : bool
        The poles' covariance was measured over the records (``record_influence`` given and usable).
    weight_scale : ndarray, shape (n_channels,), optional
        What each channel was fitted over, FRF unit: its ``channel_scale``, or with ``channel_noise`` its noise
        (at the best channel's peak-to-noise ratio). Fits of the same data compare by Σ noise_var / weight_scale².
    """

    omega_n: np.ndarray
    damping_ratio: np.ndarray
    modal_constant: np.ndarray
    offsets: np.ndarray
    mode_cov: np.ndarray
    noise_var: np.ndarray
    converged: bool
    n_iter: int
    residual: RowResidual | None = None
    channel_scale: np.ndarray | None = None
    line_weighted: bool = False
    escaped: np.ndarray | None = None
    n_evaluations: int = 0
    capped: bool = False
    record_errors: bool = False
    weight_scale: np.ndarray | None = None


class RowResidual:
    """The residual Y − Q QᴴY of a fit, formed for the channels asked: ``residual[rows]`` (n_rows, n_freq).

    With many channels the checks read a sample (128 of 1000) and a few strongest channels; the whole
    residual would be a product with every channel. ``data`` Y (n_ch, n_freq), the fit's orthonormal basis
    ``basis`` Q (n_freq, n_b) and ``projected`` (QᴴYᵀ)ᵀ = Y conj(Q) (n_ch, n_b).
    """

    __slots__ = ("_data", "_basis", "_projected")

    def __init__(self, data: np.ndarray, basis: np.ndarray, projected: np.ndarray):
        self._data, self._basis, self._projected = data, basis, projected

    @property
    def shape(self) -> tuple[int, int]:
        return self._data.shape

    def __getitem__(self, rows) -> np.ndarray:
        out = self._projected[rows] @ self._basis.T  # the fitted part
        return np.subtract(self._data[rows], out, out=out)


#: a channel's residual sum of squares is its data's minus the fitted part's (no product with every
#: channel) where that is at least this fraction of the data's: rounding of the two sums, ~1e-15 of the
#: data's, is then below 1e-11 of it. Below (near-exact data), the residual is formed and summed
RSS_BY_DIFFERENCE = 1e-4


#: largest damping ratio the fit may reach (far past critical: the mode is then a slope)
ZETA_MAX = 10.0


def _background(x, region, n_regions, powers):
    """Per-region polynomial columns t**q, t the position in the region scaled to [−1, 1].

    Shape (n_freq, n_regions · len(powers)), region by region, powers within each.
    Centring and scaling keep the columns of a narrow region apart (1, x, x² of a
    band 1e-4 wide would be collinear to 1e-8).
    """
    if not n_regions:
        return np.zeros((x.size, 0), dtype=complex)
    if tuple(powers) == (0,):  # one complex offset per region
        cols = np.zeros((x.size, n_regions), dtype=complex)
        cols[np.arange(x.size), region] = 1.0
        return cols
    lo = np.full(n_regions, np.inf)
    hi = np.full(n_regions, -np.inf)
    np.minimum.at(lo, region, x)
    np.maximum.at(hi, region, x)
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    t = (x - centre[region]) / np.where(half > 0, half, 1.0)[region]
    cols = np.zeros((x.size, n_regions, len(powers)), dtype=complex)
    for j, q in enumerate(powers):
        cols[np.arange(x.size), region, j] = t**q
    return cols.reshape(x.size, -1)


def _design(x, numerator, x_squared, params, out, dphi):
    """Basis Φ = [modes | background] and ∂Φ/∂θ of the mode columns, written into ``out`` and ``dphi``.

    ``numerator`` is (i x)^p and ``x_squared`` x², computed once per fit; ``out`` holds the
    background columns already (they do not depend on the poles). Computed line by mode, in the
    layout of ``out`` (no transposed writes: twice as fast on 4000 lines × 16 modes).
    """
    n_modes = params.size // 2
    xr, zeta = params[0::2], params[1::2]
    # the operations of each element in the same order as ever (archived results are reproduced bit for bit)
    damping = (2j * zeta) * x[:, None]  # (n_freq, n_modes): 2iζx
    denom = (xr * xr - x_squared[:, None]) + damping * xr  # xr² − x² + 2iζ xr x
    phi = numerator[:, None] / denom
    out[:, :n_modes] = phi
    slope = np.divide(phi, denom, out=phi)  # ∂φ/∂denom = −φ/denom
    np.multiply(slope, -(2 * xr + damping), out=dphi[:, 0::2])
    np.multiply(slope, -((2j * xr) * x[:, None]), out=dphi[:, 1::2])
    return out, dphi


#: the residual counts as correlated between lines when its Ljung–Box statistic over the lags exceeds the
#: chi-square quantile of this tail probability (white residuals pass 99 % of the time)
WHITENESS_P = 0.01


def _residual_correlated(residual, lags: int, region) -> bool:
    """Ljung–Box test of the (whitened) residual, pooled over channels: whether its lines correlate over
    ``lags`` (then the sandwich covariance is used, else the Fisher information alone)."""
    from .quantiles import chi2_upper_quantile

    r = residual[:]  # (n_ch, n_freq)
    n = r.shape[1]
    lags = min(lags, n // 4)
    if lags < 1:
        return False
    energy = float(np.vdot(r, r).real)
    if not energy > 0:
        return False
    same = None if region is None else np.asarray(region)
    statistic = 0.0
    for lag in range(1, lags + 1):
        product = r[:, :-lag].conj() * r[:, lag:]
        if same is not None:
            product = product[:, same[:-lag] == same[lag:]]
        rho = product.sum() / energy  # complex: real and imaginary parts each ~ N(0, 1/(2n)) when white
        statistic += 2 * n * n / (n - lag) * abs(rho) ** 2 * r.shape[0]
    return bool(statistic > chi2_upper_quantile(2 * lags, WHITENESS_P))


def _compress(rows: np.ndarray, scale: np.ndarray, design: np.ndarray, derivatives: np.ndarray) -> np.ndarray:
    """Many channels: replace Y (n_freq, n_ch) by Y V with V (n_ch, k) orthonormal, where Y is
    ``rows`` (n_ch, n_freq) transposed with each channel times its ``scale``.

    The cost ||P⊥ Y V||² and its gradient depend on the channels only through
    the row space kept by V. The fitted coefficients Φ⁺Y and, to first order, their
    change with the poles are combinations of the rows of Q₀ᴴY, Q₀ a basis of the
    start's ``design`` (n_freq, n_b) and its pole ``derivatives`` (n_freq, n_theta).
    V is an orthonormal basis of that row space: two products with Y, no random
    numbers. With exact data this is lossless; with noise it drops directions that
    carry no information on the poles (on the 1000-channel benchmark the poles
    stay within 1e-4 of their standard errors of the fit to every channel; a
    randomised range finder of 20 columns with a power iteration, five products
    with Y, stayed within 3e-3). Modal constants and noise levels are computed
    afterwards on the full data. Both products read ``rows`` as they are (BLAS takes
    the transpose): no scaled copy of every channel. The bases by :func:`orthonormal_factor` (CholeskyQR2 where
    the columns are well apart, 3x faster than Householder's QR with its explicit Q here): Q₀ is that of the
    design beside that of the derivatives projected off it (design and derivatives side by side are too
    close to parallel for CholeskyQR2: Householder's QR of them was a quarter of the compression's time).
    """
    Q, _ = orthonormal_factor(design)
    off, _ = orthonormal_factor(derivatives - Q @ (Q.conj().T @ derivatives))
    basis = np.hstack([Q, off])
    V, _ = orthonormal_factor((rows @ basis.conj()).conj() * scale[:, None])  # (n_ch, k) orthonormal: of (Q₀ᴴY)ᴴ
    return rows.T @ (V * scale[:, None])


#: CholeskyQR2 is used while the design, its columns scaled to unit norm, has a condition number below
#: about 1/sqrt(eps)·1e-1 (its Cholesky factor's diagonal spread below this): there its Q is orthonormal and
#: Q R = Φ to rounding, as Householder's (Yamamoto et al. 2015). Beyond, Householder QR
CHOLESKY_QR_RATIO = 1e-6
#: ... and while it has at least this many elements (1000 lines × 10 columns)
CHOLESKY_QR_MIN_SIZE = 10_000


def orthonormal_factor(Phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Q (n_freq, n_b) orthonormal and R upper triangular with Q R = ``Phi``.

    CholeskyQR2: the Gram matrix of the columns scaled to unit norm, its Cholesky factor, Q = Φ R⁻¹,
    and the same once more on Q to restore orthogonality to rounding. Two products with Φ of
    n_b² n_freq each, where Householder's QR with its explicit Q takes a dozen passes (16 ms against
    1 ms on 4000 lines × 17 columns). A design too ill-conditioned for it (two poles at one
    frequency, a column of zeros) takes Householder's, and so does a small one (below
    :data:`CHOLESKY_QR_MIN_SIZE` elements, where Householder's costs little): small fits are
    reproduced bit for bit as before CholeskyQR2 (an archived identification is).
    """
    norms = np.sqrt(np.einsum("ij,ij->j", Phi.real, Phi.real) + np.einsum("ij,ij->j", Phi.imag, Phi.imag))
    if Phi.size >= CHOLESKY_QR_MIN_SIZE and np.all(np.isfinite(norms)) and np.all(norms > 0):
        scaled = Phi / norms
        try:
            first = np.linalg.cholesky(scaled.conj().T @ scaled).conj().T
            diagonal = np.abs(np.diag(first))
            if diagonal.min() > CHOLESKY_QR_RATIO * diagonal.max():
                Q = scaled @ np.linalg.inv(first)
                second = np.linalg.cholesky(Q.conj().T @ Q).conj().T
                return Q @ np.linalg.inv(second), (second @ first) * norms
        except np.linalg.LinAlgError:
            pass
    Q, R = np.linalg.qr(Phi)
    return np.ascontiguousarray(Q), R


def _project(Phi, Y, y_energy=None):
    """Q, R of ``Phi`` (:func:`orthonormal_factor`), QᴴY and the residual sum of squares ‖Y − Q QᴴY‖².

    Given ``y_energy`` ‖Y‖², the sum is ‖Y‖² − ‖QᴴY‖² where that keeps :data:`RSS_BY_DIFFERENCE` of ‖Y‖²
    (its rounding then below 1e-11 of it): no product of Q with QᴴY, no residual formed (two thirds of the
    projection's time on 4000 lines × 15 columns × 41 combinations of channels).
    """
    Q, R = orthonormal_factor(Phi)
    QhY = Q.conj().T @ Y
    if y_energy is not None:
        fitted = QhY.view(float)
        cost = y_energy - float(np.einsum("ij,ij->", fitted, fitted))
        if cost >= RSS_BY_DIFFERENCE * y_energy:
            return Q, R, QhY, cost
    res = Y - Q @ QhY
    return Q, R, QhY, float(np.vdot(res, res).real)


def fit_modes(omega: np.ndarray, response: np.ndarray, power: int, omega_n0, damping_ratio0,
              region: np.ndarray | None = None, max_iter: int = 200, step_tol: float = 1e-13,
              background_powers: tuple[int, ...] = (0,), residual_terms: bool = False,
              line_weight: np.ndarray | None = None, channel_scale: np.ndarray | None = None,
              max_damping: float | None = None, errors: bool = True,
              whitening: LineWhitening | None = None, correlated_lags: int = 0,
              decrement_tol: float = 0.0, max_evaluations: int | None = None,
              record_influence: np.ndarray | None = None, overlapping_records: int = 0,
              relative_error: np.ndarray | None = None, channel_noise: np.ndarray | None = None) -> NLSFit:
    """Fit poles and modal constants of several modes to many channels at once.

    Parameters
    ----------
    omega : ndarray, shape (n_freq,)
        Lines used (the union of the mode bands), rad/s.
    response : ndarray, shape (n_channels, n_freq)
        FRF of kind power ``power`` on those lines.
    power : int
        0 receptance, 1 mobility, 2 accelerance.
    omega_n0, damping_ratio0 : array_like, shape (n_modes,)
        Start values (rad/s, dimensionless).
    region : ndarray of int, shape (n_freq,), optional
        Band region of each line; one complex offset is fitted per region.
        None: no offset.
    max_iter : int
        Levenberg–Marquardt iterations at most.
    step_tol : float
        Convergence: relative pole step below this.
    background_powers : tuple of int
        Each region's background is a complex polynomial with these powers of
        the line's position in the region (scaled to [−1, 1]); ``(0,)`` is the
        complex offset.
        :func:`truncation_shift` adds a slope and a curvature.
    residual_terms : bool
        Add the upper and lower residual terms of modes outside the lines,
        (iω)^p (stiffness line) and (iω)^p/(−ω²) (mass line) in the FRF's kind, with
        complex coefficients (after the region columns in ``offsets``; use
        ``region=None`` with them). The lines must then exclude ω = 0.
    line_weight : ndarray, shape (n_freq,), optional
        Weighted least squares: each line's residual times this weight, σ_ref/σ_line for a
        noise σ_line that varies over the lines (an estimate from time data: its noise
        spikes at the zeros of the force spectrum). ``noise_var`` and the covariances are
        then those of the weighted problem: ``noise_var`` estimates σ_ref².
    channel_scale : ndarray, shape (n_channels,), optional
        max |H| of each channel over the lines, when the caller has it (without ``channel_noise`` each
        channel is fitted over it).
    max_damping : float, optional
        A pole within the lines whose damping ratio grows past this no longer describes a resonance: with
        nothing in the data to lock onto (a pole on the tail of a mode outside the lines, or on noise) it
        widens into a smooth background and absorbs what the residual terms leave. The fit stops at the
        first accepted step that takes such a pole past it and marks it in ``escaped``, for the caller to
        drop. Outside the lines a pole's damping is barely determined and a pole on its way to a mode
        there may pass through wide ones: it is left to go on (the caller judges where it converges).
    errors : bool
        Compute ``mode_cov`` (False: NaN; a fit whose poles only start another needs none).
    whitening : modal.whitening.LineWhitening, optional
        Generalised least squares for errors correlated between lines: with the (weighted)
        errors' correlation matrix R, W with W R Wᴴ = I; the fit minimises ‖W r‖², ``noise_var``
        and the covariances are those of the whitened problem.
    decrement_tol : float
        Converged also where the Gauss–Newton step would lower the cost by less than this times the residual's
        mean square per term (cost / degrees of freedom): the step is then sqrt(2 ``decrement_tol``)
        standard errors long or less (in the norm of the poles' covariance): a pole the lines hardly determine
        converges linearly, for tens of iterations below a tenth of its error. 0: the relative step decides.
    correlated_lags : int
        0: the poles' covariance is the inverse Fisher information (independent lines). Else the
        errors may correlate over this many neighbouring lines in ways no model gives (the leakage
        of a lightly damped mode in windowed records): the covariance is the sandwich
        F⁻¹ B F⁻¹ with B the lag-window (Bartlett) sum of the products of each line's score with
        those of its neighbours within these lags, from the fit's own residual (Newey & West 1987),
        when a Ljung–Box test finds the residual correlated over the lags.
    max_evaluations : int, optional
        Evaluations of the model (each a design and its projection, the unit of the fit's work) after the
        start's, at most; the fit stops there, not converged, with ``capped`` set (None: no limit but
        ``max_iter``; 0: the start's poles, with their errors).
    record_influence : ndarray, shape (n_records, n_freq) or (n_channels, n_records, n_freq), optional
        Channels estimated from records: each record's share of their error on the lines, FRF unit
        (:mod:`modal.estimate.record_influence`); the poles' covariance is then measured over the records
        (:mod:`modal.record_variance`; ``overlapping_records`` following records overlap each), where it
        can be, in place of the one above.
    overlapping_records : int
        See ``record_influence``.
    relative_error : ndarray, shape (n_factors, n_freq), complex, optional
        An error shared over the lines (and the channels) relative to the FRF (:mod:`modal.estimate.common_error`):
        in the modal constants' covariance (:func:`modal.pole_covariance.constants_noise`) and, for several
        channels, the poles' (:func:`modal.channel_covariance.channel_sandwich`).
    channel_noise : ndarray, shape (n_channels,), optional
        The noise's standard deviation of each channel (FRF unit, the lines' typical): each channel is fitted
        over it (at the best channel's peak-to-noise ratio), the least squares of independent channels' maximum
        likelihood. Over its max |H| alone, a channel of noise only (a sensor unplugged, a response at a node)
        weighs as much as a clean one: its noise, relative to its max of order 1, outweighed a clean channel's
        1e-3 and took the poles with it (a mode 350 standard errors off).
    """
    omega = np.asarray(omega, float)
    rows = np.ascontiguousarray(np.atleast_2d(np.asarray(response, complex)))  # (n_ch, n_freq), the FRF's unit
    n_ch = rows.shape[0]
    peak = np.abs(rows).max(axis=1) if channel_scale is None else np.asarray(channel_scale, float)
    ch_scale = np.where(peak > 0, peak, 1.0)
    if channel_noise is not None:
        noise = np.asarray(channel_noise, float)
        if noise.shape == peak.shape and np.all(np.isfinite(noise) & (noise > 0)):
            ch_scale = noise * np.max(ch_scale / noise)  # the best channel over its max, the others as its noise
    inverse_scale = 1.0 / ch_scale  # the fit works on each channel scaled to max 1 (or to the same noise)
    w_ref = np.atleast_1d(np.asarray(omega_n0, float))
    w_ref = float(w_ref[0] if w_ref.size == 1 else np.median(w_ref))
    x = omega / w_ref
    n_regions = 0 if region is None else int(region.max()) + 1
    params = np.empty(2 * np.size(omega_n0))
    params[0::2] = np.asarray(omega_n0, float) / w_ref
    params[1::2] = np.asarray(damping_ratio0, float)
    n_modes = params.size // 2
    n_theta = params.size

    x_lo, x_hi = 0.5 * x.min(), 2.0 * x.max()
    # a mode below the noise can be driven towards ζ = 0 step after step; it stops at a
    # half-power width of 1e-6 line spacings, far below anything the lines resolve
    zeta_lo = 1e-6 * float((x[1:] - x[:-1]).min()) / (2 * x.max()) if x.size > 1 else 1e-12
    params[0::2] = np.minimum(np.maximum(params[0::2], x_lo), x_hi)
    params[1::2] = np.minimum(np.maximum(params[1::2], zeta_lo), ZETA_MAX)
    background = _background(x, region, n_regions, background_powers)
    if residual_terms:
        kind = (1j * x) ** power
        background = np.hstack([background, kind[:, None], (kind / -(x**2))[:, None]])
    numerator, x_squared = (1j * x) ** power, x * x  # what the design takes from the lines alone
    n_b = n_modes + background.shape[1]

    weight = None
    if line_weight is not None:
        weight = np.asarray(line_weight, float)[:, None]
        rows = rows * weight[:, 0]
        background = background * weight
    if whitening is not None:
        rows = np.ascontiguousarray(whitening(rows.T).T)
        background = whitening(background)
    def design(p):
        Phi = np.empty((x.size, n_b), dtype=complex)
        Phi[:, n_modes:] = background
        Phi, dphi = _design(x, numerator, x_squared, p, Phi, np.empty((x.size, n_theta), complex))
        if weight is not None:  # the modes' columns (the background's are weighted once, above)
            Phi[:, :n_modes] *= weight
            dphi *= weight
        if whitening is not None:
            Phi[:, :n_modes] = whitening(Phi[:, :n_modes])
            dphi = whitening(dphi)
        return Phi, dphi

    if n_ch > 2 * (2 * n_b + 8):  # many channels: fit on fewer combinations
        Y = _compress(rows, inverse_scale, *design(params))
    else:  # (n_freq, n_ch), each channel scaled: a transposed copy, multiplied on its real view
        Y = np.array(rows.T, order="C")  # (numpy multiplies complex by real as complex by complex)
        parts = Y.view(float)
        parts *= np.repeat(inverse_scale, 2)

    y_energy = float(np.vdot(Y, Y).real)
    cost_dof = max(Y.size - n_b * Y.shape[1] - n_theta, 1)  # the residual's mean square is cost / cost_dof
    # the cost by difference (rounding ~1e-11 of it) where the decrement test stops far above that
    by_difference = y_energy if decrement_tol > 0 else None

    def evaluate(p):
        Phi, dphi = design(p)
        Q, R, QhY, cost = _project(Phi, Y, by_difference)
        return Phi, dphi, Q, R, QhY, cost

    state = evaluate(params)
    escaped = np.zeros(n_modes, bool)
    mode_of = np.repeat(np.arange(n_modes), 2)
    diagonal = np.arange(n_theta)
    lam = 1e-4
    converged = capped = False
    n_iter = n_evaluations = 0
    for n_iter in range(1, max_iter + 1):
        Phi, dphi, Q, R, QhY, cost = state
        C = np.linalg.solve(R, QhY)  # (n_b, n_ch)
        E = dphi - Q @ (Q.conj().T @ dphi)  # projected basis derivatives, (n_freq, n_theta)
        Cm = C[mode_of]  # (n_theta, n_ch): the coefficient multiplying each derivative
        EhE = E.conj().T @ E
        CCh = Cm.conj() @ Cm.T
        JtJ = np.real(EhE * CCh)
        g = -np.real(np.sum((E.conj().T @ Y) * Cm.conj(), axis=1))
        diag = np.maximum(JtJ.diagonal(), 1e-300)
        accepted = converged_here = False
        for _ in range(40):
            try:
                damped = JtJ.copy()
                damped[diagonal, diagonal] += lam * diag
                step = np.linalg.solve(damped, -g)
                # a damping ratio on its floor that the step would push below it stays there (an active bound):
                # the step is solved for the others, so that the convergence tests see what can move (else a pole
                # outside the lines collapsing onto ζ = 0 kept the fit going to max_iter)
                pinned = (params[1::2] <= zeta_lo) & (step[1::2] < 0)
                if pinned.any():
                    free = np.ones(n_theta, bool)
                    free[1::2] = ~pinned
                    step = np.zeros(n_theta)
                    step[free] = np.linalg.solve(damped[np.ix_(free, free)], -g[free])
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            trial = params + step
            rel_step = float(np.max(np.abs(step) / np.maximum(np.abs(params), 1e-300)))
            if lam <= 1e-2 and rel_step < step_tol:
                break  # the Gauss–Newton step is below rounding: converged, nothing to evaluate
            # the decrease the Gauss–Newton model predicts for the step, −2gᵀs − sᵀJᵀJs (the cost is
            # ‖r‖²; it matches the actual decrease to 1e-3 near the optimum): below the flat test's
            # 1e-13 of the cost, the step is not worth an evaluation: converged where it stands
            predicted = -2.0 * float(g @ step) - float(step @ (JtJ @ step))
            if lam <= 1e-2 and 0.0 <= predicted <= max(1e-13 * cost, decrement_tol * cost / cost_dof):
                converged_here = True
                break
            # a pole the step would push to ζ ≤ 0 (a mode below the noise sliding onto a
            # spike) moves to a tenth of its value instead; rejecting the whole step drove λ
            # up until every other mode stalled where it started. Poles
            # kept inside a box (ωn within a factor 2 of the lines, ζ ≤ ZETA_MAX) move halfway
            # to the bound, so an unidentifiable mode cannot run off to overflow
            x_r, zeta_t = trial[0::2], trial[1::2]
            if x_r.min() < x_lo or x_r.max() > x_hi or zeta_t.min() <= 0 or zeta_t.max() > ZETA_MAX:
                x_r = np.where(x_r < x_lo, (params[0::2] + x_lo) / 2,
                               np.where(x_r > x_hi, (params[0::2] + x_hi) / 2, x_r))
                zeta_t = np.where(zeta_t > 0, zeta_t, np.maximum(params[1::2] / 10, zeta_lo))
                zeta_t = np.where(zeta_t > ZETA_MAX, (params[1::2] + ZETA_MAX) / 2, zeta_t)
                trial[0::2], trial[1::2] = x_r, zeta_t
                step = trial - params
                rel_step = float(np.max(np.abs(step) / np.maximum(np.abs(params), 1e-300)))
            if max_evaluations is not None and n_evaluations >= max_evaluations:
                capped = True  # the budget is spent: the fit stays where it stands
                break
            if np.isfinite(trial).all():
                n_evaluations += 1
                new_state = evaluate(trial)
                if new_state[-1] <= cost:
                    accepted = True
                    break
            lam *= 4
        if capped:
            break
        if not accepted:
            small = converged_here or rel_step < step_tol
            converged = bool(small or cost <= 1e-28 * y_energy)
            break
        params, state = trial, new_state
        if max_damping is not None:
            wide = (params[1::2] > max_damping) & (params[0::2] >= x[0]) & (params[0::2] <= x[-1])
            if wide.any():
                escaped = wide
                break
        lam = max(lam / 3, 1e-12)
        flat = cost - new_state[-1] <= 1e-13 * cost  # no decrease left above rounding
        if rel_step < step_tol or flat or new_state[-1] <= 1e-30 * y_energy:
            converged = True
            break

    Phi, dphi, Q, R, QhY, cost = state
    # back to every channel: one projection of the full data, channels first in the FRF's unit (no copy of
    # the data: BLAS reads ``rows`` transposed)
    projected = rows @ Q.conj()  # (Qᴴ Yᵀ)ᵀ, (n_ch, n_b)
    residual = RowResidual(rows, Q, projected)
    QhY = projected.T * inverse_scale
    n_freq = x.size
    n_b = Phi.shape[1]
    C = np.linalg.solve(R, QhY)
    parts = rows.view(float)  # Re, Im side by side: |y|² summed without a temporary per line
    energy = np.einsum("ij,ij->i", parts, parts)
    fitted = projected.view(float)
    rss = energy - np.einsum("ij,ij->i", fitted, fitted)  # ‖y‖² − ‖Qᴴy‖², Q orthonormal
    direct = ~(rss >= RSS_BY_DIFFERENCE * energy)
    if direct.any():
        exact = residual[direct].view(float)
        rss[direct] = np.einsum("ij,ij->i", exact, exact)
    rss *= inverse_scale**2
    dof = n_freq - n_b - n_theta / (2 * n_ch)
    noise_var = rss / dof if dof > 0 else np.full(n_ch, np.nan)
    Cm = C[mode_of]
    mode_cov = np.full((n_modes, n_ch, 4, 4), np.nan)
    record_errors = False
    if errors:
        records = None
        if record_influence is not None and n_ch == 1:  # transformed as the data were
            influence = np.asarray(record_influence, complex).T * inverse_scale[0]
            influence = influence if weight is None else influence * weight
            records = (influence if whitening is None else whitening(influence), overlapping_records)
        elif record_influence is not None and np.ndim(record_influence) == 3 and len(record_influence) == n_ch:
            records = (channel_influence_in_fit_units(record_influence, inverse_scale, weight, whitening),
                       overlapping_records)
        common = None if relative_error is None else relative_in_fit_units(
            relative_error, response, inverse_scale, weight, whitening)
        record_errors = fill_covariance(mode_cov, dphi, Q, R, Cm, noise_var, correlated_lags, residual, region,
                                        inverse_scale, records, common,
                                        lambda: _residual_correlated(residual, correlated_lags, region))
    # back to physical units: x → ω = x w_ref; c → A = c · ch_scale · w_ref^(2−p)
    a_scale = ch_scale * w_ref ** (2 - power)  # (n_ch,)
    unit = np.empty((n_ch, 4))  # each channel's (ωn, ζ, Re A, Im A) per fitted unit
    unit[:, 0], unit[:, 1], unit[:, 2], unit[:, 3] = w_ref, 1.0, a_scale, a_scale
    mode_cov *= unit[:, :, None] * unit[:, None, :]  # one product: cov_ij · s_i s_j
    modal_constant = C[:n_modes] * a_scale[None, :]
    offsets = C[n_modes:] * ch_scale[None, :]
    return NLSFit(
        omega_n=params[0::2] * w_ref,
        damping_ratio=params[1::2].copy(),
        modal_constant=modal_constant,
        offsets=offsets,
        mode_cov=mode_cov,
        noise_var=noise_var * ch_scale**2,
        converged=bool(converged),
        n_iter=n_iter,
        residual=residual,
        channel_scale=peak,
        line_weighted=weight is not None or whitening is not None,
        escaped=escaped,
        n_evaluations=n_evaluations,
        capped=capped,
        record_errors=record_errors,
        weight_scale=ch_scale,
    )


#: background powers of the check in :func:`truncation_shift`: offset, slope, curvature
TRUNCATION_POWERS = (0, 1, 2)


def truncation_shift(omega: np.ndarray, response: np.ndarray, power: int, region: np.ndarray,
                     fit: NLSFit) -> tuple[np.ndarray, np.ndarray] | None:
    """How far the fit moves when each region's background gains a slope and a curvature.

    A band region absorbs the modes outside the bands in one complex offset,
    which is exact only to zeroth order: a mode above the bands still adds
    ``−2iζ ω/ωs`` (its damping) and ``(ω/ωs)²`` of itself across the band.
    Where the noise is far below that misfit (near-exact data), the fitted
    poles are biased by many of their white-noise errors (2.5e-7 relative, 5.5
    errors, on exact data with a mode far above the bands). Refitting
    with the background ``c0 + c1 t + c2 t²`` per region (t the position in the
    region, scaled to [−1, 1]) takes
    the first- and second-order terms out; the change of each estimate is the
    size of the truncation bias, to leading order.

    Parameters
    ----------
    omega, response, power, region
        As for :func:`fit_modes`.
    fit : NLSFit
        The fit with the plain offset, on the same lines and channels.

    Returns
    -------
    (pole_shift, constant_shift) or None
        ``pole_shift`` shape (n_modes, 2): change of (ωn [rad/s], ζ);
        ``constant_shift`` shape (n_modes, n_channels): change of the modal
        constants. None when a region has too few lines for the extra terms
        (fewer than twice the polynomial's terms) or the refit fails.
    """
    counts = np.bincount(region)
    if np.any(counts < 2 * len(TRUNCATION_POWERS)):
        return None
    with np.errstate(all="ignore"):
        wider = fit_modes(omega, response, power, fit.omega_n, fit.damping_ratio, region=region,
                          background_powers=TRUNCATION_POWERS)
    pole = np.column_stack([wider.omega_n - fit.omega_n, wider.damping_ratio - fit.damping_ratio])
    constant = wider.modal_constant - fit.modal_constant
    if not (np.all(np.isfinite(pole)) and np.all(np.isfinite(constant))):
        return None
    return pole, constant
