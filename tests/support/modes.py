"""Synthetic modal cases shared by the identification tests of several modules."""
from __future__ import annotations

import numpy as np

from modal.synthetic import modal_frf

#: three well-separated modes (Hz, damping ratio, receptance modal constant 1/kg)
THREE_FN = np.array([50.0, 120.0, 300.0])
THREE_ZETA = np.array([0.01, 0.02, 0.03])
THREE_A = np.array([1.0, 0.5 + 0.05j, 2.0])  # slightly complex, below the 10° complex_mode flag


def method_check_case(lines_per_band, fn=100.0, zeta=0.01, half_widths=5):
    """One mode with ``lines_per_band`` lines per half-power band 2ζfn, ±``half_widths`` bands around it:
    (FRF, fn, ζ)."""
    bw = 2 * zeta * fn
    df = bw / lines_per_band
    f = np.arange(fn - half_widths * bw, fn + half_widths * bw + df / 2, df)
    return modal_frf(f, [fn], [zeta], [1.0]), fn, zeta


def overlapping_case(ratio):
    """Modes at 1, r, r² Hz with ζ = 0.1 and a mode below the noise at 10.55 Hz, each with its band:
    (FRF, fn, ζ, bands)."""
    # modes at 1, r, r² Hz with ζ = 0.1 (overlap 0.2/(r−1)) and a mode at 10.55 Hz whose
    # receptance peak is 0.4 σ: below the noise
    fn = np.array([1.0, ratio, ratio**2, 10.55])
    zeta = np.full(4, 0.1)
    f = np.linspace(0.05, 16, 800)
    bands = []
    for r, (fr, z) in enumerate(zip(fn, zeta)):
        lo, hi = fr - 6 * z * fr, fr + 6 * z * fr
        lo = max(lo, 0.5 * (fn[r - 1] + fr)) if r > 0 else lo
        hi = min(hi, 0.5 * (fn[r + 1] + fr)) if r < 3 else hi
        bands.append((max(lo, f[0]), min(hi, f[-1])))
    return modal_frf(f, fn, zeta, np.full(4, 39.4784176)), fn, zeta, bands
