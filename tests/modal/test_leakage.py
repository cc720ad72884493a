"""The window's bias of an estimate from time records (leakage), and identification taking it out."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.estimate.windows import segment_window
from modal.leakage import window_bias
from modal.noise_model import lag_window
from modal.synthetic_time import DigitalModes, random_record

FS = 1024.0
FN, ZETA, CONST = np.array([40.0, 95.0]), np.array([0.02, 0.012]), np.array([0.5, 0.8])


@pytest.mark.parametrize("window", ["hann", "rect"])
def test_window_bias_is_exact_for_the_digital_system(window):
    """E[Ĥ] is the transform of the impulse response times ρ(τ): the bias formula gives it to rounding."""
    plant = DigitalModes(FN, ZETA, CONST, FS)
    n = 4096
    impulse = np.zeros(n)
    impulse[0] = 1.0
    h = plant.respond(impulse, "acceleration")[0]
    w = segment_window(window, n)
    rho = lag_window(w, w, np.ones(n))
    f = np.fft.rfftfreq(n, 1 / FS)
    expected = np.fft.rfft(h * rho)
    exact = plant.frf(f, "accelerance")[0]
    bias = window_bias(2 * np.pi * f, 2, 2 * np.pi * FN, ZETA, CONST[:, None], rho, 1 / FS)[0]
    near = (f > 30) & (f < 110)
    assert np.max(np.abs(expected - exact)[near]) > 1e-3 * np.max(np.abs(exact))  # a bias to take out
    np.testing.assert_allclose((exact + bias)[near], expected[near], atol=1e-11 * np.max(np.abs(exact)))


def test_identify_takes_the_rectangular_windows_damping_bias_out():
    """Random excitation, rectangular window, 2 s segments over 200 s: the window adds ≈ 1/T to every decay
    rate, ζ +0.4 % at 40 Hz, many of its standard errors. Fitted through the lag window, ζ is within 3 of
    its errors of the truth, and the result says what was done."""
    plant = DigitalModes(FN, ZETA, CONST, FS)
    rec = random_record(plant, 200.0, response_noise=0.02, seed=3).record
    frf = modal.estimate_frf(rec.signals[0], rec.signals[1], FS, window="rect", segment_length=2048,
                             kind="accelerance")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = modal.identify(frf)
    assert "lag window" in result.settings["window_bias"]
    for mode, fn, zeta in zip(result, FN, ZETA):
        assert abs(mode.natural_frequency_hz - fn) < 4 * mode.std.natural_frequency_hz
        assert abs(mode.damping_ratio - zeta) < 3 * mode.std.damping_ratio, (mode.damping_ratio, mode.std.damping_ratio)
