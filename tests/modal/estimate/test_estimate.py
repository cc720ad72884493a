"""FRFs from time data: estimators, noise calibration, windows, hits (modal.estimate_frf)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.errors import ParameterError, QualityWarning
from modal.estimate import overlap_variance_factor
from modal.estimate.windows import segment_window
from support.timedata import DigitalModes, hammer_force

FS = 1024.0
#: median of |e|/σ for a circular complex Gaussian e with E|e|² = σ² (Rayleigh): √ln 2
RAYLEIGH_MEDIAN = np.sqrt(np.log(2.0))


def _median_sampling_std(n: int) -> float:
    """Standard deviation of the median of n Rayleigh draws: 1/(2 f(m) √n), f(m) = 2m e^{−m²} at m = √ln 2."""
    density = 2 * RAYLEIGH_MEDIAN * np.exp(-RAYLEIGH_MEDIAN**2)
    return 1.0 / (2.0 * density * np.sqrt(n))


@pytest.fixture(scope="module")
def plant():
    # three modes, four outputs; ζ large enough that a 1024-sample Hann record holds the
    # impulse response (decay time 1/(ζωn) ≤ 0.11 s against 1 s records): leakage bias ≪ noise
    return DigitalModes(np.array([40.0, 95.0, 170.0]), np.array([0.04, 0.03, 0.02]),
                        np.array([[1.0, 0.5, 0.3], [0.8, -0.6, 0.2], [0.3, 0.9, -0.5], [-0.4, 0.2, 0.7]]), FS)


def test_one_record_rect_one_average_is_exactly_y_over_x():
    rng = np.random.default_rng(0)
    x, y = rng.standard_normal(512), rng.standard_normal((2, 512))
    with pytest.warns(QualityWarning, match="one record: its coherence is 1 by construction"):
        est = modal.estimate_frf(x, y, FS, window="rect", segment_length=512)
    expected = np.fft.rfft(y, axis=-1) / np.fft.rfft(x)
    assert est.averages == 1 and est.noise_std is None  # one average: the random error is undefined
    np.testing.assert_allclose(est.response, expected, rtol=1e-12, atol=0)
    np.testing.assert_allclose(est.frequency_hz, np.fft.rfftfreq(512, 1 / FS))


def test_one_hit_rect_is_exactly_y_over_x(plant):
    n = 4096
    force = hammer_force(n, FS, [0.5])
    y = plant.respond(force)[:1]
    est = modal.estimate_frf(force, y, FS, window="rect", impact=True, segment_length=2048, pretrigger_s=0.0)
    start = int(np.argmax(force > 0.05 * force.max()))  # the trigger: first sample above 5 % of the peak
    expected = np.fft.rfft(y[0, start:start + 2048]) / np.fft.rfft(force[start:start + 2048])
    assert est.averages == 1 and est.rejected == []
    np.testing.assert_allclose(est.response, expected, rtol=1e-12)


def test_overlap_variance_factor_matches_welch():
    # ρ(50 %) = 1/6 for the periodic Hann window and 1/2 for the rectangular one
    assert overlap_variance_factor(segment_window("hann", 1024), 512) == pytest.approx(1 + 2 / 36, rel=1e-12)
    assert overlap_variance_factor(segment_window("rect", 1024), 512) == pytest.approx(1.5, rel=1e-12)
    assert overlap_variance_factor(segment_window("hann", 1024), 1024) == 1.0


@pytest.mark.parametrize("window, overlap", [("hann", 0.5), ("rect", 0.0)])
def test_noise_std_is_calibrated_on_random_excitation(plant, window, overlap):
    rng = np.random.default_rng(1)
    n = 2**18
    force = rng.standard_normal(n)
    clean = plant.respond(force)
    noisy = clean + 0.1 * clean.std(axis=1, keepdims=True) * rng.standard_normal(clean.shape)
    # 4 s records: Hann's leakage bias at the sharpest resonance is (1/3)(Be/Br)² ≈ 0.3 % (B&P 9.3),
    # below the random error, so the median against the truth is the random error's
    est = modal.estimate_frf(force, noisy, FS, segment_length=4096, window=window, overlap=overlap)
    truth = plant.frf(est.frequency_hz)
    ratio = (np.abs(est.response - truth) / est.noise_std)[:, 1:-1]  # DC and Nyquist lines are real: not circular
    # |error|/noise_std is Rayleigh when noise_std is right: its median is √ln2 ≈ 0.833, known to within
    # the median's own sampling error (4 of them: a 6e-5 false-alarm rate)
    assert abs(np.median(ratio) - RAYLEIGH_MEDIAN) < 4 * _median_sampling_std(ratio.size)
    # H1 is linear in the response: against the noise-free estimate from the same force the difference is
    # exactly the random error, bias-free at every line, resonances included: mean square 1 (Exp(1) mean)
    # (with the rectangular window the records' leakage is part of the residual, and of the error against
    # the truth, but not of this difference: there the check is against the truth below)
    reference = est if window == "rect" else modal.estimate_frf(force, clean, FS, segment_length=4096,
                                                                 window=window, overlap=overlap)
    against = truth if window == "rect" else reference.response
    z2 = (np.abs(est.response - against) / est.noise_std)[:, 1:-1] ** 2
    # E z² = (n−1)/(n−2) ≈ 1 + 1/(n−2) for a variance estimated with n − 1 degrees of freedom; the mean of
    # N Exp(1) draws scatters by 1/√N (4 of them allowed)
    assert np.mean(z2) == pytest.approx(1.0 + 1.0 / (est.averages - 2), abs=4 / np.sqrt(z2.size))
    assert est.coherence.shape == est.response.shape and np.all((0 <= est.coherence) & (est.coherence <= 1))


def test_h1_biased_low_with_force_noise_and_h2_not(plant):
    rng = np.random.default_rng(2)
    n = 2**22
    force = rng.standard_normal(n)
    response = plant.respond(force)[0]
    measured_force = force + 0.3 * rng.standard_normal(n)  # 30 % noise on the force channel
    # 4 s records: leakage (response to the previous record's force, which acts as output noise and
    # biases H2 up) is negligible; the window's remaining bias is the same in the noise-free reference
    h1 = modal.estimate_frf(measured_force, response, FS, segment_length=4096)
    h2 = modal.estimate_frf(measured_force, response, FS, segment_length=4096, estimator="H2")
    reference = modal.estimate_frf(force, response, FS, segment_length=4096)
    line = int(np.argmin(np.abs(h1.frequency_hz - 40.0)))
    # the tolerance is 4 of each estimate's own (calibrated) random errors
    tol1 = 4 * h1.noise_std[line] / abs(reference.response[line])
    tol2 = 4 * h2.noise_std[line] / abs(reference.response[line])
    # H1 = H · Gxx/(Gxx + Gnn) = H/(1 + 0.3²) for a white force; H2 is unbiased by input noise
    assert abs(h1.response[line] / reference.response[line]) == pytest.approx(1 / 1.09, abs=tol1)
    assert abs(h2.response[line] / reference.response[line]) == pytest.approx(1.0, abs=tol2)
    assert tol1 < 0.04 and tol2 < 0.04  # under half the gap between 1/1.09 and 1: the test can tell them apart


def test_hv_lies_between_h1_and_h2(plant):
    rng = np.random.default_rng(3)
    n = 2**16
    force = rng.standard_normal(n)
    response = plant.respond(force)[0]
    f_meas = force + 0.2 * rng.standard_normal(n)
    y_meas = response + 0.2 * response.std() * rng.standard_normal(n)
    est = {e: modal.estimate_frf(f_meas, y_meas, FS, segment_length=1024, estimator=e) for e in ("H1", "H2", "Hv")}
    mag = {e: np.abs(v.response) for e, v in est.items()}
    assert np.all(mag["H1"] <= mag["Hv"] * (1 + 1e-12)) and np.all(mag["Hv"] <= mag["H2"] * (1 + 1e-12))


def test_mimo_h1_recovers_both_columns(plant):
    rng = np.random.default_rng(4)
    n = 2**17
    forces = rng.standard_normal((2, n))
    # output o responds to input i through mode constants scaled per input
    second = DigitalModes(plant.natural_frequency_hz, plant.damping_ratio, 0.5 * plant.modal_constant[::-1], FS)
    clean = plant.respond(forces[0]) + second.respond(forces[1])
    noisy = clean + 0.05 * clean.std(axis=1, keepdims=True) * rng.standard_normal(clean.shape)
    est = modal.estimate_frf(forces, noisy, FS, segment_length=1024, excitation_points=["a", "b"],
                             response_points=["1", "2", "3", "4"])
    assert est.n_channels == 8 and est.reference_points[:2] == ("a", "b") and est.response_points[:2] == ("1", "1")
    truth = np.stack([plant.frf(est.frequency_hz), second.frf(est.frequency_hz)], axis=1).reshape(8, -1)
    ratio = (np.abs(est.response - truth) / est.noise_std)[:, 1:-1]
    # calibrated noise: no line beyond 6 noise_std (Rayleigh tail e^{-36} per line)
    assert ratio.max() < 6
    assert abs(np.median(ratio) - RAYLEIGH_MEDIAN) < 4 * _median_sampling_std(ratio.size)
    assert est.multiple_coherence.shape == (4, est.n_freq)


def test_mimo_estimate_carries_the_windows_lag_window(plant):
    # each input's column is, in expectation, the transform of its impulse response times the lag window of the
    # windows and that input's mean square per sample: stationary inputs share it, and the estimate carries it so
    # that identification takes the window's bias out of the damping (without it, two shakers' damping came out
    # +2.3 to +3.0 standard errors high on average over 40 records of 120 s with the default Hann segments). It is
    # the one-input estimate's of either force alone, to the scatter of the forces' mean square per sample over
    # 255 half-overlapping records (a few 1e-3)
    rng = np.random.default_rng(4)
    forces = rng.standard_normal((2, 2**17))
    second = DigitalModes(plant.natural_frequency_hz, plant.damping_ratio, 0.5 * plant.modal_constant[::-1], FS)
    clean = plant.respond(forces[0]) + second.respond(forces[1])
    mimo = modal.estimate_frf(forces, clean, FS, segment_length=1024)
    assert mimo.noise_model.line_correlation is None and mimo.noise_model.lag_window is not None
    for force in forces:
        with warnings.catch_warnings():  # one force alone: the other's response is warned of as its noise
            warnings.simplefilter("ignore", QualityWarning)
            single = modal.estimate_frf(force, clean[0], FS, segment_length=1024).noise_model.lag_window
        np.testing.assert_allclose(mimo.noise_model.lag_window, single, atol=0.01)


def test_impact_double_hit_is_rejected_and_named(plant):
    n = int(8 * FS)
    hits = [0.5, 2.5, 2.51, 4.5, 6.5]  # the second hit bounces after 10 ms: a double hit
    force = hammer_force(n, FS, hits)
    y = plant.respond(force)
    est = modal.estimate_frf(force, y, FS, impact=True, window="force", segment_length=1024)
    assert est.rejected == [{"hit": 2, "time_s": pytest.approx(2.5, abs=1.5 / FS), "reason": "double hit",
                             "detail": "a second pulse 10 ms after the first"}]
    assert est.averages == 3
    truth = plant.frf(est.frequency_hz)
    band = (est.frequency_hz > 10) & (est.frequency_hz < 250)  # within the 2 ms hammer's band
    # noise-free records of decayed responses: each hit gives the exact FRF up to the decay left at the end
    assert np.max(np.abs(est.response[:, band] - truth[:, band])) < 1e-3 * np.max(np.abs(truth))


def test_exponential_window_shifts_every_pole_by_one_over_tau(plant):
    # A lightly damped mode that does not decay within the record: the exponential window forces the decay.
    # ζ = 0.005 at 60 Hz decays with 0.53 s: 2.3 % left after a 2 s record (leakage); the next hit comes
    # 8 s later, when e^-15 of the first is left
    light = DigitalModes(np.array([60.0]), np.array([0.005]), np.array([[1.0]]), FS)
    n = int(17 * FS)
    force = hammer_force(n, FS, [0.5, 8.5])
    y = light.respond(force)
    tau = 0.1
    est = modal.estimate_frf(force, y, FS, impact=True, window="exponential", exponential_decay_s=tau,
                             segment_length=2048)
    assert est.exponential_decay_s == tau and est.rejected == []
    # the windowed FRF is the system with its pole moved left by 1/τ, residue unchanged
    p = light.poles()[0] - 1.0 / tau
    wn, zeta = abs(p), -p.real / abs(p)
    expected = DigitalModes(np.array([wn / 2 / np.pi]), np.array([zeta]), np.array([[1.0]]), FS).frf(est.frequency_hz)
    band = (est.frequency_hz > 20) & (est.frequency_hz < 150)
    assert np.max(np.abs(est.response[band] - expected[0, band])) < 1e-3 * np.max(np.abs(expected))


def test_undecayed_response_is_rejected():
    # ζ = 0.001 at 60 Hz decays with 2.65 s: a 2 s record ends with 47 % of the peak left (the hits are 12 s
    # apart, so each starts in silence)
    light = DigitalModes(np.array([60.0]), np.array([0.001]), np.array([[1.0]]), FS)
    n = int(26 * FS)
    force = hammer_force(n, FS, [0.5, 12.5])
    with pytest.raises(ParameterError, match="every hit was rejected") as info:
        modal.estimate_frf(force, light.respond(force), FS, impact=True, window="force", segment_length=2048)
    reasons = str(info.value)
    assert "hit 1" in reasons and "hit 2" in reasons and "response not decayed within the record" in reasons


def test_clipped_force_is_rejected():
    light = DigitalModes(np.array([60.0]), np.array([0.05]), np.array([[1.0]]), FS)
    n = int(6 * FS)
    force = hammer_force(n, FS, [0.5, 2.5, 4.5], width_s=0.006)
    start = int(2.5 * FS)
    force[start:start + 7] = np.minimum(force[start:start + 7], 60.0)  # the converter clips hit 2
    force[int(0.5 * FS):int(0.5 * FS) + 7] *= 0.5  # hits 1 and 3 stay below the clip level
    force[int(4.5 * FS):int(4.5 * FS) + 7] *= 0.5
    est = modal.estimate_frf(force, light.respond(force), FS, impact=True, window="force", segment_length=1024)
    assert [(r["hit"], r["reason"]) for r in est.rejected] == [(2, "overload (clipped)")]


def test_kind_conversion_from_acceleration(plant):
    rng = np.random.default_rng(5)
    force = rng.standard_normal(2**15)
    disp = plant.respond(force)[0]
    receptance = modal.estimate_frf(force, disp, FS, segment_length=1024)
    # an acceleration record converted back to receptance (DC line dropped) equals the receptance estimate
    # of the same data multiplied by (iω)² then divided again: exact up to rounding
    acc_frf = receptance.as_kind("accelerance")
    back = acc_frf.cropped(1.0, FS / 2).as_kind("receptance")
    np.testing.assert_allclose(back.response, receptance.cropped(1.0, FS / 2).response, rtol=1e-10)
    np.testing.assert_allclose(back.noise_std, receptance.cropped(1.0, FS / 2).noise_std, rtol=1e-10)
    converted = modal.estimate_frf(force, disp, FS, segment_length=1024, kind="accelerance",
                                   response_quantity="displacement")
    np.testing.assert_allclose(converted.response, acc_frf.response, rtol=1e-12)
    down = modal.estimate_frf(force, disp, FS, segment_length=1024, kind="receptance",
                              response_quantity="acceleration")
    assert down.frequency_hz[0] > 0  # the 0 Hz line cannot be divided by (iω)²


def test_streams_from_a_memmap(tmp_path, plant):
    rng = np.random.default_rng(6)
    force = rng.standard_normal(2**15)
    y = plant.respond(force)
    path = tmp_path / "y.dat"
    mm = np.memmap(path, dtype=float, mode="w+", shape=y.shape)
    mm[:] = y
    mm.flush()
    from_disk = modal.estimate_frf(force, np.memmap(path, dtype=float, mode="r", shape=y.shape), FS,
                                   segment_length=512)
    in_memory = modal.estimate_frf(force, y, FS, segment_length=512)
    np.testing.assert_allclose(from_disk.response, in_memory.response, rtol=1e-12)


def test_cropping_and_channels_keep_noise_and_coherence(plant):
    rng = np.random.default_rng(7)
    force = rng.standard_normal(2**15)
    y = plant.respond(force)
    # noise 1 % of each response's RMS (0.01 m absolute buried these sub-millimetre responses: coherence at chance)
    y = y + 0.01 * np.std(y, axis=1, keepdims=True) * rng.standard_normal(y.shape)
    est = modal.estimate_frf(force, y, FS, segment_length=512)
    cropped = est.cropped(20.0, 200.0)
    keep = (est.frequency_hz >= 20) & (est.frequency_hz <= 200)
    np.testing.assert_array_equal(cropped.noise_std, est.noise_std[:, keep])
    np.testing.assert_array_equal(cropped.coherence, est.coherence[:, keep])
    one = est.channel(2)
    np.testing.assert_array_equal(one.noise_std, est.noise_std[2])
    np.testing.assert_array_equal(one.response, est.response[2])


@pytest.mark.parametrize("kwargs, message", [
    (dict(window="blackman"), "field 'window'"),
    (dict(estimator="H3"), "field 'estimator'"),
    (dict(overlap=1.0), "field 'overlap'"),
    (dict(segment_length=10**9), "field 'segment_length'"),
    (dict(window="force"), "impact records"),
    (dict(kind="inertance"), "field 'kind'"),
])
def test_bad_settings_name_the_field(kwargs, message):
    rng = np.random.default_rng(8)
    with pytest.raises(ParameterError, match=message):
        modal.estimate_frf(rng.standard_normal(4096), rng.standard_normal(4096), FS, **kwargs)


def test_bad_records_name_the_field():
    rng = np.random.default_rng(9)
    x = rng.standard_normal(4096)
    with pytest.raises(ParameterError, match="equal lengths"):
        modal.estimate_frf(x, x[:-1], FS)
    bad = x.copy()
    bad[100] = np.nan
    with pytest.raises(ParameterError, match="'response' has a non-finite sample at channel 1, sample 100"):
        modal.estimate_frf(x, bad, FS)
    with pytest.raises(ParameterError, match="one excitation channel"):
        modal.estimate_frf(np.vstack([x, x[::-1]]), x, FS, estimator="H2")
    with pytest.raises(ParameterError, match="sample_rate_hz"):
        modal.estimate_frf(x, x, -1.0)


def test_plots_draw_the_estimate_and_the_hits(plant):
    from matplotlib.collections import PolyCollection

    from modal.estimate.plots import plot_estimate, plot_hits

    n = int(8 * FS)
    force = hammer_force(n, FS, [0.5, 2.5, 2.51, 4.5, 6.5])
    y = plant.respond(force)
    y = y + 1e-6 * np.random.default_rng(12).standard_normal(y.shape)
    est = modal.estimate_frf(force, y, FS, impact=True, window="force", segment_length=1024,
                             response_points=["a", "b", "c", "d"], excitation_points="a")
    fig = plot_estimate(est, channels=[0, 2])
    ax_mag, ax_phase, ax_coh = fig.axes
    np.testing.assert_allclose(ax_mag.lines[1].get_ydata(), np.abs(est.response[2]))
    np.testing.assert_allclose(ax_coh.lines[0].get_ydata(), est.coherence[0])
    assert [t.get_text() for t in ax_mag.get_legend().get_texts()] == ["a / a", "c / a"]
    bands = [c for c in ax_mag.collections if isinstance(c, PolyCollection)]
    assert len(bands) == 2  # one ±2σ band per channel drawn
    top = bands[0].get_paths()[0].vertices[:, 1].max()
    assert top == pytest.approx(np.max(np.abs(est.response[0]) + 2 * est.noise_std[0]), rel=1e-9)
    fig = plot_hits(force, y, FS, est)
    ax_f, _ = fig.axes
    spans = [p for p in ax_f.patches]
    assert len(spans) == est.averages == 3  # one shaded record per accepted hit
    rejected_lines = [ln for ln in ax_f.lines if ln.get_linestyle() == "--"]
    assert [ln.get_xdata()[0] for ln in rejected_lines] == [est.rejected[0]["time_s"]]
    assert "hit 2: double hit" in [t.get_text() for t in ax_f.texts]


def test_one_record_matches_pyfrf():
    """pyFRF (ladisk, on the test extra) gives the same H1 on one rectangular record, to 1e-8."""
    import pyFRF

    rng = np.random.default_rng(13)
    x = rng.standard_normal(1024)
    y = np.convolve(x, [0.5, 0.2, -0.1])[:1024]
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")  # pyFRF divides by zero at 0 Hz and warns about its own keywords
        theirs = np.squeeze(pyFRF.FRF(1024, exc=x, resp=y, exc_type="f", resp_type="d", window="none").get_H1())
    with pytest.warns(QualityWarning, match="one record"):
        ours = modal.estimate_frf(x, y, 1024.0, window="rect", segment_length=1024)
    # pyFRF's 0 Hz line is NaN (a division by ω there); every other line agrees
    np.testing.assert_allclose(ours.response[1:], theirs[1:], rtol=1e-8)


def test_an_impact_record_with_force_and_response_swapped_is_refused_naming_both():
    # the accelerometer's ringing recorded as the force and the hammer's pulses as the response: hit detection read
    # every ringing peak as a pulse and refused all hits as double hits, which sends a user after the hammer tip
    from modal.synthetic import impact_record

    plant = DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5]], FS)
    record = impact_record(plant, [0.5, 4.5, 8.5], 12.0, seed=2, response_noise=1e-3, force_noise=1e-3).record
    force, response = record.signals[0], record.signals[1]
    with pytest.raises(ParameterError, match=r"force is no train of hammer pulses .* but response 1 is .*look swapped"):
        modal.estimate_frf(response, force, FS, impact=True, window="force", kind="accelerance")
    est = modal.estimate_frf(force, response, FS, impact=True, window="force", kind="accelerance")
    assert est.averages == 3  # the right way round: the three hits


def test_a_hammer_record_swapped_and_estimated_as_continuous_is_warned_naming_the_pulsed_response():
    # without impact=True the impact path's refusal never ran: the ringing accelerometer became the excitation
    # and H1 the inverse of the structure's FRF, with no word (a fit then printed three flagged "modes")
    from modal.synthetic import impact_record

    plant = DigitalModes([40.0, 95.0], [0.01, 0.02], [[1.0, 0.5]], FS)
    record = impact_record(plant, [0.5, 4.5, 8.5], 12.0, seed=2, response_noise=1e-3, force_noise=1e-3).record
    force, response = record.signals[0], record.signals[1]
    with pytest.warns(QualityWarning, match=r"response 1 is \d+ short pulse\(s\) .* while the excitation is none: "
                                            r"the force and response channels look swapped"):
        modal.estimate_frf(response, force, FS, kind="accelerance", segment_length=1024)
    with warnings.catch_warnings(record=True) as caught:  # the right way round: only the hint to use impact=True
        warnings.simplefilter("always")
        modal.estimate_frf(force, response, FS, kind="accelerance", segment_length=1024)
    assert not [w for w in caught if "look swapped" in str(w.message)]
    assert [w for w in caught if "estimate it as an impact record" in str(w.message)]


def test_a_shaker_record_with_a_lightly_damped_response_is_no_pulse_train():
    # a random force has no sample above 8 robust standard deviations, so the responses are not screened; a
    # swept sine's response swells at each resonance, which must not read as hits either way
    from modal.estimate.hits import pulse_train

    rng = np.random.default_rng(3)
    plant = DigitalModes([40.0, 95.0], [0.002, 0.005], [[1.0, 0.5], [0.4, -0.9]], FS)
    t = np.arange(int(40 * FS)) / FS
    sweep = np.sin(2 * np.pi * (5.0 * t + 0.5 * (195.0 / 40.0) * t**2))  # 5 → 200 Hz in 40 s
    for force in (rng.standard_normal(t.size), sweep):
        response = plant.respond(force, "acceleration")
        response += 1e-3 * response.std() * rng.standard_normal(response.shape)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            modal.estimate_frf(force, response, FS, kind="accelerance", segment_length=4096)
        assert not [w for w in caught if "pulse" in str(w.message)], [str(w.message) for w in caught]
        # and were they screened (an excitation with a few excursions), they would pass
        assert not any(pulse_train(channel, FS).impulsive for channel in response)


@pytest.mark.parametrize("records, warned", [(1, "one record"), (2, "2 records"), (3, None)])
def test_a_continuous_record_of_fewer_than_three_records_is_warned(records, warned):
    # with one or two records each line's noise rests on 0 or 1 degree of freedom: fits of 2-record estimates
    # gave error bars 1.5–2.7 times too small; 3 records (the bench's random-hann-3avg cell) 0.6–1.2
    rng = np.random.default_rng(3)
    x = rng.standard_normal(512 * records)
    y = np.convolve(x, [0.5, 0.2, -0.1])[:x.size]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        est = modal.estimate_frf(x, y, FS, window="hann", segment_length=512, overlap=0.0, source="short.csv")
    assert est.averages == records
    said = [str(w.message) for w in caught if issubclass(w.category, QualityWarning)]
    if warned is None:
        assert said == []
    else:
        assert len(said) == 1 and said[0].startswith(f"short.csv: the FRF is averaged over {warned}")
        assert "segment_length 512 samples = 0.5 s" in said[0]


@pytest.mark.parametrize("correlation, warned", [(0.0, False), (0.999, True)])
def test_two_shakers_driven_by_nearly_one_signal_are_warned(correlation, warned):
    # two forces 99.8 % coherent: MIMO H1 rests on the 0.2 % they do not share; synthetic two-shaker fits gave
    # errors 95 times their error bars there (1.7–2.8 for inputs up to 0.9 coherent, as with independent ones)
    rng = np.random.default_rng(11)
    first = rng.standard_normal(2**15)
    second = correlation * first + np.sqrt(1 - correlation**2) * rng.standard_normal(first.size)
    response = np.convolve(first, [0.5, 0.2, -0.1])[:first.size] + np.convolve(second, [0.3, -0.2])[:first.size]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        modal.estimate_frf(np.vstack([first, second]), response, FS, segment_length=1024, source="mimo.csv",
                           excitation_points=["1+Z", "2+Z"])
    said = [str(w.message) for w in caught if issubclass(w.category, QualityWarning)]
    if warned:
        assert len(said) == 1 and said[0].startswith("mimo.csv: force 1+Z and force 2+Z are 99.8 % coherent")
    else:
        assert said == []


def test_runs_with_one_blas_thread_and_gives_the_callers_setting_back(monkeypatch, plant):
    """The estimate's products are small or one vector long (the noise split's sums over the lines): a BLAS
    thread per core only waits for its threads (modal/blas.py), so the call runs with one, whatever the
    caller set, and the caller's setting holds again after."""
    from threadpoolctl import threadpool_info, threadpool_limits

    import modal.noise_model

    seen = []
    real = modal.noise_model._nonnegative_fit_of_sums

    def spy(sums):  # each round of the noise split, from its BLAS dot products
        seen.append({lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"})
        return real(sums)

    monkeypatch.setattr(modal.noise_model, "_nonnegative_fit_of_sums", spy)
    rng = np.random.default_rng(5)
    force = rng.standard_normal(16384)
    response = plant.respond(force)
    response += 0.01 * response.std() * rng.standard_normal(response.shape)
    with threadpool_limits(2, user_api="blas"):
        modal.estimate_frf(force, response, FS, segment_length=1024)
        after = {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    assert seen and all(threads == {1} for threads in seen)
    assert after == {2}
