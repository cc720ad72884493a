"""What generates the covariance of an estimate's excitation-noise error, and its factor on a fit's lines.

The relative error η every output of a hammer estimate shares (:mod:`modal.estimate.common_error`) has the
covariance E[η_k η*_l] = W(k − l) Σ_i g_i(k) g_i*(l), g_i = X_i*/S the force spectrum of record i over the
summed power and W(d) = σ² Σ_n w[n]² e^{−2πidn/N} the squared excitation window's transform (σ the force
noise's standard deviation per sample). :class:`CommonError` keeps g, the window's support and σ w; a fit asks
for a factor on its lines (:meth:`CommonError.factor`): on a band of tens to hundreds of lines the lines'
covariance is small, where the rows (records × window samples) over every line of a 16384-sample record would
be a hundred MB.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CommonError", "JoinedError", "MAX_FACTOR_SIZE", "MAX_EIGEN_SIZE", "MAX_FACTOR_BYTES", "FACTOR_TOLERANCE",
           "SKETCH_COLUMNS"]

#: the factor of a set of lines comes from an eigendecomposition of the smaller of its two Gram matrices, lines ×
#: lines (the covariance) or rows × rows (records × window samples), of at most this size (1024²: 0.3 s at the
#: worst); a fit's band of tens to hundreds of lines is always within it, every line of a long record with
#: hundreds of hits' samples is not (that fit goes without it)
MAX_FACTOR_SIZE = 1024
#: a Gram matrix whose rank exceeds the random sketch's columns (:func:`_eigen`) is decomposed whole up to this
#: size (a 4-hit test of 8 s records with a 138-sample force window: 552 rows, 0.2 s); beyond (every line of
#: 16384-sample records with 3 hits of 266 force-window samples, 798 rows of rank 276: 1.5 s a fit, and a factor
#: of 36 MB per channel), no factor is formed
MAX_EIGEN_SIZE = 640
#: a factor of more bytes than this (rows kept × lines) is not formed: its fit goes without it
MAX_FACTOR_BYTES = 64 * 2**20
#: eigenvalues of the covariance below this fraction squared of the largest are dropped (their variance is 1e-8
#: of it)
FACTOR_TOLERANCE = 1e-4
#: columns of the first random sketch of a Gram matrix's range (:func:`_eigen`): a force window's rows (12 hits ×
#: 42 samples on the bench) span about 50 directions
SKETCH_COLUMNS = 64
#: values per block of transforms forming a factor from the rows' side (32 MiB of complex values)
_BLOCK_VALUES = 1 << 21


def frozen(value, dtype) -> np.ndarray:
    """``value`` as a read-only array of ``dtype``: itself when it is one already (a noise model made from
    another by ``replace``, whose arrays may be tens of MB: records' influences of 4 channels × 256 records × 4097
    lines), else a copy, so that no caller's array is frozen or shared."""
    if isinstance(value, np.ndarray) and value.dtype == np.dtype(dtype) and not value.flags.writeable:
        return value
    copy = np.array(value, dtype=dtype)
    copy.setflags(write=False)
    return copy


@dataclass(frozen=True, eq=False)
class CommonError:
    """What generates the covariance of the relative error η the outputs of one estimate share
    (:mod:`modal.estimate.common_error`).

    Attributes
    ----------
    gains : ndarray, shape (n_records, n_lines), complex
        g_i(k) = X_i*(k) / S_xx(k) on each line, in 1/(the force spectrum's unit).
    lines : ndarray, shape (n_lines,), int
        Each line's index k in its record's transform (the FRF's lines, cropped or reordered).
    support : ndarray, shape (n_support,), int
        The samples n of a record the excitation window keeps.
    amplitude : ndarray, shape (n_support,)
        σ w[n] on them, in the force's unit: σ the excitation noise's standard deviation per sample.
    length : int
        N, samples per record.
    """

    gains: np.ndarray
    lines: np.ndarray
    support: np.ndarray
    amplitude: np.ndarray
    length: int

    def __post_init__(self) -> None:
        for name, dtype in (("gains", complex), ("lines", np.int64), ("support", np.int64), ("amplitude", float)):
            object.__setattr__(self, name, frozen(getattr(self, name), dtype))
        if (self.gains.ndim != 2 or self.lines.shape != self.gains.shape[1:]
                or self.amplitude.shape != self.support.shape
                or not np.all(np.isfinite(self.gains)) or not np.all(np.isfinite(self.amplitude))):
            raise ValueError("a common error needs finite gains (records × lines), one index per line and one "
                             "amplitude per support sample")

    @property
    def n_lines(self) -> int:
        """Lines carried."""
        return self.lines.size

    def cropped(self, keep) -> "CommonError":
        """On the lines ``keep`` (a bool mask over the lines or their indices, in any order)."""
        return CommonError(self.gains[:, keep], self.lines[keep], self.support, self.amplitude, self.length)

    def window_transform(self, offset: np.ndarray) -> np.ndarray:
        """W(d) = Σ_n σ² w[n]² e^{−2πidn/N} for the line offsets ``offset`` (d = k − l)."""
        grid = np.zeros(self.length)
        grid[self.support] = self.amplitude**2
        return np.fft.fft(grid)[np.asarray(offset) % self.length]

    def lagged(self, m: int) -> np.ndarray:
        """E[η_k η*_{k+m}] for the positions k = 0 … n_lines − m − 1 (m = 0: the variance of every line)."""
        end = self.n_lines - m
        power = np.sum(self.gains[:, :end] * self.gains[:, m:].conj(), axis=0)
        return self.window_transform(self.lines[:end] - self.lines[m:]) * power

    def factor(self, keep=None) -> np.ndarray | None:
        """P, shape (n_factors, n_kept) complex, on the lines ``keep`` (bool mask or indices; default all):
        E[η_k η*_l] = Σ_r P_rk conj(P_rl), with the eigenvalues below :data:`FACTOR_TOLERANCE` squared of the
        largest dropped. None where both Gram matrices exceed :data:`MAX_FACTOR_SIZE`, the smaller's rank exceeds
        the sketch's and its size :data:`MAX_EIGEN_SIZE` (:func:`_eigen`), or P :data:`MAX_FACTOR_BYTES`.

        Fewer lines than rows (a fit's band): P = Λ^½ Vᴴ from the lines' covariance V Λ Vᴴ, W(k − l) Σ_i g_i(k)
        g_i*(l). Else from the rows' Gram matrix, whose entry of rows (i, n) and (j, m) is
        σ² w[n] w[m] Σ_k g_i(k) g_j*(k) e^{−2πik(n−m)/N}, one transform per pair of records, and P = Uᴴ rows on
        its eigenvectors U, Σ_i g_i(k) Σ_n conj(U_(i,n)r) σ w[n] e^{−2πikn/N}, one transform per record and row.
        The last lines' factor is kept (read-only): a band's fits ask for it several times.
        """
        key = None if keep is None else np.arange(self.n_lines)[keep].tobytes()
        last = self.__dict__.get("_last")  # (lines, their factor) last formed: no field, not archived
        if last is not None and last[0] == key:
            return last[1]
        part = self if keep is None else self.cropped(keep)
        factor = part._factor()
        if factor is not None:
            factor.setflags(write=False)
        object.__setattr__(self, "_last", (key, factor))
        return factor

    def _factor(self) -> np.ndarray | None:
        n_records, n_lines = self.gains.shape
        n_rows = n_records * self.support.size
        if min(n_lines, n_rows) > MAX_FACTOR_SIZE:
            return None
        if n_lines <= n_rows:
            covariance = (self.window_transform(np.subtract.outer(self.lines, self.lines))
                          * (self.gains.T @ self.gains.conj()))
            eigen = _eigen(covariance)
            if eigen is None:
                return None
            power, vectors = eigen
            kept = _kept(power)
            if kept.sum() * n_lines * 16 > MAX_FACTOR_BYTES:
                return None
            return np.sqrt(power[kept])[:, None] * vectors[:, kept].T
        return self._factor_from_rows(n_rows)

    def _factor_from_rows(self, n_rows: int) -> np.ndarray | None:
        n_records, n_support, size = self.gains.shape[0], self.support.size, self.length
        on_grid = np.zeros((n_records, size), complex)
        on_grid[:, self.lines] = self.gains
        # F_ij(d) = Σ_k g_i(k) g_j*(k) e^{−2πikd/N} at the support's differences d = n − m
        difference = np.subtract.outer(self.support, self.support) % size
        gram = np.empty((n_records, n_support, n_records, n_support), complex)
        for i in range(n_records):
            transforms = np.fft.fft(on_grid[i] * on_grid.conj(), axis=-1)  # (n_records j, N)
            gram[i] = transforms[:, difference].transpose(1, 0, 2)
        gram *= np.multiply.outer(self.amplitude, self.amplitude)[None, :, None, :]
        eigen = _eigen(gram.reshape(n_rows, n_rows))
        if eigen is None:
            return None
        power, vectors = eigen
        kept = _kept(power)
        if kept.sum() * self.n_lines * 16 > MAX_FACTOR_BYTES:
            return None
        weights = (vectors[:, kept].conj().reshape(n_records, n_support, -1)
                   * self.amplitude[None, :, None])  # (n_records, n_support, n_kept)
        out = np.zeros((weights.shape[-1], self.n_lines), complex)
        block = max(1, _BLOCK_VALUES // size)
        for first in range(0, out.shape[0], block):
            for i in range(n_records):
                grid = np.zeros((min(block, out.shape[0] - first), size), complex)
                grid[:, self.support] = weights[i, :, first:first + block].T
                out[first:first + block] += np.fft.fft(grid, axis=-1)[:, self.lines] * self.gains[i]
        return out


def _eigen(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The eigenvalues (ascending) and eigenvectors of a Hermitian positive semi-definite ``matrix`` that carry it
    but for what :data:`FACTOR_TOLERANCE` may drop: its rank is a few dozen where it is hundreds wide (a force
    window's few dozen samples span as few directions over a band).

    Q, an orthonormal basis of ``matrix`` Ω for a fixed Gaussian Ω of :data:`SKETCH_COLUMNS` columns
    (Halko, Martinsson & Tropp 2011), holds its range when what Q leaves out, tr(M) − tr(Qᴴ M Q) (the rows'
    squared norm Q misses, for M = L Lᴴ), is below what the tolerance may drop; then M's eigenpairs are Qᴴ M Q's,
    their vectors times Q. The sketch doubles once if it does not; then (a rank of hundreds, where sketches cost
    more) the eigendecomposition of ``matrix`` itself, up to :data:`MAX_EIGEN_SIZE` wide; None beyond (its
    factor of hundreds of rows over thousands of lines would not fit the fits' memory either)."""
    size = matrix.shape[0]
    total = float(np.trace(matrix).real)
    columns = min(SKETCH_COLUMNS, size)
    rng = np.random.default_rng(0)  # fixed: the same file gives the same factor
    while columns < size and columns <= 2 * SKETCH_COLUMNS:  # a sketch that fails twice: the rank is high
        q, _ = np.linalg.qr(matrix @ rng.standard_normal((size, columns)))
        power, vectors = np.linalg.eigh(q.conj().T @ matrix @ q)
        if total - float(np.sum(power)) <= FACTOR_TOLERANCE**2 * power[-1] * size:
            return power, q @ vectors
        columns *= 2
    return np.linalg.eigh(matrix) if size <= MAX_EIGEN_SIZE else None


def _kept(power: np.ndarray) -> np.ndarray:
    """The eigenvalues (ascending) kept: above :data:`FACTOR_TOLERANCE` squared of the largest."""
    return power > FACTOR_TOLERANCE**2 * max(float(power[-1]), 0.0) if power.size else np.zeros(0, bool)


@dataclass(frozen=True, eq=False)
class JoinedError:
    """The common errors of estimates joined channel-wise (:mod:`modal.roving`): each part's channels take its own
    factor over its own ξ, independent of the others' (the parts' records are independent).

    Attributes
    ----------
    parts : tuple of CommonError
        One per joined estimate, on the same lines.
    channels : tuple of int
        The joined FRF's channels of each part, in order.
    """

    parts: tuple
    channels: tuple

    def __post_init__(self) -> None:
        object.__setattr__(self, "parts", tuple(self.parts))
        object.__setattr__(self, "channels", tuple(int(c) for c in self.channels))
        if (len(self.parts) != len(self.channels) or not all(isinstance(p, CommonError) for p in self.parts)
                or len({p.n_lines for p in self.parts}) > 1):
            raise ValueError("a joined common error needs one CommonError on the same lines per part and its "
                             "channel count")

    @property
    def n_lines(self) -> int:
        """Lines carried."""
        return self.parts[0].n_lines

    def cropped(self, keep) -> "JoinedError":
        """On the lines ``keep`` (as :meth:`CommonError.cropped`)."""
        return JoinedError(tuple(p.cropped(keep) for p in self.parts), self.channels)

    def factor(self, keep=None) -> np.ndarray | None:
        """Each channel's factor over one ξ, shape (n_channels, n_factors, n_kept): a part's factor
        (:meth:`CommonError.factor`) in its own block of factors, zero in the others'; None if a part's is."""
        factors = [p.factor(keep) for p in self.parts]
        if any(f is None for f in factors):
            return None
        n_factors, n_lines = sum(f.shape[0] for f in factors), factors[0].shape[1]
        if sum(self.channels) * n_factors * n_lines * 16 > MAX_FACTOR_BYTES:
            return None
        out = np.zeros((sum(self.channels), n_factors, n_lines), complex)
        channel = row = 0
        for f, count in zip(factors, self.channels):
            out[channel:channel + count, row:row + f.shape[0]] = f
            channel, row = channel + count, row + f.shape[0]
        return out


