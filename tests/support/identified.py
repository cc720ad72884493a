"""Real identification results for tests of the code that consumes them.

`identified_mode` builds the receptance of a known single-degree-of-freedom system
(one or several driving-point channels), adds seeded noise and runs
``modal.identify`` on it, so a consumer is fed what the toolkit really returns
(a ``ModeResult`` with its ``std`` and flags), not a hand-made stand-in.
"""
from __future__ import annotations

import warnings

import numpy as np

import modal
from modal.synthetic import add_noise, modal_frf

#: 0.1 % noise relative to max |H| and 20 lines per half-power band: a well-posed fit whose
#: standard errors are ~1e-4 relative (k, c, m)
NOISE = 1e-3
LINES_PER_BAND = 20


def identified_mode(mass_kg, stiffness_n_per_m: float, damping_n_s_per_m: float, *, seed: int = 0,
                    driving_point=None, noise: float = NOISE):
    """The NLS-identified mode of m x'' + c x' + k x = f, measured on one or more channels.

    ``mass_kg`` may be an array over channels: channel j then has modal constant
    1/mass_kg[j] (the same pole; k and c per channel scale with it, k_j = m_j ωn²). k and c
    are those of the first channel.
    """
    masses = np.atleast_1d(np.asarray(mass_kg, float))
    wn = np.sqrt(stiffness_n_per_m / masses[0])
    zeta = damping_n_s_per_m / (2 * np.sqrt(stiffness_n_per_m * masses[0]))
    fn = wn / (2 * np.pi)
    f = np.arange(fn * (1 - 8 * zeta), fn * (1 + 8 * zeta), 2 * zeta * fn / LINES_PER_BAND)
    const = (1.0 / masses)[:, None] if np.ndim(mass_kg) else [1.0 / masses[0]]
    frf = add_noise(modal_frf(f, [fn], [zeta], const), noise, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.QualityWarning)
        result = modal.identify(frf, "nls", driving_point=True if driving_point is None else driving_point)
    assert len(result) == 1
    return result[0]


def within(value, truth, std, k_sigma: float = 5.0) -> bool:
    """|value − truth| <= k_sigma std, elementwise (5 sigma: 6e-7 for a calibrated error)."""
    return bool(np.all(np.abs(np.asarray(value) - truth) <= k_sigma * np.asarray(std)))
