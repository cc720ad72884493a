"""Half-power bandwidth (modal.sdof.halfpower): unbiased under noise, crossings on their own side."""
import warnings

import numpy as np

import modal
from modal import identify
from modal.synthetic import add_noise, modal_frf
from support.modes import method_check_case


def test_half_power_noise_bias_is_gone_and_errors_hold():
    # 300 lines per half-power band, 5 % noise: choosing the peak-fit and crossing-fit lines by
    # the noisy lines themselves lifted the -3 dB level and ζ came out low by ~20 of the method's
    # errors. The lines are now chosen on the model of the previous
    # pass: the estimate is unbiased and its propagated errors hold. A calibrated
    # error fails |z| <= 3 with probability 0.27 % per quantity and seed, 2.7 % over these 10.
    clean, fn, zeta = method_check_case(300)
    for seed in range(5):
        mode = identify(add_noise(clean, 0.05, seed=seed), "halfpower", bands_hz=[(clean.frequency_hz[0], clean.frequency_hz[-1])])[0]
        assert "method_bias" not in mode.flags
        assert abs(mode.damping_ratio - zeta) <= 3 * mode.std.damping_ratio
        assert abs(mode.natural_frequency_hz - fn) <= 3 * mode.std.natural_frequency_hz


def test_half_power_crossing_stays_on_its_side_of_the_peak():
    # mobility, ζ = 0.28 and 0.5, 18 % noise. The least-squares crossing
    # of the upper side (a quadratic through the lines within 1 dB of the level, which the
    # noise scatters over the whole side) fell below zero, and sqrt(ω1·ω2) warned and gave NaN.
    # A refined crossing outside its side's lines now keeps the line-interpolated one.
    f = 0.1593487327504735 + 0.21869746550094699 * np.arange(1864)
    clean = modal_frf(f, [1.0, 67.96612506431045], [0.2761579208653549, 0.5], [39.4784176, 70.2036572],
                      kind="mobility")
    frf = add_noise(clean, 0.1796875, seed=139715)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        warnings.simplefilter("error", RuntimeWarning)
        result = identify(frf, "halfpower", bands_hz=[(0.16, 2.66), (34.48, 271.86)])
    for mode, band in zip(result, [(0.16, 2.66), (34.48, 271.86)]):
        assert np.isfinite(mode.natural_frequency_hz) and np.isfinite(mode.damping_ratio)
        assert band[0] <= mode.natural_frequency_hz <= band[1]


def test_model_curves_are_those_of_every_sample():
    # the model's peak and its exact −3 dB crossings are computed on the samples around them (a coarse pass
    # locates them): the same numbers as the largest of all the samples and the interpolation over all of them
    from modal.model import mode_basis
    from modal.sdof.halfpower import CROSSING_SAMPLES, PEAK_SAMPLES, _exact_crossing, _model_db, _model_peak

    rng = np.random.default_rng(8)
    level = -10 * np.log10(2)
    for _ in range(200):
        power, wn = int(rng.integers(0, 3)), float(rng.uniform(10, 1e4))
        zeta = float(10 ** rng.uniform(-4, np.log10(0.75)))
        first, last = sorted(rng.uniform(0.2, 1.8, 2) * wn)
        peak = _model_peak.__wrapped__(first, last, power, wn, zeta)
        assert peak == np.abs(mode_basis(np.linspace(first, last, PEAK_SAMPLES), wn, zeta, power)[0]).max()
        lines = np.linspace(first, last, int(rng.integers(5, 40)))
        model = _model_db(lines, power, (wn, zeta))
        for a in range(lines.size - 1):
            if min(model[a], model[a + 1]) <= level <= max(model[a], model[a + 1]):
                fine = np.linspace(lines[a], lines[a + 1], CROSSING_SAMPLES)
                curve = _model_db(fine, power, (wn, zeta), reference=lines)
                order = np.argsort(curve)
                expected = float(np.interp(level, curve[order], fine[order]))
                assert _exact_crossing(lines[a], lines[a + 1], power, (wn, zeta), lines, level) == expected
