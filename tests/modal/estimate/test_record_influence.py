"""Each record's share of a continuous estimate's error (modal.estimate.record_influence), carried by its noise
model, and what identification says about the errors it reports from them."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.errors import QualityWarning
from modal.estimate import core
from modal.estimate.windows import segment_window
from modal.synthetic_time import DigitalModes, random_record

FS = 1024.0
PLANT = DigitalModes(np.array([40.0, 95.0]), np.array([0.02, 0.012]), np.array([0.5, 0.8]), FS)


@pytest.fixture(scope="module")
def record():
    return random_record(PLANT, 60.0, response_noise=0.05, seed=7).record


def _estimate(record, **options):
    return modal.estimate_frf(record.signals[0], record.signals[1], FS, kind="accelerance", **options)


def test_influences_are_each_records_share_of_the_error(record):
    frf = _estimate(record)
    model = frf.noise_model
    length, step = frf.segment_length, frf.segment_length // 2
    starts = np.arange(0, record.signals.shape[1] - length + 1, step)
    assert model.record_influence.shape == (starts.size, frf.frequency_hz.size)
    assert model.overlapping_records == 1 and not model.influence_withheld
    # one record's share from its own transforms: ψ = (Y − Ĥ X) conj(X) / Σ|X|²
    window = segment_window("hann", length)
    x = np.fft.rfft(record.signals[0, starts[:, None] + np.arange(length)] * window, axis=-1)
    y = np.fft.rfft(record.signals[1, starts[:, None] + np.arange(length)] * window, axis=-1)
    expected = (y[5] - frf.response * x[5]) * x[5].conj() / np.sum(np.abs(x) ** 2, axis=0)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(model.record_influence[5], expected, rtol=0, atol=1e-9 * scale)
    # H1 leaves no residual correlated with the excitation: the shares sum to zero at every line
    assert np.abs(model.record_influence.sum(axis=0)).max() <= 1e-9 * scale


def test_few_records_hits_and_a_full_budget_carry_none(record, monkeypatch):
    short = _estimate(record, segment_length=16384)  # 6 records
    assert short.noise_model.record_influence is None and not short.noise_model.influence_withheld
    monkeypatch.setattr(core, "MAX_INFLUENCE_VALUES", 1000)
    withheld = _estimate(record)
    assert withheld.noise_model.record_influence is None and withheld.noise_model.influence_withheld
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = modal.identify(withheld)
    assert "memory budget" in result.settings["pole_errors"]


def test_identify_reports_errors_measured_over_the_records(record):
    frf = _estimate(record)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = modal.identify(frf)
    n = frf.noise_model.record_influence.shape[0]
    assert result.settings["pole_errors"].startswith(f"measured over the {n} records")


def test_conversions_and_crops_carry_the_influences(record):
    frf = _estimate(record)
    influence = frf.noise_model.record_influence
    keep = (frf.frequency_hz >= 20) & (frf.frequency_hz <= 150)
    np.testing.assert_array_equal(frf.cropped(20, 150).noise_model.record_influence, influence[:, keep])
    cropped = frf.cropped(20, 150)
    receptance = cropped.as_kind("receptance")
    np.testing.assert_allclose(receptance.noise_model.record_influence,
                               cropped.noise_model.record_influence * (1j * cropped.omega_rad_s) ** -2)
    # the response measured as acceleration, the FRF asked as receptance: the influences convert with it
    direct = modal.estimate_frf(record.signals[0], record.signals[1], FS, kind="receptance",
                                response_quantity="acceleration")
    omega = direct.omega_rad_s
    np.testing.assert_allclose(direct.noise_model.record_influence, influence[:, 1:] * (1j * omega) ** -2,
                               rtol=1e-9, atol=1e-12 * np.abs(influence[:, 1:] / omega**2).max())


def test_several_channels_carry_each_records_share_of_their_errors(monkeypatch):
    # two independent forces, two outputs: Ĥ_o = S_yx,o S_xx⁻¹, so record i's share of channel (o, q) is
    # Σ_p R_iop conj(X_ip) [S_xx⁻¹]_pq with R_io = Y_io − Ĥ_o X_i; as for one channel, the shares of every
    # channel sum to zero at every line (H1 leaves no residual correlated with any input), to rounding
    rng = np.random.default_rng(5)
    length, n = 1024, 1024 * 24
    forces = rng.standard_normal((2, n))
    second = DigitalModes(PLANT.natural_frequency_hz, PLANT.damping_ratio, np.array([[0.3, -0.6], [0.2, 0.5]]), FS)
    first = DigitalModes(PLANT.natural_frequency_hz, PLANT.damping_ratio, np.array([[0.5, 0.8], [0.4, -0.3]]), FS)
    responses = first.respond(forces[0]) + second.respond(forces[1])
    responses += 0.05 * responses.std(axis=1, keepdims=True) * rng.standard_normal(responses.shape)
    frf = modal.estimate_frf(forces, responses, FS, segment_length=length)
    starts = np.arange(0, n - length + 1, length // 2)
    influence = frf.noise_model.record_influence
    assert influence.shape == (4, starts.size, length // 2 + 1) and frf.noise_model.overlapping_records == 1
    window = segment_window("hann", length)
    x = np.fft.rfft(forces[:, starts[:, None] + np.arange(length)] * window, axis=-1)  # (inputs, records, lines)
    y = np.fft.rfft(responses[:, starts[:, None] + np.arange(length)] * window, axis=-1)
    sxx = np.einsum("isk,jsk->kij", x, x.conj())
    h = frf.response.reshape(2, 2, -1)  # (outputs, inputs, lines)
    residual = y[:, 5] - np.einsum("opk,pk->ok", h, x[:, 5])
    expected = np.einsum("ok,pk,kpq->oqk", residual, x[:, 5].conj(), np.linalg.inv(sxx)).reshape(4, -1)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(influence[:, 5], expected, rtol=0, atol=1e-9 * scale)
    assert np.abs(influence.sum(axis=1)).max() <= 1e-9 * scale
    # one input, several outputs: each output's shares, those of its one-output estimate
    with warnings.catch_warnings():  # one force alone: the other's response is warned of as its noise
        warnings.simplefilter("ignore", QualityWarning)
        single = modal.estimate_frf(forces[0], responses, FS, segment_length=length)
        alone = modal.estimate_frf(forces[0], responses[1], FS, segment_length=length)
    np.testing.assert_allclose(single.noise_model.record_influence[1], alone.noise_model.record_influence,
                               rtol=0, atol=1e-9 * np.abs(alone.noise_model.record_influence).max())
    # one channel taken out carries its own shares
    np.testing.assert_array_equal(frf.channel(2).noise_model.record_influence, influence[2])
    # the memory budget counts every channel's: 47 records × 513 lines fit in it once, not four times
    monkeypatch.setattr(core, "MAX_INFLUENCE_VALUES", 2 * starts.size * (length // 2 + 1))
    withheld = modal.estimate_frf(forces, responses, FS, segment_length=length).noise_model
    assert withheld.record_influence is None and withheld.influence_withheld


def test_errors_measured_over_the_records_take_no_truncation_shift(record, monkeypatch):
    # errors measured over the records are widened by a misfit the records do not see (the residual's power
    # over theirs); the truncation check's shift, added on top, counted a misfit twice, and with one shaker and
    # three outputs (their lines whitened with the window's model) it was measured on most records, noise added
    # to the errors (z SD of ζ 0.68-0.71 over 80 records)
    from modal.sdof import pipeline

    outputs = DigitalModes(PLANT.natural_frequency_hz, PLANT.damping_ratio,
                           np.array([[0.5, 0.8], [0.45, 0.35], [0.3, -0.75]]), FS)
    many = random_record(outputs, 60.0, response_noise=0.05, seed=3).record
    frf = modal.estimate_frf(many.signals[0], many.signals[1:], FS, kind="accelerance", segment_length=4096)
    assert frf.noise_model.record_influence.shape[:2] == (3, frf.averages)
    consulted = []
    monkeypatch.setattr(pipeline, "truncation", lambda *args, **kwargs: consulted.append(1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = modal.identify(frf)
    assert result.settings["pole_errors"].startswith(f"measured over the {frf.averages} records")
    assert not consulted
    # one channel whose errors are not measured (too few records) still takes the check
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        modal.identify(_estimate(record, segment_length=16384))
    assert consulted
