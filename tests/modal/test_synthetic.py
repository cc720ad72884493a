"""Synthetic time records (modal.synthetic: DigitalModes, impact_record, random_record)."""
from __future__ import annotations

import numpy as np
import pytest

import modal
from modal.errors import ParameterError
from modal.synthetic import DigitalModes, impact_record, matrix_frf, modal_frf, random_record

FS = 1024.0
FN = np.array([40.0, 95.0])
ZETA = np.array([0.03, 0.02])
A = np.array([[1.0, 0.5], [0.6, -0.8]])
KINDS = ("receptance", "mobility", "accelerance")
QUANTITIES = ("displacement", "velocity", "acceleration")


@pytest.fixture(scope="module")
def plant():
    return DigitalModes(FN, ZETA, A, FS)


def _continuous_impulse_response(t, power):
    """d^p/dt^p of Σ A/ωd e^{−σt} sin(ωd t) for t > 0 (real modal constants), per output."""
    wn = 2 * np.pi * FN
    sigma, wd = ZETA * wn, wn * np.sqrt(1 - ZETA**2)
    decay, s, c = np.exp(-np.outer(t, sigma)), np.sin(np.outer(t, wd)), np.cos(np.outer(t, wd))
    shape = {0: s, 1: wd * c - sigma * s, 2: (sigma**2 - wd**2) * s - 2 * sigma * wd * c}[power]
    return ((decay * shape / wd) @ A.T).T


@pytest.mark.parametrize("power", [0, 1, 2])
def test_impulse_response_samples_the_continuous_one(plant, power):
    impulse = np.zeros(600)
    impulse[0] = 1.0
    digital = plant.respond(impulse, QUANTITIES[power])
    T = 1.0 / FS
    expected = T * _continuous_impulse_response(np.arange(1, 600) * T, power)
    scale = np.max(np.abs(expected))
    np.testing.assert_allclose(digital[:, 1:], expected, rtol=0, atol=1e-12 * scale)  # rounding of the filter
    # at t = 0 the response jumps (velocity: from 0 to A; acceleration: a direct term A and a jump −2σA):
    # the first sample takes the mid value T g(0)/2, plus the direct term
    sigma = ZETA * 2 * np.pi * FN
    first = {0: np.zeros(2), 1: T * A.sum(axis=1) / 2, 2: A @ (1 - sigma * T)}[power]
    np.testing.assert_allclose(digital[:, 0], first, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("kind", KINDS)
def test_frf_is_the_aliased_sum_of_the_continuous_one(plant, kind):
    f = np.linspace(0.0, FS / 2, 17)
    K = 4000
    shifts = np.arange(-K, K + 1) * FS
    aliases = plant.continuous_frf((f[None, :] + shifts[:, None]).ravel(), kind).reshape(2, shifts.size, f.size)
    # accelerance tends to the constant Σ A (the direct term): it is not sampled, so it does not alias
    direct = A.sum(axis=1)[:, None] if kind == "accelerance" else np.zeros((2, 1))
    alias_sum = (aliases - direct[:, None, :]).sum(axis=1) + direct
    # the terms fall off as 1/k² (symmetric pairs for mobility and accelerance): the tail beyond K is about
    # K times the last pair
    last = np.abs(aliases[:, 0] + aliases[:, -1] - 2 * direct)
    np.testing.assert_allclose(plant.frf(f, kind), alias_sum, rtol=0, atol=float(10 * K * last.max()) + 1e-12)
    # far below the Nyquist frequency the aliases are negligible: the digital system is the continuous one
    low = f < 100
    truth = modal_frf(f[low], FN, ZETA, A, kind=kind).channels
    assert np.max(np.abs(plant.frf(f[low], kind) - truth)) < 5e-3 * np.max(np.abs(truth))


@pytest.mark.parametrize("quantity, kind", list(zip(QUANTITIES, KINDS)))
def test_frf_is_the_spectrum_of_the_response(plant, quantity, kind):
    impulse = np.zeros(8192)
    impulse[0] = 1.0
    spectrum = np.fft.rfft(plant.respond(impulse, quantity), axis=1)
    lines = np.fft.rfftfreq(8192, 1 / FS)
    # 8 s holds e^(−σ 8) < 1e-20 of the slowest mode: the DFT of the impulse response is the FRF
    np.testing.assert_allclose(spectrum, plant.frf(lines, kind), rtol=0, atol=1e-12 * np.max(np.abs(spectrum)))


def test_from_matrices_matches_the_direct_solution():
    M = np.diag([1.0, 2.0])
    K = np.array([[3e5, -1e5], [-1e5, 1e5]])
    C = 1e-4 * K + np.diag([5.0, 0.0])  # not proportional: complex modal constants
    modes = DigitalModes.from_matrices(M, C, K, FS, reference_dof=1)
    assert np.any(np.abs(modes.modal_constant.imag) > 1e-4 * np.abs(modes.modal_constant).max())
    f = np.linspace(1.0, 200.0, 60)
    for kind in KINDS:
        direct = matrix_frf(f, M, C, K, reference_dof=1, kind=kind).channels
        np.testing.assert_allclose(modes.continuous_frf(f, kind), direct, rtol=0, atol=1e-12 * np.abs(direct).max())
    with pytest.raises(ParameterError, match="not underdamped"):
        DigitalModes.from_matrices(M, 1e3 * np.eye(2), K, FS)


def test_impact_record_hits_rebounds_and_scatter():
    plant = DigitalModes(FN, ZETA, A, FS)
    times = np.arange(40) * 1.0 + 0.5
    synthetic = impact_record(plant, times, 41.0, pulse_width_s=0.004, amplitude_n=200.0,
                              amplitude_variation=0.1, rebound_delay_s=[0.06] + [None] * 39,
                              rebound_fraction=0.25, response_quantity="velocity",
                              names=["hammer", "p1", "p2"], seed=3)
    record = synthetic.record
    assert record.names == ("hammer", "p1", "p2")
    assert record.quantities == ("force", "velocity", "velocity") and record.units == ("N", "m/s", "m/s")
    assert record.sample_rate_hz == FS and record.n_samples == 41 * 1024 and record.full_scale is None
    assert synthetic.hit_times_s == tuple(times) and synthetic.rebound_times_s == pytest.approx((0.56,))
    force = record.signals[0]
    windows = [force[int(t * FS):int(t * FS) + 6] for t in times]
    peaks = np.array([w.max() for w in windows])
    # a 4 ms half sine sampled every 0.98 ms: the largest sample is within sin(π/2 ± 0.38) of the peak
    log_peaks = np.log(peaks)
    # the scatter is log-normal with σ = 0.1: 40 hits estimate it within its sampling error (√(1/78) ≈ 11 %)
    assert abs(np.std(log_peaks, ddof=1) / 0.1 - 1) < 3 / np.sqrt(78)
    rebound = force[int(0.56 * FS):int(0.56 * FS) + 6].max()
    assert rebound / peaks[0] == pytest.approx(0.25, rel=0.1)  # the same pulse shape sampled at other phases
    # the responses are the system's response to this force, nothing else (no noise asked for)
    np.testing.assert_allclose(record.signals[1:], plant.respond(force, "velocity"), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(synthetic.frf([40.0]), plant.frf([40.0], "mobility"))


def test_impact_record_noise_and_clipping():
    plant = DigitalModes(FN, ZETA, A, FS)
    clean = impact_record(plant, [0.5, 2.5], 4.0, seed=1)
    noisy = impact_record(plant, [0.5, 2.5], 4.0, force_noise=0.01, response_noise=0.02, seed=1)
    difference = noisy.record.signals - clean.record.signals
    peaks = np.max(np.abs(clean.record.signals), axis=1)
    # white noise of 1 % (force) and 2 % (responses) of each channel's peak; 4096 samples estimate the
    # standard deviation within 3/√(2·4096) ≈ 3.3 %
    np.testing.assert_allclose(difference.std(axis=1) / peaks, [0.01, 0.02, 0.02], rtol=3 / np.sqrt(2 * 4096))
    full_scale = 0.6 * peaks[0]
    clipped = impact_record(plant, [0.5, 2.5], 4.0, full_scale=[full_scale, None, None], seed=1)
    force = clipped.record.signals[0]
    assert force.max() == full_scale and clipped.clipped_samples[0] == int(np.sum(clean.record.signals[0] > full_scale))
    assert clipped.clipped_samples[0] > 0 and clipped.clipped_samples[1:] == (0, 0)
    assert clipped.record.full_scale == (full_scale, None, None)
    undeclared = impact_record(plant, [0.5, 2.5], 4.0, full_scale=full_scale, declare_full_scale=False, seed=1)
    assert undeclared.record.full_scale is None and np.array_equal(undeclared.record.signals[0], force)


def test_random_record_estimates_its_own_frf():
    plant = DigitalModes(FN, ZETA, A, FS)
    synthetic = random_record(plant, 128.0, force_rms_n=5.0, response_noise=0.05, seed=2)
    record = synthetic.record
    assert np.sqrt(np.mean(record.signals[0] ** 2)) == pytest.approx(5.0, rel=1e-12)
    est = modal.estimate_frf(record.signals[0], record.signals[1:], FS, kind=synthetic.kind,
                             response_quantity="acceleration", segment_length=2048)
    ratio = (np.abs(est.response - synthetic.frf(est.frequency_hz)) / est.noise_std)[:, 1:-1]
    # |error|/noise_std is Rayleigh when the record is stationary and the truth exact: median √ln 2, known to
    # within 4 of its sampling errors 1/(2 f(m) √n) (no start-up transient, no model error)
    m = np.sqrt(np.log(2.0))
    spread = 1.0 / (2 * 2 * m * np.exp(-m * m) * np.sqrt(ratio.size))
    assert abs(np.median(ratio) - m) < 4 * spread


def test_random_record_band_limits_the_force():
    plant = DigitalModes(FN, ZETA, A, FS)
    force = random_record(plant, 16.0, band_hz=(20.0, 200.0), seed=4).record.signals[0]
    spectrum = np.abs(np.fft.rfft(force))
    f = np.fft.rfftfreq(force.size, 1 / FS)
    outside = (f < 20) | (f > 200)
    assert np.max(spectrum[outside]) < 1e-12 * np.max(spectrum)  # zero but for rounding


@pytest.mark.parametrize("kwargs, message", [
    (dict(natural_frequency_hz=[600.0]), "Nyquist"),
    (dict(damping_ratio=[1.2]), "damping_ratio"),
    (dict(modal_constant=[[1.0, 2.0]]), "modal_constant"),
])
def test_bad_modes_name_the_field(kwargs, message):
    args = dict(natural_frequency_hz=[40.0], damping_ratio=[0.02], modal_constant=[[1.0]], sample_rate_hz=FS)
    with pytest.raises(ParameterError, match=message):
        DigitalModes(**{**args, **kwargs})


def test_bad_record_settings_name_the_field(plant):
    with pytest.raises(ParameterError, match="'names' has 2 names"):
        impact_record(plant, [0.5], 2.0, names=["f", "a"])
    with pytest.raises(ParameterError, match="'hit_times_s'"):
        impact_record(plant, [3.0], 2.0)
    with pytest.raises(ParameterError, match="'response_quantity'"):
        random_record(plant, 2.0, response_quantity="strain")
