"""How much of a continuous record's measured excitation the responses do not follow: H1's bias.

H1 assumes the excitation channel measures the force into the structure exactly. When it also holds
content the responses do not follow (a force cell's noise, a force measured at the shaker's body or
armature instead of through the cell at the stinger's tip, cross-talk), the measured excitation is
x + n_x and H1 = S_yx / S_xx reads, per line,

    E[Ĥ1] = H · S_x / (S_x + S_n) = H (1 − q),   q = S_n / (S_x + S_n),

too low by the fraction q of the measured excitation's power that is noise (Bendat & Piersol, *Random
Data*, ch. 9): frequencies stay, modal constants shrink by q, masses and stiffnesses grow by 1/(1 − q).
More averages do not reduce it; only the error bars shrink. The residual of H1 over the records holds
the same noise, in proportion to |H|² (:func:`modal.noise_model.input_noise_split`, power a + b|H|² per
record and line): b n / S_xx estimates q at each line.
"""
from __future__ import annotations

import numpy as np

from ..noise_model import input_noise_split

__all__ = ["excitation_noise_share", "EXCITATION_NOISE_LIMIT", "POWERED_LINE_FRACTION"]

#: a measured excitation whose noise share q exceeds this, on its median powered line, is warned: H1 is then
#: more than 10 % low (masses and stiffnesses more than 10 % high) whatever the averages. Clean synthetic
#: shaker records (bench_chain's random and burst cells, 40 records each: force noise 0–1 % of its RMS,
#: response noise 2–5 %, 3 to 50 averages, Hann, rectangular, burst) give q ≤ 0.014; ζ 0.1 % on 0.125 Hz
#: lines, whose peaks leak into every line, 0.065–0.074; a force read with noise of q = 0.083 and 0.5 gives
#: 0.083 and 0.49
EXCITATION_NOISE_LIMIT = 0.1
#: the lines counted: those where the measured excitation's power is at least this fraction of its
#: largest (a band-limited random or a chirp has no power above its band; lines there hold noise alone)
POWERED_LINE_FRACTION = 1e-3


def excitation_noise_share(sxx: np.ndarray, syx: np.ndarray, syy: np.ndarray, n_records: int) -> float | None:
    """The share q of the measured excitation's power that the responses do not follow, on its median line.

    Two estimates per output, each raised by something else, and the smaller kept: the residual's split
    (b n / S_xx, median over the powered lines; leakage near a peak also grows with |H|² and raises it, and
    where a response's own noise swamps it everywhere the split is not determined) and one minus the median
    coherence (the responses' own noise lowers the coherence, but the split gives that noise to a, not b).
    The excitation's noise raises both, in every output alike: the lowest output's value is kept.

    Parameters
    ----------
    sxx : ndarray, shape (n_lines,)
        Σ|X|² over the records (one excitation).
    syx : ndarray, shape (n_outputs, n_lines)
        Σ Y conj(X) over the records.
    syy : ndarray, shape (n_outputs, n_lines)
        Σ|Y|² over the records.
    n_records : int
        Records summed.

    Returns
    -------
    float or None
        q over the lines where the excitation has power (:data:`POWERED_LINE_FRACTION`); None with fewer
        than 3 records (the residual cannot split) or no powered line.
    """
    power = np.asarray(sxx, float)
    if n_records < 3 or not np.any(power > 0):
        return None
    powered = power >= POWERED_LINE_FRACTION * power.max()
    shares = []
    with np.errstate(divide="ignore", invalid="ignore"):
        for cross, auto in zip(np.atleast_2d(syx), np.atleast_2d(syy)):
            h = cross / power
            residual = (auto - np.abs(cross) ** 2 / power) / (n_records - 1)
            _, b = input_noise_split(residual, np.abs(h) ** 2, powered)
            split = float(np.median(b * n_records / power[powered]))
            coherence = np.abs(cross[powered]) ** 2 / (power[powered] * auto[powered])
            shares.append(min(split, 1.0 - float(np.nanmedian(coherence))))
    share = min(shares)
    return share if np.isfinite(share) else None
