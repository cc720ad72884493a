"""Scale-free identification: FRFs of any magnitude are fitted at unit scale.

Identification is scale-invariant (H → g H gives A → g A, k, c, m → k/g, c/g, m/g
with the same poles), but floating point is not: values near 1e307 overflow when
squared and values near 1e-300 underflow. :func:`modal.identify` therefore fits an
FRF whose largest value lies outside :data:`SAFE_MAGNITUDE` multiplied by a power of
two (exact in binary floating point) and scales the results back.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from .frf import FRF
from .results import IdentificationResult, ModeResult, ModeStd

__all__ = ["SAFE_MAGNITUDE", "scale_exponent", "scaled_frf", "unscale_result"]

#: Largest |H| that is fitted as it is (its square and products stay far from over- and underflow).
SAFE_MAGNITUDE = (1e-30, 1e30)


def scale_exponent(frf: FRF, peak: np.ndarray | None = None) -> int:
    """Power of two ``e`` such that ``2**e * max|H|`` is about 1, or 0 when the FRF needs no scaling.

    ``peak``: each channel's max |H|, when the caller has it (no pass over the data; |H| lies
    within √2 of max(|Re|, |Im|), far inside :data:`SAFE_MAGNITUDE`'s distance from over- and underflow).
    """
    response = np.asarray(frf.response)
    if peak is not None and np.size(peak) and np.all(np.isfinite(peak)):
        peak = float(np.max(peak))
    else:
        parts = np.ascontiguousarray(response, dtype=complex).view(float)  # Re, Im side by side, no copy
        peak = max(float(np.max(parts)), -float(np.min(parts))) if parts.size else 0.0  # |Re|, |Im| cannot overflow
    if not np.isfinite(peak):  # an FRF holds finite values; this is for arrays set past its validation
        finite = response[np.isfinite(response)]
        if finite.size == 0:
            return 0
        peak = max(float(np.max(np.abs(finite.real))), float(np.max(np.abs(finite.imag))))
    if peak == 0.0 or SAFE_MAGNITUDE[0] <= peak <= SAFE_MAGNITUDE[1]:
        return 0
    return -math.frexp(peak)[1]


def scaled_frf(frf: FRF, exponent: int) -> FRF:
    """The FRF multiplied by ``2**exponent`` (and its per-line noise, when it carries one)."""
    gain = 2.0**exponent
    noise = None if frf.noise_std is None else np.asarray(frf.noise_std) * gain
    return dataclasses.replace(frf, response=np.asarray(frf.response) * gain, noise_std=noise)


def _times(value, factor):
    if value is None:
        return None
    out = np.asarray(value) * factor
    return out if out.ndim else out[()].item() if hasattr(out[()], "item") else out[()]


def unscale_result(result: IdentificationResult, gain: float) -> IdentificationResult:
    """Results of ``g H`` turned into results of ``H`` (``gain`` = g)."""
    modes = []
    for mode in result.modes:
        std = dataclasses.replace(
            mode.std, modal_constant=_times(mode.std.modal_constant, 1 / gain),
            stiffness_n_per_m=_times(mode.std.stiffness_n_per_m, gain),
            damping_n_s_per_m=_times(mode.std.damping_n_s_per_m, gain), mass_kg=_times(mode.std.mass_kg, gain))
        modes.append(dataclasses.replace(
            mode, modal_constant=_times(mode.modal_constant, 1 / gain),
            stiffness_n_per_m=_times(mode.stiffness_n_per_m, gain), damping_n_s_per_m=_times(mode.damping_n_s_per_m, gain),
            mass_kg=_times(mode.mass_kg, gain), std=std))
    residuals = None if result.residuals is None else np.asarray(result.residuals) / gain
    return dataclasses.replace(result, modes=tuple(modes), noise_std=np.asarray(result.noise_std) / gain,
                               residuals=residuals)
