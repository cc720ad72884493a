"""Pathological FRFs for the caps on identify's work: many modes on many lines.

- ``"even"``: modes evenly spread over the axis, ζ = 0.005, equal driving-point constants, 0.1 % noise
  (the batch tests' slow file);
- ``"random"``: modes at random over the axis, ζ 0.002-0.03, constants of either sign and 0.2-2 in size,
  1 % noise: close pairs, weak modes and modes the peaks do not show, which the global method's
  significance tests and missing-mode search refit again and again.
"""
from __future__ import annotations

import warnings

import numpy as np

from modal.frf import FRF
from modal.synthetic import add_noise, modal_frf

VARIANTS = ("even", "random")


def many_modes_frf(n_modes: int, n_lines: int, variant: str = "even", seed: int = 3) -> FRF:
    """A driving-point mobility of ``n_modes`` modes on ``n_lines`` lines 0.25 Hz apart from 10 Hz (see the
    module docstring for the ``variant``), with the noise drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    freq = np.linspace(10.0, 10.0 + 0.25 * n_lines, n_lines)
    if variant == "even":
        modes = np.linspace(freq[0], freq[-1], n_modes + 2)[1:-1]
        zeta, constant, noise = np.full(n_modes, 0.005), np.ones(n_modes), 1e-3
    elif variant == "random":
        modes = np.sort(rng.uniform(freq[0] * 1.05, freq[-1] * 0.95, n_modes))
        zeta = rng.uniform(0.002, 0.03, n_modes)
        constant = rng.uniform(0.2, 2.0, n_modes) * rng.choice([-1, 1], n_modes)
        noise = 1e-2
    else:
        raise ValueError(f"variant {variant!r}: expected one of {VARIANTS}")
    frf = modal_frf(freq, list(modes), list(zeta), list(constant), kind="mobility", response_points=["1+Z"],
                    reference_points=["1+Z"])
    return add_noise(frf, noise, seed=seed)


def six_modes() -> FRF:
    """Six modes in 10-500 Hz on 1500 lines, 1 % noise: an ordinary global fit (a few model evaluations)."""
    f = np.linspace(10.0, 500.0, 1500)
    frf = modal_frf(f, [60, 120, 200, 260, 330, 420], [0.02, 0.01, 0.015, 0.01, 0.02, 0.01],
                    [1, 0.5, 2, 1, 0.7, 1.2], kind="mobility", response_points=["1"], reference_points=["1"])
    return add_noise(frf, 0.01, seed=1)


def fit_global(frf: FRF, **kwargs):
    """``identify(frf, "global", **kwargs)`` and the text of every warning it gave."""
    from modal import identify

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = identify(frf, "global", **kwargs)
    return result, [str(w.message) for w in caught]
