"""Each record's share of an H1 estimate's error (its influence on the estimate), kept for identification to
measure the variance of what it fits over the records.

With one input, Ĥ_k = Σ_i Y_ik conj(X_ik) / S_xx,k over the records i, so for the records' errors
N_ik = Y_ik − H_k X_ik (measurement noise and leakage alike)

    Ĥ_k − H_k = Σ_i N_ik conj(X_ik) / S_xx,k,

a sum over the records. Its terms are estimated by each record's residual R_ik = Y_ik − Ĥ_k X_ik:

    ψ_ik = R_ik conj(X_ik) / S_xx,k = (p_ik − Ĥ_k q_ik) / S_xx,k,   p = Y conj(X), q = |X|²,

the terms :mod:`modal.estimate.error_correlation` sums over the records line pair by line pair (Σ_i ψ_ik = 0
exactly: H1 leaves no residual correlated with the excitation). Anything linear in Ĥ, a fitted parameter to
first order, then errs by Σ_i s_i with s_i its response to ψ_i, and its variance is measured by Σ_i s_i s_iᵀ
plus the cross terms of records that overlap (:mod:`modal.record_variance`): every line's correlation with
every other enters, where the measured line correlation carries a few lags only.

Several channels (inputs or outputs): Ĥ_o = S_yx,o S_xx⁻¹ per output (a row over the inputs), so

    ψ_i,oq = Σ_p R_iop conj(X_ip) [S_xx⁻¹]_pq,   R_io = Y_io − Σ_p Ĥ_op X_ip

(:func:`channel_influence`), one set of records for every channel: the channels' errors correlate through
them as they do in the estimate (a lightly damped mode's leakage follows its shape, the same in every output:
two shakers' errors at 95 Hz correlated by 0.97 between the outputs of one input, over 40 records of 120 s).
"""
from __future__ import annotations

import numpy as np

from ..noise_model import MAX_INFLUENCE_VALUES

__all__ = ["record_influence", "channel_influence", "overlapping_records", "MAX_INFLUENCE_VALUES"]


def record_influence(cross: np.ndarray, power: np.ndarray, frf: np.ndarray,
                     input_power: np.ndarray) -> np.ndarray | None:
    """ψ_ik = (p_ik − Ĥ_k q_ik) / S_xx,k (see the module), in the FRF's unit.

    Parameters
    ----------
    cross : ndarray, shape (n_records, n_lines), complex
        Each record's Y conj(X) (:attr:`modal.estimate.spectra.SpectralSums.record_cross`).
    power : ndarray, shape (n_records, n_lines)
        Each record's |X|².
    frf : ndarray, shape (n_lines,), complex
        The H1 estimate.
    input_power : ndarray, shape (n_lines,)
        S_xx, the sum of ``power`` over the records.

    Returns
    -------
    ndarray, shape (n_records, n_lines), complex, or None where a value is not finite.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        influence = (cross - frf[None, :] * power) / input_power[None, :]
    return influence if np.all(np.isfinite(influence)) else None


def channel_influence(inputs: np.ndarray, outputs: np.ndarray, frf: np.ndarray,
                      input_power: np.ndarray) -> np.ndarray | None:
    """ψ_i,oq of several channels (see the module), in the FRF's unit.

    Parameters
    ----------
    inputs : ndarray, shape (n_records, n_inputs, n_lines), complex
        Each record's X (:attr:`modal.estimate.spectra.SpectralSums.record_input`).
    outputs : ndarray, shape (n_records, n_outputs, n_lines), complex
        Each record's Y.
    frf : ndarray, shape (n_outputs, n_inputs, n_lines), complex
        The H1 estimate.
    input_power : ndarray, shape (n_inputs, n_inputs, n_lines), complex
        S_xx = Σ_i X_i X_iᴴ.

    Returns
    -------
    ndarray, shape (n_outputs · n_inputs, n_records, n_lines), complex, channels ordered as the estimate's
    (output by output, input by input within one), or None where a value is not finite.
    """
    n_records, n_in, n_lines = inputs.shape
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        residual = np.array(outputs, complex)  # R_io = Y_io − Σ_p Ĥ_op X_ip, (records, outputs, lines)
        for p in range(n_in):
            residual -= frf[None, :, p, :] * inputs[:, None, p, :]
        try:
            inverse = np.linalg.inv(np.moveaxis(input_power, -1, 0))  # (lines, inputs, inputs)
        except np.linalg.LinAlgError:
            return None
        # Σ_p conj(X_ip) [S_xx⁻¹]_pq once per record and input q, (records, inputs, lines); then times each R_io
        weights = np.einsum("ipk,kpq->iqk", inputs.conj(), inverse)
        influence = residual[:, :, None, :] * weights[:, None, :, :]  # (records, outputs, inputs, lines)
    influence = influence.transpose(1, 2, 0, 3).reshape(-1, n_records, n_lines)
    return influence if np.all(np.isfinite(influence)) else None


def overlapping_records(length: int, step: int) -> int:
    """How many following records each record of ``length`` samples overlaps, records ``step`` samples apart."""
    return max(0, -(-int(length) // max(int(step), 1)) - 1)
