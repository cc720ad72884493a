"""What an FRF estimated from time records knows about its own errors, beyond each line's noise level.

An estimate's errors are not independent from line to line: a window correlates
neighbouring lines (Hann: the noise of lines k and k + 1 correlates by 4/9 in an H1
estimate from white excitation; an exponential window over tens of lines), and the
windowed records smooth the spectrum, which biases the damping (leakage). The
:class:`NoiseModel` that :func:`modal.estimate_frf` attaches to its FRF carries both,
computed from the windows and the excitation actually recorded, so that
:func:`modal.identify` can weight the lines with their covariance and take the
window's bias out.

The bias follows from the lag window ρ(τ) (Bendat & Piersol, *Random Data*, ch. 11):
for an excitation whose samples are uncorrelated (white random, or a pulse shorter
than any window change), the expected estimate at every line is the transform of the
impulse response times ρ, E[Ĥ](ω) = Σ_τ h[τ] ρ(τ) e^{−iωτT}, with

    ρ(τ) = Σ_n w_out[n] w_in[n − τ] v[n − τ] / Σ_n w_in[n]² v[n],

w_in, w_out the windows of excitation and response and v the excitation's mean square
at each sample of a record (averaged over the records). A rectangular window on
stationary excitation gives ρ(τ) = 1 − τ/N, a Hann window ≈ 1 − (2π²/3)(τ/N)² near
τ = 0, an exponential window e^{−τT/τ_w} until the record ends.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from .errors import FRFValidationError
from .shared_error import CommonError, JoinedError, frozen as _frozen

__all__ = ["NoiseModel", "window_line_correlation", "lag_window", "input_noise_split", "MAX_LAGS", "CORRELATION_FLOOR",
           "MEASURED_CORRELATION_RECORDS", "MAX_INFLUENCE_VALUES"]

#: neighbouring lines whose noise correlation is carried, at most
MAX_LAGS = 64
#: records × lines (× channels) whose influences a continuous estimate keeps at most (64 MiB of complex values, 160 MiB while
#: they are formed; 29 records × 4097 lines is 0.12 M); above, it carries none and identification reports the
#: errors of the lines' correlation (:mod:`modal.estimate.record_influence`)
MAX_INFLUENCE_VALUES = 1 << 22
#: a continuous estimate from at least this many records carries its errors' correlation as measured over them
#: (:mod:`modal.estimate.error_correlation`; fewer scatter too much to whiten by: ±0.25 per line with 16)
MEASURED_CORRELATION_RECORDS = 16
#: a window's line correlation |c(m)| below this at every lag from m on ends the lags carried
CORRELATION_FLOOR = 0.01
#: at most this many correlation values per FRF (lags × lines): long FRFs carry fewer lags
MAX_CORRELATION_VALUES = 4_000_000


@dataclass(frozen=True, eq=False)
class NoiseModel:
    """The errors of an FRF estimated from time records, beyond ``FRF.noise_std``.

    Attributes
    ----------
    averages : int
        Records (segments or accepted hits) averaged.
    degrees_of_freedom : float
        Of each line's variance estimate (``noise_std``): averages less inputs, over
        the variance inflation of overlapping records; 0 where no variance was estimated.
    line_correlation : ndarray, shape (n_lags, n_freq), complex, or None
        Correlation coefficient of the random errors of line k and line k + m
        (row m − 1), E[e_k e*_{k+m}] / (σ_k σ_{k+m}), shared by every channel; zero
        past the last line. None when unknown (MIMO estimates).
    lag_window : ndarray, shape (n_samples,), or None
        ρ(τ) for τ = 0 … n − 1 samples (see the module): the expected estimate is the
        transform of the impulse response times it. An exponential window's own
        decay is left out of it (the FRF's ``exponential_decay_s`` says it).
    sample_interval_s : float
        Time between samples, s (the lag window's step).
    variance_model : ndarray, shape (n_freq,), or None
        Each line's error variance as the response's and the excitation's noise give it (a + b|H|²)/S_xx
        (:func:`input_noise_split`), in the FRF's unit squared: the shape of ``noise_std²`` without its
        scatter from few averages. NaN on lines where the excitation's noise is not small against the
        excitation (there H1 is biased and the model does not hold); None when not fitted (no excitation
        noise found, several inputs, one record). Several outputs of one input: the part every channel's variance
        shares, a/S_xx with a the outputs' mean response-noise power (the excitation noise's part, b|H_o|², differs
        per channel).
    record_influence : ndarray, shape (n_records, n_freq) or (n_channels, n_records, n_freq), complex, or None
        Each record's share of the estimate's error at each line, in the FRF's unit
        (:mod:`modal.estimate.record_influence`): identification measures its parameters' variance over
        the records with them (:mod:`modal.record_variance`). 2-D: one channel; 3-D: several channels (inputs or
        outputs), each channel's over the same records. None when not kept (H1, continuous records, at least
        :data:`MEASURED_CORRELATION_RECORDS` of them, within the memory budget).
    overlapping_records : int
        How many following records each record overlaps (1 for half-overlapping records; 0 without overlap).
    influence_withheld : bool
        The records' influences would have been kept but exceed the memory budget
        (:data:`MAX_INFLUENCE_VALUES`).
    relative_error : CommonError or JoinedError, or None
        A short excitation window (a hammer's): the excitation noise's error, H_o η with η relative
        (dimensionless, whatever the FRF's kind), as what generates its covariance
        (:mod:`modal.estimate.common_error`); a fit asks it for a factor P on its lines (``factor(keep)``),
        η = Pᵀ ξ with ξ standard complex: E[η_k η*_l] = Σ_r P_rk conj(P_rl). A
        :class:`~modal.shared_error.CommonError`: one η for every output; a
        :class:`~modal.shared_error.JoinedError`: each channel's own (a joined estimate: channels from
        independent records take disjoint factors, :mod:`modal.roving`). None otherwise.
    """

    averages: int
    degrees_of_freedom: float
    line_correlation: np.ndarray | None
    lag_window: np.ndarray | None
    sample_interval_s: float
    variance_model: np.ndarray | None = None
    record_influence: np.ndarray | None = None
    overlapping_records: int = 0
    influence_withheld: bool = False
    relative_error: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.line_correlation is not None:
            corr = _frozen(self.line_correlation, complex)
            if corr.ndim != 2:
                raise FRFValidationError(f"field 'line_correlation' has shape {corr.shape}; expected (n_lags, n_freq)")
            if not np.all(np.isfinite(corr)) or np.any(np.abs(corr) > 1 + 1e-9):
                raise FRFValidationError("field 'line_correlation' holds values that are not correlation "
                                         "coefficients; expected finite |values| <= 1")
            object.__setattr__(self, "line_correlation", corr)
        if self.lag_window is not None:
            lag = _frozen(self.lag_window, float)
            if lag.ndim != 1 or not np.all(np.isfinite(lag)):
                raise FRFValidationError("field 'lag_window' must be a finite 1-D array (one value per lag)")
            object.__setattr__(self, "lag_window", lag)
        if self.variance_model is not None:
            variance = _frozen(self.variance_model, float)
            if variance.ndim != 1 or np.any(np.isinf(variance)) or np.any(variance < 0):
                raise FRFValidationError("field 'variance_model' must hold one variance >= 0 (or NaN) per line")
            object.__setattr__(self, "variance_model", variance)
        if self.record_influence is not None:
            value = _frozen(self.record_influence, complex)
            if value.ndim not in (2, 3) or not np.all(np.isfinite(value)):
                raise FRFValidationError("field 'record_influence' must be a finite array of records × lines "
                                         "(or channels × records × lines)")
            object.__setattr__(self, "record_influence", value)
        if self.relative_error is not None and not isinstance(self.relative_error, (CommonError, JoinedError)):
            raise FRFValidationError(f"field 'relative_error' is a {type(self.relative_error).__name__}; expected "
                                     "a CommonError or JoinedError (modal.estimate.common_error)")
        if not (isinstance(self.overlapping_records, (int, np.integer)) and self.overlapping_records >= 0):
            raise FRFValidationError(f"field 'overlapping_records' is {self.overlapping_records!r}; "
                                     "expected an integer >= 0")
        if not (np.isfinite(self.sample_interval_s) and self.sample_interval_s > 0):
            raise FRFValidationError(f"field 'sample_interval_s' is {self.sample_interval_s!r}; expected a time in s")

    @property
    def n_lags(self) -> int:
        """Neighbouring lines whose correlation is carried."""
        return 0 if self.line_correlation is None else self.line_correlation.shape[0]

    def smoothing_inflation(self, lines: int) -> float:
        """Variance inflation 1 + 2 Σ (1 − m/K)|ρ(m)|² of a noise power averaged over K = ``lines`` neighbouring
        lines whose errors correlate by ρ (the median over the lines)."""
        if lines <= 1 or self.line_correlation is None:
            return 1.0
        m = np.arange(1, min(lines, self.n_lags + 1))
        rho = self._lag_correlation[m - 1]
        return 1.0 + 2.0 * float(np.sum((1 - m / lines) * rho**2))

    @functools.cached_property
    def _lag_correlation(self) -> np.ndarray:
        """|ρ(m)| of every lag m = 1 … n_lags, the median over the lines (each row's own median: the
        same values whichever lags are asked; :func:`modal.sdof.bands.smoothing_lines` asks for one more
        lag at each of up to 20 steps)."""
        return np.median(np.abs(self.line_correlation), axis=1)

    def cropped(self, keep: np.ndarray) -> "NoiseModel":
        """The model on the lines ``keep`` (bool over the lines, a contiguous run keeps every correlation).

        Lines dropped from inside the run break the neighbour relation: the correlation is then dropped.
        """
        variance = None if self.variance_model is None else self.variance_model[keep]
        influence = None if self.record_influence is None else self.record_influence[..., keep]
        common = None if self.relative_error is None else self.relative_error.cropped(keep)
        if self.line_correlation is None:
            return replace(self, variance_model=variance, record_influence=influence, relative_error=common)
        lines = np.flatnonzero(keep)
        if lines.size and np.any(np.diff(lines) != 1):
            return replace(self, line_correlation=None, variance_model=variance, record_influence=influence,
                           relative_error=common)
        corr = self.line_correlation[:, keep].copy()
        for m in range(1, corr.shape[0] + 1):  # the last m lines have no neighbour m lines on
            corr[m - 1, max(corr.shape[1] - m, 0):] = 0
        return replace(self, line_correlation=corr, variance_model=variance, record_influence=influence,
                       relative_error=common)

    def scaled(self, factor: np.ndarray, frf_factor: np.ndarray | None = None) -> "NoiseModel":
        """The model of the FRF times a factor per line whose phase is the same on every line (a change of
        kind, (iω)^p): the variance model times ``factor`` (|scale|², one value per line); the correlation
        is unchanged; the records' influences times ``frf_factor`` (the scale itself, complex; None: they are
        dropped, their phase unknown)."""
        influence = None
        if self.record_influence is not None and frf_factor is not None:
            influence = self.record_influence * np.asarray(frf_factor)
        variance = None if self.variance_model is None else self.variance_model * np.asarray(factor, float)
        return replace(self, variance_model=variance, record_influence=influence)

    def correlation_band(self, lines: np.ndarray) -> np.ndarray | None:
        """The correlation matrix R of the errors on the lines with indices ``lines`` (ascending), in LAPACK's
        lower banded storage: ``band[d, j] = R[j + d, j]`` for d = 0 … n_lags (R is zero beyond: lines more
        than ``n_lags`` apart do not correlate, and neither do lines further apart in ``lines``)."""
        if self.line_correlation is None:
            return None
        lines = np.asarray(lines, int)
        n = lines.size
        band = np.zeros((self.n_lags + 1, n), complex)
        band[0] = 1.0
        for d in range(1, min(self.n_lags, n - 1) + 1):
            gap = lines[d:] - lines[:-d]  # lines j + d and j are gap lines apart
            ok = gap <= self.n_lags
            j = np.flatnonzero(ok)
            band[d, j] = np.conj(self.line_correlation[gap[j] - 1, lines[j]])
        return band


def window_line_correlation(window: np.ndarray) -> np.ndarray:
    """c(m) = Σ w[n]² e^{2πimn/N} / Σ w²: the correlation of line k with line k + m of a windowed white
    noise's DFT, for m = 0 … N − 1 (c(0) = 1)."""
    power = np.asarray(window, float) ** 2
    return np.conj(np.fft.fft(power)) / power.sum()


def lags_carried(correlation: np.ndarray, n_lines: int) -> int:
    """Lags to carry: up to the last m with |c(m)| at or above :data:`CORRELATION_FLOOR`, within the caps."""
    half = correlation[1:correlation.size // 2 + 1]
    above = np.flatnonzero(np.abs(half) >= CORRELATION_FLOOR)
    wanted = 0 if above.size == 0 else int(above[-1]) + 1
    return int(min(wanted, MAX_LAGS, MAX_CORRELATION_VALUES // max(n_lines, 1)))


def lag_window(input_window: np.ndarray, output_window: np.ndarray, mean_square: np.ndarray) -> np.ndarray:
    """ρ(τ), τ = 0 … N − 1, from the windows and the excitation's mean square at each sample of a record.

    ρ(τ) = Σ_n w_out[n] u[n − τ] / Σ_n w_in[n] u[n], u = w_in · v (see the module).
    """
    u = np.asarray(input_window, float) * np.asarray(mean_square, float)
    n = u.size
    size = 1 << int(np.ceil(np.log2(2 * n)))
    # Σ_n w_out[n] u[n − τ]: the cross-correlation, by one product of transforms
    corr = np.fft.irfft(np.fft.rfft(output_window, size) * np.conj(np.fft.rfft(u, size)), size)[:n]
    scale = float(np.dot(input_window, u))
    return corr / scale if scale > 0 else np.ones(n)


#: reweighting rounds of :func:`input_noise_split`'s fit
SPLIT_ROUNDS = 5
#: the two-part noise model holds on lines where the excitation's noise power is below this fraction of the
#: excitation's (H1's bias, q/(1 + q) for a fraction q, then stays below 9 %, and the model's |H|² within
#: 18 %, a small error of a line weight's shape; a hammer test without a force window, its force noise over
#: the whole record, is near 1 % on many lines)
INPUT_NOISE_LIMIT = 0.1


def input_noise_split(residual_power: np.ndarray, frf_power: np.ndarray,
                      lines: np.ndarray | None = None) -> tuple[float, float]:
    """The residual power of an H1 estimate split into the response's noise and the excitation's.

    An H1 estimate from a measured excitation x + n_x and response y + n_y leaves, per record and line, the
    residual n_y − H n_x: its power is a + b |H|² with a = E|N_y|² (the same on every line for white noise
    through the same window) and b = E|N_x|² (the excitation's noise, carried into the FRF in proportion to
    it). Fitted over the lines by least squares relative to the model (each line's power scatters in
    proportion to its mean), with a, b ≥ 0.

    Parameters
    ----------
    residual_power : ndarray, shape (n_lines,)
        Σ|Y − ĤX|² / (n − 1) per line.
    frf_power : ndarray, shape (n_lines,)
        |Ĥ|² per line.
    lines : ndarray of bool, shape (n_lines,), optional
        The lines to fit on (default all).

    Returns
    -------
    (a, b) : the response noise's power and the excitation noise's (per record, in the spectra's units).
    """
    r = np.asarray(residual_power, float)
    h = np.asarray(frf_power, float)
    ok = np.isfinite(r) & np.isfinite(h) & (r > 0)
    if lines is not None:
        ok &= np.asarray(lines, bool)
    r, h = r[ok], h[ok]
    if r.size < 3:
        return (float(np.median(r)) if r.size else 0.0), 0.0
    # the weighted problem by its sums: each round costs a few passes over the lines instead of forming the
    # weighted design (65 537 lines × 16 outputs × 3 calls in a long shaker record's estimate); in units of the
    # median residual and the largest |H|², so that the squared weights stay within floating point's range
    r_unit = float(np.median(r))
    h_unit = float(h.max()) if h.max() > 0 else 1.0
    r, h = r / r_unit, h / h_unit
    h_square, hr, rr = h * h, h * r, r * r
    a, b = 1.0, 0.0
    w2 = np.ones(r.size)  # the first round: every line counts alike, relative to the median
    for _ in range(SPLIT_ROUNDS):
        sums = np.array([w2.sum(), w2 @ h, w2 @ h_square, w2 @ r, w2 @ hr, w2 @ rr])
        fitted = _nonnegative_fit_of_sums(sums)
        if fitted is None:  # the two columns nearly parallel: the weighted design itself, solved by lstsq
            weight = np.sqrt(w2)
            fitted = _nonnegative_fit(np.column_stack([weight, h * weight]), r * weight)
        a, b = fitted
        model = a + b * h
        if not np.all(model > 0):
            break
        w2 = 1.0 / np.maximum(model, 1e-150 * r.max()) ** 2
    return float(a * r_unit), float(b * r_unit / h_unit)


#: the normal equations of the two scaled columns are solved while 1 − ρ² (ρ the cosine between the columns)
#: stays above this; their rounding, about 1e-16 / (1 − ρ²) relative, then stays below 1e-10
NORMAL_EQUATIONS_FLOOR = 1e-6


def _nonnegative_fit_of_sums(sums: np.ndarray) -> tuple[float, float] | None:
    """:func:`_nonnegative_fit` from the problem's sums: with columns x0, x1 and target t, ``sums`` is
    (x0·x0, x0·x1, x1·x1, x0·t, x1·t, t·t). None where the columns are too near parallel for the normal
    equations (:data:`NORMAL_EQUATIONS_FLOOR`)."""
    g00, g01, g11, t0, t1, tt = (float(v) for v in sums)
    if not (g00 > 0 and g11 > 0):
        return None
    n0, n1 = np.sqrt(g00), np.sqrt(g11)
    rho, u0, u1 = g01 / (n0 * n1), t0 / n0, t1 / n1  # scaled to unit columns: |H|² may be 1e-13 of the constant
    det = 1.0 - rho * rho
    if det < NORMAL_EQUATIONS_FLOOR:
        return None
    c0, c1 = (u0 - rho * u1) / det, (u1 - rho * u0) / det
    if c0 >= 0 and c1 >= 0:
        return c0 / n0, c1 / n1
    # a column alone, clipped at 0 (cost tt − u²), else neither (cost tt): the convex problem's minimum is the
    # best of these active sets
    best, best_cost = (0.0, 0.0), tt
    for value, cost, fit in ((u0, tt - u0 * u0, (max(u0, 0.0) / n0, 0.0)),
                             (u1, tt - u1 * u1, (0.0, max(u1, 0.0) / n1))):
        if value > 0 and cost < best_cost:
            best, best_cost = fit, cost
    return best


def _nonnegative_fit(design: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """Least squares of two coefficients, both ≥ 0 (the problem ``scipy.optimize.nnls`` solves, whose import,
    with scipy.linalg's, cost a time-record fit 0.4 CPU-s): the unconstrained fit if it is non-negative, else
    the better of the fits of one column alone (clipped at 0). The problem is convex, so the best feasible
    point of these active sets is its minimum."""
    # columns scaled to unit length first: |H|² may be 1e-13 of the constant column, which lstsq's cut of small
    # singular values would otherwise drop (its coefficient set to 0)
    norms = np.sqrt(np.sum(design**2, axis=0))
    norms = np.where(norms > 0, norms, 1.0)
    coefficients = np.linalg.lstsq(design / norms, target, rcond=None)[0] / norms
    if np.all(coefficients >= 0):
        return float(coefficients[0]), float(coefficients[1])
    best, best_cost = (0.0, 0.0), float(target @ target)
    for column in (0, 1):
        x = design[:, column]
        norm = float(x @ x)
        value = max(float(x @ target) / norm, 0.0) if norm > 0 else 0.0
        cost = float(np.sum((target - value * x) ** 2))
        if cost < best_cost:
            best, best_cost = ((value, 0.0) if column == 0 else (0.0, value)), cost
    return best
