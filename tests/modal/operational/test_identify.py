"""modal.oma: every mode once, no tone or spurious pole as a mode, errors that cover the truth, clear
errors for bad input."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from modal.errors import ParameterError
from modal.operational.selection import OMAStabilisation, shape_mac
from modal.synthetic import ambient_modal_response, ambient_response, chain_matrices
from support.ambient import FN, FORCE, TONES, ZETA, anchor_record, anchor_shapes

#: a fixed seed's estimate lies within this many of its standard errors of the truth (for calibrated
#: Gaussian errors, one of the 12 values of a case exceeds it with probability 12 · 6e-5 < 0.1 %)
SIGMAS = 4.0


def _oma(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return modal.oma(*args, **kwargs)


def _match(result, fn):
    """Index of the result's mode within 0.5 % of each true frequency (asserting exactly one each)."""
    found = []
    for f in fn:
        near = [i for i, m in enumerate(result) if abs(m.natural_frequency_hz / f - 1) < 0.005]
        assert len(near) == 1, (f, [m.natural_frequency_hz for m in result])
        found.append(near[0])
    return found


@pytest.mark.parametrize("seed, noise, tones", [(11, 0.05, True), (12, 0.2, True), (13, 0.1, False)])
def test_anchor_case_every_mode_once_within_its_errors(seed, noise, tones):
    rec = anchor_record(seed, noise=noise, tones=tones)
    result = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0))
    assert result.method == "ssi"
    found = _match(result, FN)
    assert len(result) == len(FN)  # nothing else: no tone, no spurious pole among the modes
    for k, i in enumerate(found):
        mode = result[i]
        assert abs(mode.natural_frequency_hz - FN[k]) < SIGMAS * mode.std.natural_frequency_hz
        assert abs(mode.damping_ratio - ZETA[k]) < SIGMAS * mode.std.damping_ratio
        assert shape_mac(mode.mode_shape, rec.mode_shape[:, k]) >= 0.98
        assert mode.mode_shape.shape == (8,) and np.iscomplexobj(mode.mode_shape)
        assert np.all(np.isnan(mode.mass_kg)) and np.all(np.isnan(mode.stiffness_n_per_m))
        assert mode.std.mode_shape.shape == (8,) and np.all(np.isfinite(mode.std.mode_shape))
        # the flags stay silent on modes the record determines (relative errors of zeta 3-7 % here): a flag
        # that fired on these would say nothing where it fires on the real record
        assert mode.flags == (), (mode.natural_frequency_hz, mode.flags)
    if tones:
        assert len(result.harmonics_hz) == 3
        assert np.allclose(sorted(result.harmonics_hz), TONES, atol=0.01)
    else:
        assert result.harmonics_hz == ()


def test_shape_errors_cover_the_truth():
    rec = anchor_record(14, noise=0.1, tones=False)
    result = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0))
    z = []
    for k, i in enumerate(_match(result, FN)):
        mode = result[i]
        lead = int(np.argmax(np.abs(mode.mode_shape)))  # the estimate's entry 1 (error 0 by definition)
        err = mode.mode_shape - rec.mode_shape[:, k] / rec.mode_shape[lead, k]
        ok = np.arange(8) != lead
        z.append(np.abs(err[ok]) / mode.std.mode_shape[ok])
    z = np.concatenate(z)
    # |error|/σ of a complex entry is Rayleigh-like: its RMS is 1 when the errors are calibrated
    assert 0.6 < np.sqrt(np.mean(z**2)) < 1.6


def test_weakly_excited_mode_is_found():
    # mode 5 of the anchor case is driven by a tenth of the others' force: 1 % of their response power
    rec = anchor_record(15, noise=0.1, tones=True)
    result = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0))
    i = _match(result, FN)[4]
    assert abs(result[i].natural_frequency_hz - FN[4]) < SIGMAS * result[i].std.natural_frequency_hz


def test_chain_with_forces_at_two_masses():
    M, C, K = chain_matrices([2.0, 1.0, 1.5, 1.0], [8e3, 5e3, 6e3, 4e3], 0.02)
    rec = ambient_response(M, C, K, 200.0, 200_000, force_dofs=[1, 3], quantity="displacement", noise=0.1, seed=2)
    result = _oma(rec.signals, 200.0, band_hz=(1.0, 60.0), quantity="displacement")
    assert result.kind == "receptance"
    found = _match(result, rec.natural_frequency_hz)
    assert len(result) == 4
    for k, i in enumerate(found):
        assert abs(result[i].damping_ratio - 0.02) < SIGMAS * result[i].std.damping_ratio
        assert shape_mac(result[i].mode_shape, rec.mode_shape[:, k]) >= 0.98


def test_rotor_speed_flags_a_mode_on_a_harmonic():
    # a structural mode at 2 × 5.6 Hz and tones at 1× and 3×: the tones go to harmonics_hz, the mode
    # on the second harmonic stays a mode, flagged
    shapes = anchor_shapes()[:, :3]
    rec = ambient_modal_response([3.1, 11.2, 20.0], [0.015, 0.01, 0.02], shapes, 100.0, 100_000, noise=0.1,
                                 tones_hz=[5.6, 16.8], tone_rms=0.5, seed=3)
    result = _oma(rec.signals, 100.0, band_hz=(1.0, 30.0), rotor_speed_hz=5.6)
    on_harmonic = [m for m in result if abs(m.natural_frequency_hz - 11.2) < 0.05]
    assert len(on_harmonic) == 1 and "harmonic" in on_harmonic[0].flags
    assert np.allclose(sorted(result.harmonics_hz), [5.6, 16.8], atol=0.01)
    assert all("harmonic" not in m.flags for m in result if abs(m.natural_frequency_hz - 11.2) > 0.05)


def test_stabilisation_diagram_is_kept():
    rec = anchor_record(16, noise=0.1, tones=True)
    result = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0))
    diagram = result.stabilisation
    assert isinstance(diagram, OMAStabilisation)
    assert diagram.chosen[diagram.cluster >= 0].sum() == len(result)
    assert (diagram.chosen & diagram.tone).sum() == len(result.harmonics_hz) == 3
    for k, mode in enumerate(result):
        pick = diagram.chosen & (diagram.cluster == k)
        assert pick.sum() == 1
        assert diagram.frequency_hz[pick][0] == pytest.approx(mode.natural_frequency_hz, rel=1e-9)
    # the tones' poles are marked, and are no mode's
    assert np.all(diagram.cluster[diagram.tone] == -1)
    assert np.any(np.abs(diagram.frequency_hz[diagram.tone] - 4.8) < 0.01)


def test_time_record_and_path_give_the_rate(tmp_path):
    from modal.io.timedata import TimeRecord

    rec = anchor_record(17, noise=0.1, tones=False, duration_s=600.0)
    record = TimeRecord(rec.signals, rec.sample_rate_hz, tuple(f"{k + 1}+Z" for k in range(8)),
                        ("acceleration",) * 8, ("m/s^2",) * 8, "anchor.h5")
    result = _oma(record, band_hz=(1.0, 30.0))
    assert result.settings["sample_rate_hz"] == 100.0
    assert result.settings["channel_names"][0] == "1+Z"
    assert len(result) == 6


def _record(n_channels=3, n=20_000, seed=0):
    shapes = anchor_shapes(n_channels)[:, :2]
    return ambient_modal_response([5.0, 12.0], [0.02, 0.02], shapes, 100.0, n, seed=seed).signals


@pytest.mark.parametrize("data, kwargs, message", [
    (_record(n_channels=1), {}, "1 channel; operational modal analysis needs at least 2"),
    (np.vstack([_record(2), np.full(20_000, 3.0)]), {}, r"channel\(s\) 3 constant"),
    (np.where(np.arange(20_000) == 77, np.nan, _record(3)), {}, "channel 1, sample 77: nan"),
    (np.vstack([_record(2), np.where(np.arange(20_000) == 5, -np.inf, 1.0)]), {}, "channel 3, sample 5: -inf"),
    # finite samples whose sum overflows double precision: named, not turned into NaN correlations
    (np.vstack([_record(2), np.full(20_000, 1e305) * (1 + np.arange(20_000) % 2)]), {}, "channel 3: samples up to 2e"),
    (_record(n=1500), {}, "the record lasts 15 s"),
    (_record(), {"band_hz": (1.0, 80.0)}, r"FMAX <= 50 Hz"),
    (_record(), {"band_hz": (10.0, 5.0)}, "0 <= FMIN < FMAX"),
    (_record(), {"reference_channels": [0, 7]}, "reference_channels"),
    (_record(), {"method": "magic"}, "'method' is 'magic'"),
    (_record(), {"sample_rate_hz": None}, "'sample_rate_hz' is missing"),
    (_record(), {"rotor_speed_hz": -3.0}, "rotor_speed_hz"),
    (_record(), {"band_hz": (0.1, 2.0)}, "the record lasts 200 s; the band from 0.2 Hz"),
    (_record(), {"max_order": 4000}, "the record lasts 200 s; .* model order 4000"),
    (_record(), {"workers": 0}, "'workers' is 0; expected a positive integer"),
])
def test_bad_input_is_one_clear_error(data, kwargs, message):
    kwargs = {"sample_rate_hz": 100.0, **kwargs}
    with pytest.raises(ParameterError, match=message) as info:
        _oma(data, **kwargs)
    assert "\n" not in str(info.value)


def test_many_channels_take_fewer_output_block_rows():
    """32 sensors, 8 references: the outputs take as many block rows as make the Hankel matrix about twice
    as tall as wide (not the references' 34), and every mode is still found once within its errors."""
    rng = np.random.default_rng(3)
    shapes = rng.standard_normal((32, FN.size))
    rec = ambient_modal_response(FN, ZETA, shapes, 100.0, 200_000, modal_force_std=FORCE, noise=0.1, seed=4)
    result = _oma(rec.signals, 100.0, band_hz=(1.0, 30.0))
    rows, cols = result.settings["block_rows"], result.settings["block_cols"]
    assert len(result.settings["reference_channels"]) == 8 and cols == 34
    assert rows == 17 and 32 * (rows + 1) <= 2 * 8 * cols * 1.1  # about twice as tall as wide: 576 x 272
    found = _match(result, FN)
    assert len(result) == len(FN)
    for k, i in enumerate(found):
        mode = result[i]
        assert abs(mode.natural_frequency_hz - FN[k]) < SIGMAS * mode.std.natural_frequency_hz
        assert abs(mode.damping_ratio - ZETA[k]) < SIGMAS * mode.std.damping_ratio
        assert shape_mac(mode.mode_shape, shapes[:, k]) >= 0.98


def test_many_channel_errors_hold_over_a_few_records():
    """The anchor case on 32 sensors (8 references chosen, fewer output block rows than the references'):
    every mode once, and z = error / reported error over 4 records × 6 modes × (frequency, damping).

    48 values of z: for calibrated errors their mean square is χ²₄₈/48, between 0.48 and 1.75 with
    probability 99.9 % (RMS 0.69-1.32); the bounds below leave room for the correlation between a record's
    frequency and damping errors. The 50-record table is ``python -m benchmarks.bench_oma --records 0
    --calibration 50 --channels 32``."""
    z = []
    for seed in range(4):
        rec = anchor_record(60 + seed, noise=0.1, tones=True, n_sensors=32)
        result = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0))
        assert result.settings["block_rows"] < result.settings["block_cols"]  # the many-channel layout
        assert len(result) == len(FN) and np.allclose(sorted(result.harmonics_hz), TONES, atol=0.01)
        for k, i in enumerate(_match(result, FN)):
            mode = result[i]
            z.append((mode.natural_frequency_hz - FN[k]) / mode.std.natural_frequency_hz)
            z.append((mode.damping_ratio - ZETA[k]) / mode.std.damping_ratio)
            assert shape_mac(mode.mode_shape, rec.mode_shape[:, k]) >= 0.98
    rms = np.sqrt(np.mean(np.square(z)))
    assert 0.65 < rms < 1.4, rms


def test_single_and_double_precision_records_give_the_same_modes():
    """The same record stored in single precision, with an offset of 5 RMS: its samples differ from the
    double-precision ones by rounding (3e-8 of each), white and far below the 10 % measurement noise, and both are
    centred in double precision before the single-precision FFTs; the modes then differ by the FFTs' rounding
    (1e-7 of the correlations, whose scatter over 40 000 samples is about 1e-2), so by about 1e-5 of their
    standard errors (up to 7e-6 seen; 1e-4 allowed)."""
    rec = anchor_record(31, noise=0.1, tones=False, duration_s=400.0)
    double = rec.signals + 5 * rec.signals.std(axis=1, keepdims=True)
    single = double.astype(np.float32)
    a = _oma(double, rec.sample_rate_hz, band_hz=(1.0, 30.0))
    b = _oma(single, rec.sample_rate_hz, band_hz=(1.0, 30.0))
    assert len(a) == len(b) == 6
    for x, y in zip(a, b):
        assert abs(x.natural_frequency_hz - y.natural_frequency_hz) < 1e-4 * x.std.natural_frequency_hz
        assert abs(x.damping_ratio - y.damping_ratio) < 1e-4 * x.std.damping_ratio
        assert np.isclose(x.std.natural_frequency_hz, y.std.natural_frequency_hz, rtol=1e-4)
        assert shape_mac(x.mode_shape, y.mode_shape) > 1 - 1e-9


def test_runs_with_one_blas_thread_and_gives_the_callers_setting_back(monkeypatch):
    """modal.oma's many small products are slower with a BLAS thread per core (modal/blas.py): it limits the BLAS
    to one thread for the call, whatever the caller set, and the caller's setting holds again after it."""
    from threadpoolctl import threadpool_info, threadpool_limits

    import modal.operational.identify as identify

    seen = []
    real = identify.correlations

    def spy(*args, **kwargs):
        seen.append({lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"})
        return real(*args, **kwargs)

    monkeypatch.setattr(identify, "correlations", spy)
    rec = ambient_modal_response([3.1, 11.2, 20.0], [0.015, 0.01, 0.02], np.eye(3)[:, :3] + 0.3, 100.0, 60_000,
                                 noise=0.1, seed=2)
    with threadpool_limits(2, user_api="blas"):
        _oma(rec.signals, 100.0, band_hz=(1, 30))
        after = {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    assert seen and all(threads == {1} for threads in seen)
    assert after == {2}


@pytest.mark.parametrize("method", ["ssi", "plscf"])
def test_modes_do_not_depend_on_the_number_of_threads(method):
    """A long record's blocks and channels are shared among threads (modal/parallel.py), each share computed as
    one loop computes it: the same modes and errors, bit for bit."""
    rec = anchor_record(32, noise=0.1, tones=False, duration_s=150.0)
    one = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0), method=method, workers=1)
    two = _oma(rec.signals, rec.sample_rate_hz, band_hz=(1.0, 30.0), method=method, workers=2)
    assert len(one) == len(two) >= 4
    for x, y in zip(one, two):
        assert (x.natural_frequency_hz, x.damping_ratio, x.std.natural_frequency_hz, x.std.damping_ratio) == \
            (y.natural_frequency_hz, y.damping_ratio, y.std.natural_frequency_hz, y.std.damping_ratio)
        assert np.array_equal(x.mode_shape, y.mode_shape)
