"""The one-mode rational start (modal.sdof.rational) and the NLS start that uses it."""
import importlib

import numpy as np
import pytest

from modal import FRF, identify
from modal.model import mode_basis
from modal.sdof.rational import rational_pole

starts_module = importlib.import_module("modal.sdof.starts")


def band(power, offset=0.0, noise=0.0, seed=0, n_channels=1):
    omega_n, zeta = 2 * np.pi * 100.0, 0.02
    omega = np.linspace(0.9, 1.1, 81) * omega_n
    constants = np.linspace(1.0, -0.5, n_channels)[:, None] + 0j
    h = constants * mode_basis(omega, omega_n, zeta, power)
    h = h + offset * np.abs(h).max() * (1 + 0.5j)  # a complex offset in the FRF's own kind
    rng = np.random.default_rng(seed)
    scale = np.abs(h).max()
    h = h + noise * scale * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / np.sqrt(2)
    return omega, h, omega_n, zeta


@pytest.mark.parametrize("power", [0, 1, 2])
def test_exact_mode_with_offset_is_recovered_to_rounding(power):
    # the numerator's quadratic holds A s^p plus an offset times D exactly: Levy's equations are
    # then consistent and the pole is exact up to the rounding of a 2x2 solve on ~100 lines
    omega, h, omega_n, zeta = band(power, offset=0.3)
    wn, z = rational_pole(omega, h)
    assert abs(wn / omega_n - 1) < 1e-10
    assert abs(z / zeta - 1) < 1e-8


def test_many_channels_share_the_pole_and_noise_leaves_it_within_a_few_errors():
    # 1 % noise on 8 channels: the SDOF Cramér–Rao error of ζ is about 1e-2/sqrt(lines·channels·ζ-width
    # share) ≈ 1e-3 relative; a start must be well inside the least-squares basin (here within 5 %)
    omega, h, omega_n, zeta = band(0, noise=0.01, n_channels=8)
    wn, z = rational_pole(omega, h)
    assert abs(wn / omega_n - 1) < 0.05 * zeta
    assert abs(z / zeta - 1) < 0.05


def test_no_oscillation_gives_none():
    omega = np.linspace(10.0, 20.0, 50)
    assert rational_pole(omega, np.ones((1, 50), complex)) is None  # a constant has no pole
    assert rational_pole(omega[:3], np.ones(3, complex)) is None  # too few lines


def test_nls_falls_back_to_the_careful_start_when_the_quick_one_gives_no_pole(monkeypatch):
    omega, h, omega_n, zeta = band(0, noise=0.002)
    frf = FRF(omega / (2 * np.pi), h[0], kind="receptance")
    quick = identify(frf, "nls", bands_hz=[(90.0, 110.0)])
    calls = []
    original = starts_module.start_pole

    def counting(*args):
        calls.append(args)
        return original(*args)

    monkeypatch.setattr(starts_module, "quick_start", lambda *args: None)
    monkeypatch.setattr(starts_module, "start_pole", counting)
    careful = identify(frf, "nls", bands_hz=[(90.0, 110.0)])
    assert calls, "the half-power and circle start was not used"
    # one least-squares optimum: both starts reach it (to the fit's stopping rule, 1e-13 relative step)
    assert careful.modes[0].natural_frequency_hz == pytest.approx(quick.modes[0].natural_frequency_hz, rel=1e-9)
    assert careful.modes[0].damping_ratio == pytest.approx(quick.modes[0].damping_ratio, rel=1e-7)
