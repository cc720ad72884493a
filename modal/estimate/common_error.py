"""The error every output of a one-input estimate shares: the excitation channel's own noise.

An H1 estimate from a measured excitation x + n_x and responses y_o + n_o has, to first order,
the error Ĥ_o − H_o = (Σ_i N_o,i X*_i − H_o Σ_i N_x,i X*_i) / S_xx per line: the response noise's
part is each output's own, the excitation noise's is H_o η with one η = −Σ_i N_x,i X*_i / S_xx for
every output. Over the few dozen samples a force window keeps, η is smooth across the lines and
correlates the outputs' errors (on the bench's six accelerometers with a force window, the FRF
errors relative to H correlate by 0.4–0.8 between channels near a mode). A fit that takes the
channels as independent misses it.

With white noise of variance σ² per sample on the excitation, windowed by w,
E[η_k η*_l] = σ² Σ_i Σ_n w[n]² e^{−2πi(k−l)n/N} X*_ik X_il / (S_k S_l) = W(k − l) Σ_i g_i(k) g_i*(l), with
g_i = X_i*/S record i's force spectrum over the summed power and W(d) = σ² Σ_n w[n]² e^{−2πidn/N} the squared
window's transform: a sum over the records and the window's support of rank-one terms, one row per (record,
sample). :func:`common_error_factor` keeps what generates them (:class:`CommonError`: g on each line, the
support and σ w[n]), a few MB where the rows over every line of a 16384-sample record are a hundred; a fit asks
for the factor on its own lines (:meth:`CommonError.factor`), P with E[η η^H] = Pᵀ conj(P) of as few rows as
its eigenvalues need. σ² follows from the excitation noise's power per record b
(:func:`~modal.noise_model.input_noise_split`), E|N_x|² = σ² Σ w².
"""
from __future__ import annotations

import numpy as np

from ..shared_error import CommonError

__all__ = ["common_error_factor", "MAX_SUPPORT_FRACTION"]

#: the excitation window keeps at most this fraction of a record (a force window's few dozen samples); a window
#: over the whole record (a hammer test without a force window, a continuous estimate) is no short support: its
#: excitation noise is left to the line correlation
MAX_SUPPORT_FRACTION = 1 / 8


def common_error_factor(excitation: np.ndarray, starts: np.ndarray, length: int, input_window: np.ndarray,
                        excitation_noise_power: float) -> CommonError | None:
    """What generates the covariance of the relative error η the outputs share (see the module), on every line
    of the records' transform.

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
    CommonError or None
        None where the window keeps more than :data:`MAX_SUPPORT_FRACTION` of a record (or nothing), the noise
        power is not positive, or a line holds no excitation.
    """
    window = np.asarray(input_window, float)
    support = np.flatnonzero(window != 0)
    starts = np.asarray(starts, np.int64)
    if not excitation_noise_power > 0 or support.size == 0 or support.size > MAX_SUPPORT_FRACTION * length:
        return None
    records = np.stack([excitation[s:s + length] for s in starts]) * window  # (n_records, length)
    spectra = np.fft.rfft(records, axis=-1)
    power = np.sum(np.abs(spectra) ** 2, axis=0)
    if not np.all(power > 0):
        return None
    sigma = np.sqrt(excitation_noise_power / float(np.sum(window**2)))
    return CommonError(spectra.conj() / power, np.arange(length // 2 + 1), support, sigma * window[support], length)
