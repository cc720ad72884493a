"""The error every output of a one-input estimate shares: the excitation channel's own noise.

An H1 estimate from a measured excitation x + n_x and responses y_o + n_o has, to first order,
the error Ĥ_o − H_o = (Σ_i N_o,i X*_i − H_o Σ_i N_x,i X*_i) / S_xx per line: the response noise's
part is each output's own, the excitation noise's is H_o η with one η = −Σ_i N_x,i X*_i / S_xx for
every output. Over the few dozen samples a force window keeps, η is smooth across the lines and
correlates the outputs' errors (on the bench's six accelerometers with a force window, the FRF
errors relative to H correlate by 0.4–0.8 between channels near a mode). A fit that takes the
channels as independent misses it.

With white noise of variance σ² per sample on the excitation, windowed by w,
E[η_k η*_l] = σ² Σ_i Σ_n w[n]² e^{−2πi(k−l)n/N} X*_ik X_il / (S_k S_l): a sum over the records and the
window's support of rank-one terms, one per (record, sample). :func:`common_error_factor` forms those
rows and keeps the few that carry them (their singular vectors), P with E[η η^H] = Pᵀ conj(P). σ² follows from the
excitation noise's power per record b (:func:`~modal.noise_model.input_noise_split`), E|N_x|² = σ² Σ w².
"""
from __future__ import annotations

import numpy as np

__all__ = ["common_error_factor", "compressed_factor", "SKETCH_COLUMNS", "MAX_SUPPORT_ROWS", "MAX_FACTOR_WORK", "MAX_UNCOMPRESSED_BYTES", "MAX_SUPPORT_FRACTION", "FACTOR_TOLERANCE"]

#: records × window samples at most (rows of the factor before it is compressed, :func:`compressed_factor`)
MAX_SUPPORT_ROWS = 1024
#: rows² × lines at most (the products the factor's Gram matrix costs: 1024 rows of 1025 lines, ~1 s at the
#: worst); beyond, as for a 16384-sample record's 8193 lines with 948 rows (7 s), the excitation's noise is left
#: to the line correlation
MAX_FACTOR_WORK = 1024**2 * 1025
#: the excitation window keeps at most this fraction of a record (a force window's few dozen samples); a window
#: over the whole record (a hammer test without a force window, a continuous estimate) is no short support: its
#: excitation noise is left to the line correlation
MAX_SUPPORT_FRACTION = 1 / 8
#: beyond MAX_FACTOR_WORK the rows themselves are the factor (P = rows, nothing compressed) if they take at most
#: this many bytes: a 4-hit test of 8 s records at 1 kHz with a 138-sample force window has 552 rows of 4097 lines
#: (36 MB), whose Gram matrix would cost 0.7 s, and without the factor its constants (and k, c, m) scattered 11
#: times their errors; the fits use only their bands' lines of it
MAX_UNCOMPRESSED_BYTES = 64 * 2**20
#: singular values of the factor below this fraction of the largest are dropped (their variance is 1e-8 of it)
FACTOR_TOLERANCE = 1e-4


def common_error_factor(excitation: np.ndarray, starts: np.ndarray, length: int, input_window: np.ndarray,
                        excitation_noise_power: float) -> np.ndarray | None:
    """P, shape (n_factors, n_lines) complex: E[η_k η*_l] = Σ_r P_rk conj(P_rl) for the relative error η the
    outputs share (see the module).

    Parameters
    ----------
    excitation : ndarray, shape (n_samples,)
        The excitation channel as the estimate read it (offset removed).
    starts : ndarray of int
        First sample of each record.
    length : int
        Samples per record.
    input_window : ndarray, shape (length,)
        The excitation's window.
    excitation_noise_power : float
        b, the excitation noise's power per record and line in the spectra's units (E|N_x|²).

    Returns
    -------
    ndarray or None
        None where the window's support over the records exceeds :data:`MAX_SUPPORT_ROWS` rows (or their
        Gram matrix :data:`MAX_FACTOR_WORK` products and the rows :data:`MAX_UNCOMPRESSED_BYTES`) or
        :data:`MAX_SUPPORT_FRACTION` of a record, the noise power is not positive, or a line holds no excitation.
    """
    window = np.asarray(input_window, float)
    support = np.flatnonzero(window != 0)
    starts = np.asarray(starts, np.int64)
    n_rows = support.size * starts.size
    n_lines = length // 2 + 1
    compress = n_rows**2 * n_lines <= MAX_FACTOR_WORK
    if (not excitation_noise_power > 0 or n_rows > MAX_SUPPORT_ROWS or support.size == 0
            or support.size > MAX_SUPPORT_FRACTION * length
            or not (compress or n_rows * n_lines * 16 <= MAX_UNCOMPRESSED_BYTES)):
        return None
    records = np.stack([excitation[s:s + length] for s in starts]) * window  # (n_records, length)
    spectra = np.fft.rfft(records, axis=-1)
    power = np.sum(np.abs(spectra) ** 2, axis=0)
    if not np.all(power > 0):
        return None
    sigma = np.sqrt(excitation_noise_power / float(np.sum(window**2)))
    lines = np.arange(length // 2 + 1)
    # row (i, n): σ w[n] e^{−2πikn/N} X*_ik / S_k
    phase = np.exp(-2j * np.pi * np.outer(support, lines) / length) * (sigma * window[support])[:, None]
    rows = (phase[None, :, :] * (spectra.conj() / power)[:, None, :]).reshape(-1, lines.size)
    return compressed_factor(rows) if compress else rows


#: columns of the first random sketch of the rows' range (:func:`compressed_factor`): a force window's rows
#: (12 hits × 42 samples on the bench) span about 50 directions
SKETCH_COLUMNS = 64


def compressed_factor(rows: np.ndarray) -> np.ndarray:
    """P with Pᴴ P = rowsᴴ rows, of as few rows as the singular values of ``rows`` above
    :data:`FACTOR_TOLERANCE` of the largest (the rest dropped, as their variance is 1e-8 of it).

    P = Uᴴ rows on the kept left singular vectors U of ``rows``. Their range is found by a random sketch
    (Halko, Martinsson & Tropp 2011): Q, an orthonormal basis of ``rows`` Ω for a fixed Gaussian Ω of a few more
    columns than the rank, holds it when what Q leaves out, ‖rows‖² − ‖Qᴴ rows‖² (exact, Q orthonormal), is
    below what the tolerance may drop; the small Qᴴ rows then give P (:func:`_kept_factor`). The sketch doubles
    once if it does not; then (a rank of hundreds, where sketches cost more) the factor comes from all the rows
    at once, exactly. An eigendecomposition of every row's Gram matrix (504² for 12 hits × 42 samples) cost
    0.15 s a hammer file, against the sketch's two products.
    """
    n_rows = rows.shape[0]
    total = float(np.sum(np.abs(rows) ** 2))
    columns = min(SKETCH_COLUMNS, n_rows)
    rng = np.random.default_rng(0)  # fixed: the same file gives the same factor
    while columns < n_rows and columns <= 2 * SKETCH_COLUMNS:  # a sketch that fails twice: the rank is high
        q, _ = np.linalg.qr(rows @ rng.standard_normal((rows.shape[1], columns)))
        power, factor = _kept_factor(q.conj().T @ rows)
        if total - float(np.sum(power)) <= FACTOR_TOLERANCE**2 * power[-1] * n_rows:
            return factor
        columns *= 2
    return _kept_factor(rows)[1]


def _kept_factor(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(every squared singular value of ``rows``, ascending; Uᴴ rows on those above :data:`FACTOR_TOLERANCE`
    of the largest), U from the eigenvectors of the rows' small Gram matrix (rows × rows: an SVD of the rows
    themselves, as wide as the lines, costs several times more)."""
    power, vectors = np.linalg.eigh(rows @ rows.conj().T)
    kept = power > FACTOR_TOLERANCE**2 * power[-1]
    return power, vectors[:, kept].conj().T @ rows
