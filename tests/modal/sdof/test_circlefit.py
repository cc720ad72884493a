"""The circle fit (modal.sdof.circlefit): its errors against the scatter."""
import warnings

import numpy as np

from modal import QualityWarning, identify
from modal.synthetic import add_noise
from support.modes import method_check_case


def test_circle_errors_match_scatter():
    # 30 lines per band, 1 % noise, 100 seeds: the circle is efficient on the lines it uses,
    # and its errors (floored at the Cramér–Rao bound of those lines; one channel, no median
    # penalty) match the observed scatter to 25 % (a 100-sample SD alone scatters ±7 %).
    # The mass too: the circle's own constant (its diameter) had errors 1.5x optimistic
    # (median error / scatter 0.65); its variance along
    # the difference from the refinement is now at least that difference squared
    clean, fn, zeta = method_check_case(30, half_widths=3)
    band = [(clean.frequency_hz[0], clean.frequency_hz[-1])]
    values, stds, masses, mass_stds = [], [], [], []
    for seed in range(100):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", QualityWarning)  # damping_pair_spread at times
            mode = identify(add_noise(clean, 0.01, seed=seed), "circle", bands_hz=band, driving_point=True)[0]
        values.append(mode.damping_ratio)
        stds.append(mode.std.damping_ratio)
        masses.append(float(mode.mass_kg))
        mass_stds.append(float(mode.std.mass_kg))
    assert abs(np.median(stds) / np.std(values) - 1) < 0.25
    assert abs(np.median(mass_stds) / np.std(masses) - 1) < 0.25
