"""The noise of a single impact record from its quiet samples (modal.estimate.quiet) and the noise level a
one-hit estimate carries with it."""
from __future__ import annotations

import numpy as np

import modal
from modal.estimate.quiet import quiet_noise
from modal.synthetic import DigitalModes, impact_record

FS = 1024.0
PLANT = DigitalModes([40.0, 95.0], [0.02, 0.012], [0.5, 0.8], FS)
#: median of |e|/σ for a circular complex Gaussian e with E|e|² = σ² (Rayleigh): √ln 2
RAYLEIGH_MEDIAN = np.sqrt(np.log(2.0))


def test_quiet_noise_reads_each_channels_noise_power_per_line():
    rng = np.random.default_rng(1)
    length, pretrigger, pulse = 4096, 1024, 8
    force = 0.3 * rng.standard_normal(length)
    force[pretrigger:pretrigger + pulse] += 100.0 * np.sin(np.pi * np.arange(pulse) / pulse)  # the hit
    response = 0.05 * rng.standard_normal((2, length)) * np.array([[1.0], [2.0]])
    response[:, pretrigger:] += np.sin(2 * np.pi * 40 * np.arange(length - pretrigger) / FS)  # the response rings
    window = np.hanning(length)
    noise = quiet_noise(force, response, 0, length, pretrigger, pulse, np.ones(length), window)
    # a = σ_y² Σ w_out² from the 1020 pre-trigger samples (variance within ±4.4 % one standard error,
    # √(2/1019)); b = σ_x² Σ w_in² from the 3060 samples after the pulse by their median absolute deviation
    # (efficiency 37 %: ±4.2 %); both within five standard errors
    np.testing.assert_allclose(noise.response_power, (0.05 * np.array([1.0, 2.0])) ** 2 * np.sum(window**2),
                               rtol=0.22)
    np.testing.assert_allclose(noise.force_power, 0.3**2 * length, rtol=0.21)


def test_quiet_noise_is_not_read_from_a_handful_of_samples():
    rng = np.random.default_rng(2)
    force, response = rng.standard_normal(512), rng.standard_normal((1, 512))
    assert quiet_noise(force, response, 0, 512, 8, 4, np.ones(512), np.ones(512)) is None  # 4 pre-trigger samples


def test_one_hit_carries_a_calibrated_noise_level_on_every_line():
    # 300 single hits with noise on the force and the response: the force's noise makes the error grow as |H|
    # at the peaks; noise_std must follow it there and between the modes
    ratios = []
    for seed in range(300):
        rec = impact_record(PLANT, [0.5], 4.5, amplitude_variation=0.2, width_variation=0.1, response_noise=0.002,
                            force_noise=0.002, seed=seed)
        est = modal.estimate_frf(rec.record.signals[0], rec.record.signals[1], FS, impact=True, window="rect",
                                 kind="accelerance")
        assert est.averages == 1
        ratios.append(np.abs(est.response - rec.frf(est.frequency_hz)[0]) / est.noise_std)
    ratios = np.array(ratios)
    f = est.frequency_hz
    peaks = (np.abs(f - 40.0) <= 0.8) | (np.abs(f - 95.0) <= 1.1)  # within a half-power width of each mode
    between = (f > 50.0) & (f < 80.0)
    # calibrated: |error|/σ is Rayleigh, median √ln 2; the median of n draws has standard error 1/(2 f(m) √n),
    # f(m) = 2m e^(−m²) the density at the median (0.012 over the 300 × 8 peak lines); ±0.07 is over five
    # of it. With the force's noise left out of noise_std the peaks' median is about 13
    for lines in (peaks, between):
        assert abs(np.median(ratios[:, lines]) - RAYLEIGH_MEDIAN) < 0.07, np.median(ratios[:, lines])


def test_noise_free_hit_leaves_its_noise_to_the_fit():
    # exact data: the quiet samples are exactly zero, no noise level per line to weight by (every weight
    # would be infinite); the estimate carries none, as with one average of a continuous record
    rec = impact_record(PLANT, [0.5], 4.5, seed=0)
    est = modal.estimate_frf(rec.record.signals[0], rec.record.signals[1], FS, impact=True, window="rect",
                             kind="accelerance")
    assert est.averages == 1 and est.noise_std is None
