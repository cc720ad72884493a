"""Cross-spectral sums over records and the FRF estimators built on them.

The sums are accumulated block by block (a bounded number of records at a
time), so a long record is never held twice in memory: any array-like that
slices along its last axis (ndarray, ``np.memmap``, an h5py dataset) streams.

Conventions, per frequency line and summed over the n records (not averaged;
the scale cancels in every estimator):

* ``sxx[i, j] = Σ X_i conj(X_j)`` (inputs × inputs, Hermitian),
* ``syx[o, i] = Σ Y_o conj(X_i)`` (Bendat & Piersol's G_xy for one pair),
* ``syy[o] = Σ |Y_o|²``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["SpectralSums", "accumulate", "overlap_variance_factor", "h1", "h2", "hv", "ESTIMATORS"]

ESTIMATORS: tuple[str, ...] = ("H1", "H2", "Hv")
#: bytes of complex spectra held at once while accumulating
_BLOCK_BYTES = 64 * 2**20


@dataclass(frozen=True)
class SpectralSums:
    """Sums of auto- and cross-spectra over ``n_records`` records.

    Attributes
    ----------
    sxx : ndarray, shape (n_inputs, n_inputs, n_lines)
    syx : ndarray, shape (n_outputs, n_inputs, n_lines)
    syy : ndarray, shape (n_outputs, n_lines)
    n_records : int
    sxx_lag : ndarray, shape (n_lags, n_lines), optional
        One input: ``Σ conj(X_k) X_{k+m}`` for m = 1 … n_lags (zero past the last line).
    excitation_square : ndarray, shape (length,), optional
        Σ x[n]² over the records at each sample n of a record (unwindowed); several inputs: summed over them.
    error_products : ndarray, shape (4, n_lags + 1, n_lines), optional
        One input and one output: with p = Y conj(X) and q = |X|² per record and line, the sums over the
        records of p_k conj(p_{k+m}), p_k q_{k+m}, q_k conj(p_{k+m}) and q_k q_{k+m} for m = 0 … n_lags
        (zero past the last line): each line's error products over the records
        (:func:`modal.estimate.error_correlation.measured_line_correlation`).
    record_cross, record_power : ndarray, shape (n_records, n_lines), optional
        One input and one output, when asked: each record's Y conj(X) (complex) and |X|² (real), the terms
        of the sums above record by record (:mod:`modal.estimate.record_influence`).
    record_input : ndarray, shape (n_records, n_inputs, n_lines), optional
    record_output : ndarray, shape (n_records, n_outputs, n_lines), optional
        Several channels (inputs or outputs), when asked: each record's spectra X and Y, windowed as summed
        (:func:`modal.estimate.record_influence.channel_influence`).
    """

    sxx: np.ndarray
    syx: np.ndarray
    syy: np.ndarray
    n_records: int
    sxx_lag: np.ndarray | None = None
    excitation_square: np.ndarray | None = None
    error_products: np.ndarray | None = None
    record_cross: np.ndarray | None = None
    record_power: np.ndarray | None = None
    record_input: np.ndarray | None = None
    record_output: np.ndarray | None = None


def _records(signal, starts: np.ndarray, length: int) -> np.ndarray:
    """Records ``signal[:, s:s+length]`` for each start in ``starts`` (ascending), shape (channels, n, length)."""
    span = np.asarray(signal[:, int(starts[0]): int(starts[-1]) + length], dtype=float)
    offsets = starts - starts[0]
    windows = np.lib.stride_tricks.sliding_window_view(span, length, axis=-1)
    return windows[:, offsets, :]


def accumulate(excitation, response, starts, length: int, input_window: np.ndarray,
               output_window: np.ndarray, lags: int = 0, error_lags: int = 0,
               keep_records: bool = False) -> SpectralSums:
    """Sum the spectra of the records that start at ``starts``.

    Parameters
    ----------
    excitation : array_like, shape (n_inputs, n_samples)
    response : array_like, shape (n_outputs, n_samples)
    starts : array_like of int
        First sample of each record, ascending.
    length : int
        Samples per record.
    input_window, output_window : ndarray, shape (length,)
        Weights applied to the excitation and response records.
    lags : int
        One input: also sum the products of each line with the ``lags`` lines above it
        (``sxx_lag``) and the excitation's square at each sample (``excitation_square``).
    error_lags : int
        One input and one output: also sum the ``error_products`` over this many lags (0: not).
    keep_records : bool
        Also keep each record's terms: one input and one output, ``record_cross`` and ``record_power``; several
        channels, ``record_input`` and ``record_output``.
    """
    starts = np.asarray(starts, dtype=np.int64)
    n_in, n_out = excitation.shape[0], response.shape[0]
    n_lines = length // 2 + 1
    sxx = np.zeros((n_in, n_in, n_lines), complex)
    syx = np.zeros((n_out, n_in, n_lines), complex)
    syy = np.zeros((n_out, n_lines))
    one_input = n_in == 1
    sxx_lag = np.zeros((lags, n_lines), complex) if one_input else None
    square = np.zeros(length)
    error_lags = min(error_lags, n_lines - 1) if one_input and n_out == 1 else 0
    products = np.zeros((4, error_lags + 1, n_lines), complex) if error_lags > 0 else None
    keep_spectra = keep_records and not (one_input and n_out == 1)
    keep_records = keep_records and one_input and n_out == 1
    record_cross = np.zeros((starts.size, n_lines), complex) if keep_records else None
    record_power = np.zeros((starts.size, n_lines)) if keep_records else None
    record_input = np.zeros((starts.size, n_in, n_lines), complex) if keep_spectra else None
    record_output = np.zeros((starts.size, n_out, n_lines), complex) if keep_spectra else None
    per_record = (n_in + n_out) * n_lines * 16 + (n_in + n_out) * length * 8
    block = max(1, int(_BLOCK_BYTES // max(per_record, 1)))
    for first in range(0, starts.size, block):
        chunk = starts[first:first + block]
        raw = _records(excitation, chunk, length)
        x = np.fft.rfft(raw * input_window, axis=-1)
        y = np.fft.rfft(_records(response, chunk, length) * output_window, axis=-1)
        xc = x.conj()
        sxx += np.einsum("isf,jsf->ijf", x, xc)
        syx += np.einsum("osf,isf->oif", y, xc)
        syy += np.einsum("osf,osf->of", y, y.conj()).real
        if one_input:
            square += np.einsum("sn,sn->n", raw[0], raw[0])
            for m in range(1, min(lags, n_lines - 1) + 1):
                sxx_lag[m - 1, :-m] += np.einsum("sf,sf->f", xc[0, :, :-m], x[0, :, m:])
        else:
            square += np.einsum("isn,isn->n", raw, raw)
        if products is not None or keep_records:
            cross, power = y[0] * xc[0], (x[0] * xc[0]).real
            if products is not None:
                _add_error_products(products, cross, power)
            if keep_records:
                record_cross[first:first + chunk.size], record_power[first:first + chunk.size] = cross, power
        if keep_spectra:
            record_input[first:first + chunk.size] = x.transpose(1, 0, 2)
            record_output[first:first + chunk.size] = y.transpose(1, 0, 2)
    return SpectralSums(sxx, syx, syy, int(starts.size), sxx_lag, square, products, record_cross, record_power,
                        record_input, record_output)


def _add_error_products(products: np.ndarray, cross: np.ndarray, power: np.ndarray) -> None:
    """Add the records' p_k conj(p_{k+m}), p_k q_{k+m}, q_k conj(p_{k+m}), q_k q_{k+m} (p = ``cross``,
    q = ``power``, each (records, lines)) to ``products`` (4, lags + 1, lines)."""
    n_lines = cross.shape[1]
    for m in range(products.shape[1]):
        end = n_lines - m
        left_p, left_q = cross[:, :end], power[:, :end]
        right_p, right_q = cross[:, m:].conj(), power[:, m:]
        products[0, m, :end] += np.einsum("sf,sf->f", left_p, right_p)
        products[1, m, :end] += np.einsum("sf,sf->f", left_p, right_q)
        products[2, m, :end] += np.einsum("sf,sf->f", left_q, right_p)
        products[3, m, :end] += np.einsum("sf,sf->f", left_q, right_q)


def overlap_variance_factor(window: np.ndarray, step: int) -> float:
    """Variance inflation of an average over overlapping records, 1 + 2 Σ ρ_m².

    ρ_m = Σ w[n] w[n + m·step] / Σ w² is the correlation of a white noise's
    spectral line between records m steps apart (Welch 1967). 1 without overlap;
    1.06 for Hann at 50 %; 1.5 for a rectangular window at 50 %.
    """
    length = window.size
    energy = float(np.dot(window, window))
    factor = 1.0
    lag = step
    while 0 < lag < length:
        rho = float(np.dot(window[:-lag], window[lag:])) / energy
        factor += 2.0 * rho * rho
        lag += step
    return factor


def _guard_input_power(sxx_diag: np.ndarray, source: str) -> None:
    if np.any(sxx_diag <= 0):
        line = int(np.argwhere(sxx_diag <= 0)[0][-1])
        raise ParameterError(
            f"{source}: the excitation has no power at line {line}; an FRF cannot be estimated there "
            "(check the excitation channel, or crop the band)"
        )


def h1(sums: SpectralSums, source: str = "<array>"):
    """H1 (least squares with noise on the response), SISO or MIMO.

    Returns
    -------
    frf : ndarray, shape (n_outputs, n_inputs, n_lines)
    coherence : ndarray, same shape
        Ordinary coherence of each input–output pair.
    multiple_coherence : ndarray, shape (n_outputs, n_lines)
    variance : ndarray, shape (n_outputs, n_inputs, n_lines) or None
        E|Ĥ − H|² from the residual (n − n_inputs degrees of freedom), before the overlap factor;
        None when n_records <= n_inputs.
    """
    n_in = sums.sxx.shape[0]
    diag = np.einsum("iif->if", sums.sxx).real
    _guard_input_power(diag, source)
    sxx_t = np.moveaxis(sums.sxx, -1, 0)  # (F, i, j)
    syx_t = np.moveaxis(sums.syx, -1, 0)  # (F, o, i)
    if n_in == 1:
        frf_t = syx_t / sxx_t
        inv_diag = 1.0 / diag  # (1, F)
    else:
        if sums.n_records < n_in:
            raise ParameterError(
                f"{source}: {sums.n_records} records cannot separate {n_in} inputs; "
                "MIMO H1 needs more records (averages) than excitation channels"
            )
        try:
            inv = np.linalg.inv(sxx_t)  # (F, i, j)
        except np.linalg.LinAlgError:
            raise ParameterError(
                f"{source}: the excitation channels are fully correlated at some line; "
                "MIMO H1 needs inputs that are not linear combinations of each other"
            ) from None
        frf_t = syx_t @ inv
        inv_diag = np.einsum("fii->if", inv).real
    frf = np.moveaxis(frf_t, 0, -1)  # (o, i, F)
    syy = np.maximum(sums.syy, np.finfo(float).tiny)
    explained = np.einsum("oif,oif->of", frf, sums.syx.conj()).real
    multiple = np.clip(explained / syy, 0.0, 1.0)
    coherence = np.clip(np.abs(sums.syx) ** 2 / (diag[np.newaxis, :, :] * syy[:, np.newaxis, :]), 0.0, 1.0)
    variance = None
    dof = sums.n_records - n_in
    if dof > 0:
        residual = np.maximum(sums.syy - explained, 0.0)  # Σ|Y − ĤX|²
        variance = (residual / dof)[:, np.newaxis, :] * inv_diag[np.newaxis, :, :]
    return frf, coherence, multiple, variance


def _siso(sums: SpectralSums, name: str, source: str):
    if sums.sxx.shape[0] != 1:
        raise ParameterError(
            f"estimator {name!r} takes one excitation channel, got {sums.sxx.shape[0]}; use 'H1' for MIMO"
        )
    sxx = sums.sxx[0, 0].real
    _guard_input_power(sxx[np.newaxis], source)
    return sxx, sums.syx[:, 0, :], sums.syy


def _siso_variance(frf, coherence, n_records):
    """E|Ĥ − H|² ≈ |H|² (1 − γ²) / (γ² (n − 1)) (Bendat & Piersol, first order)."""
    if n_records <= 1:
        return None
    gamma2 = np.maximum(coherence, np.finfo(float).tiny)
    return np.abs(frf) ** 2 * (1.0 - coherence) / (gamma2 * (n_records - 1))


def h2(sums: SpectralSums, source: str = "<array>"):
    """H2 = G_yy / G_yx (least squares with noise on the excitation), one input.

    Returns the same tuple as :func:`h1`.
    """
    sxx, syx, syy = _siso(sums, "H2", source)
    if np.any(np.abs(syx) == 0):
        raise ParameterError(f"{source}: the response is uncorrelated with the excitation at some line; H2 is undefined")
    frf = syy / syx.conj()
    coherence = np.clip(np.abs(syx) ** 2 / (sxx * np.maximum(syy, np.finfo(float).tiny)), 0.0, 1.0)
    frf = frf[:, np.newaxis, :]
    coherence = coherence[:, np.newaxis, :]
    return frf, coherence, coherence[:, 0, :], _siso_variance(frf, coherence, sums.n_records)


def hv(sums: SpectralSums, source: str = "<array>"):
    """Hv, the total-least-squares estimate (equal noise on excitation and response), one input.

    Hv = [G_yy − G_xx + √((G_xx − G_yy)² + 4|G_xy|²)] / (2 G_yx). Like every total-least-squares
    estimate it assumes equal noise on both channels *in their units*; scale them accordingly.
    Returns the same tuple as :func:`h1`.
    """
    sxx, syx, syy = _siso(sums, "Hv", source)
    if np.any(np.abs(syx) == 0):
        raise ParameterError(f"{source}: the response is uncorrelated with the excitation at some line; Hv is undefined")
    diff = sxx - syy
    root = np.sqrt(diff**2 + 4.0 * np.abs(syx) ** 2)
    # two algebraically equal forms; each avoids the cancellation of the other
    # (a + √(a² + b) = b / (√(a² + b) − a)), so Hv is exact to rounding whatever the units' ratio
    with np.errstate(divide="ignore", invalid="ignore"):
        frf = np.where(diff >= 0, 2.0 * syx / (diff + root), (root - diff) / (2.0 * syx.conj()))
    coherence = np.clip(np.abs(syx) ** 2 / (sxx * np.maximum(syy, np.finfo(float).tiny)), 0.0, 1.0)
    frf = frf[:, np.newaxis, :]
    coherence = coherence[:, np.newaxis, :]
    return frf, coherence, coherence[:, 0, :], _siso_variance(frf, coherence, sums.n_records)
