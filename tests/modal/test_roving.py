"""Roving-hammer time files fitted in one command (modal.roving): each hit point estimated, the FRFs joined."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from modal.errors import FormatError
from modal.fitting import FitOptions, fit_path
import modal
from modal.roving import CORRELATION_TOLERANCE, RovingEstimate, _response_part, join_estimates
from modal.synthetic_time import random_record
from modal.time_frf import frf_from_time
from support.cli import run_module
from support.paths import ROOT

from support.roving import hits as _hits, plant as _plant, roving_files, write as _write


@pytest.fixture(scope="module")
def roving(tmp_path_factory):
    """A roving-hammer test: the hammer at points 1, 2 and 3, the accelerometer at point 1, one file per point."""
    return roving_files(tmp_path_factory.mktemp("roving"))


def _options(**given):
    values = dict(excitation=None, response=None, impact=True, estimator=None, window=None, exponential_decay_s=None,
                  segment_length=None, overlap=None, kind=None)
    values.update(given)
    return SimpleNamespace(**values)


def run(*args):
    env = {**os.environ, "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "modal", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120)


def test_a_roving_hammer_test_is_fitted_in_one_command(roving):
    out = run("fit", *roving, "--impact", "--json")
    assert out.returncode == 0, out.stderr
    rows = json.loads(out.stdout)["modes"]
    truth = _plant(0)
    # the shapes over the hit points: by reciprocity, the constants of the force at point j and the response at
    # point 1 are those of the force at 1 and the response at j
    shapes = np.array([_plant(j).modal_constant[0] for j in range(3)])  # (points, modes)
    for m, (fn, zeta) in enumerate(zip(truth.natural_frequency_hz, truth.damping_ratio)):
        number = min({r["mode"] for r in rows}, key=lambda k: abs(
            next(r for r in rows if r["mode"] == k)["natural_frequency_hz"] - fn))
        mode = sorted((r for r in rows if r["mode"] == number), key=lambda r: r["channel"])
        assert len(mode) == 3
        # the errors are the fit's one-sigma values; 4 sigma leaves a chance of 6e-5 per value
        assert abs(mode[0]["natural_frequency_hz"] - fn) <= 4 * mode[0]["std"]["natural_frequency_hz"]
        assert abs(mode[0]["damping_ratio"] - zeta) <= 4 * mode[0]["std"]["damping_ratio"]
        fitted = np.array([complex(r["modal_constant"]["re"], r["modal_constant"]["im"])
                           if isinstance(r["modal_constant"], dict) else complex(*r["modal_constant"]) for r in mode])
        mac = abs(np.vdot(fitted, shapes[:, m])) ** 2 / (np.vdot(fitted, fitted).real * np.vdot(shapes[:, m],
                                                                                                 shapes[:, m]).real)
        assert mac >= 0.98
    # k, c, m only at the driving point (hammer and accelerometer both at point 1)
    assert [r["driving_point"] for r in rows if r["mode"] == 1] == [True, False, False]


def test_the_results_say_what_the_points_estimates_share(roving):
    fitted = fit_path(roving, FitOptions(method="nls", impact=True))
    frf = fitted.frf
    assert isinstance(frf, RovingEstimate) and frf.n_channels == 3 and fitted.time_data[0] is None
    assert frf.reference_points == ("1+Z", "2+Z", "3+Z") and frf.response_points == ("1+Z",) * 3
    note = fitted.results[0].settings["roving_hammer"]
    assert f"3 hit points 1+Z ({roving[0]}), 2+Z ({roving[1]}), 3+Z ({roving[2]})" in note
    # each channel is its own file's estimate, noise and coherence with it
    for k, path in enumerate(roving):
        alone = frf_from_time(path, _options())[0]
        np.testing.assert_array_equal(frf.channels[k], alone.response)
        np.testing.assert_array_equal(np.atleast_2d(frf.noise_std)[k], alone.noise_std)
        np.testing.assert_array_equal(frf.coherence[k], alone.coherence)


def test_a_point_hit_in_two_files_is_averaged_as_takes_of_that_point(roving, tmp_path):
    again = _write(tmp_path / "p1b.csv", _hits(0, seed=99))
    notes = []
    frf = frf_from_time([roving[0], roving[1], again], _options(), notes.append)[0]
    assert frf.n_channels == 2 and frf.reference_points == ("1+Z", "2+Z")
    assert frf.point_sources == (("1+Z", (str(roving[0]), str(again))), ("2+Z", (str(roving[1]),)))
    assert f"{roving[0]}, {again}: all hit at 1+Z: averaged as takes of that point" in notes
    takes = frf_from_time([roving[0], again], _options())[0]  # the two files alone: takes of one test
    assert takes.averages == 6
    np.testing.assert_array_equal(frf.channels[0], takes.response)


def test_points_whose_hits_give_other_record_lengths_are_cut_alike(roving, tmp_path):
    # hits 3 s apart at point 2 give shorter hit records by default than those 6 s apart elsewhere
    close = _write(tmp_path / "p2.csv", _hits(1, seed=11, hits=[0.5, 3.5, 6.5, 9.5], duration=12.0))
    notes = []
    frf = frf_from_time([roving[0], close], _options(), notes.append)[0]
    alone = [frf_from_time(p, _options())[0].segment_length for p in (roving[0], close)]
    assert alone[0] > alone[1] and frf.segment_length == alone[1]
    assert any(f"hit records of {alone[1]} samples at every point" in n for n in notes)


@pytest.mark.parametrize("change, fragment", [
    ({"response": "2+Z"}, "response channel 2 (names) is '2+Z' where {first} has '1+Z'; expected the same "
                          "accelerometers"),
    ({"rate": 2048.0}, "sample rate 2048 Hz where {first} has 1024 Hz; expected one rate"),
])
def test_files_that_are_not_one_roving_test_are_refused_on_one_line(roving, tmp_path, change, fragment):
    other = _write(tmp_path / "p2.csv", _hits(1, seed=3, **change))
    out = run_module("modal", "fit", roving[0], other, "--impact", cwd=ROOT)  # in-process: the first test runs it
    assert out.returncode == 1 and out.stderr.count("\n") == 1, out.stderr
    assert out.stderr.startswith(f"error: {other}: ") and fragment.format(first=roving[0]) in out.stderr


def _estimate(point, window="force", decay=None, seed=0):
    record = replace(_hits(point, seed=seed), source=f"p{point + 1}.csv")
    return frf_from_time_record(record, _options(window=window, exponential_decay_s=decay))


def frf_from_time_record(record, args):
    from modal.time_frf import estimate_time_frf, plan_time_frf

    return estimate_time_frf(record, plan_time_frf(record, args), args)


def test_the_points_response_noise_correlation_is_kept_and_their_force_noise_carried_apart():
    # an exponential window correlates neighbouring lines; each point's estimate mixes its response noise's
    # correlation with its own force noise's, in proportion to its own |H|. The response noise's part is one
    # for every point (one window, alike hits): the join keeps it, and carries each point's force noise as its
    # channel's own factor, independent of the other point's
    first, second = _estimate(0, "exponential", 0.5), _estimate(1, "exponential", 0.5, seed=1)
    mixed = [e.noise_model.line_correlation for e in (first, second)]
    assert np.max(np.abs(mixed[0] - mixed[1])) > CORRELATION_TOLERANCE  # as mixed, the points' differ
    joined = join_estimates([first, second], [("1+Z", ["p1.csv"]), ("2+Z", ["p2.csv"])])
    model = joined.noise_model
    assert model.line_correlation is not None and "line correlations differ" not in joined.join_note
    parts = [_response_part(e.noise_model, np.atleast_2d(e.response)) for e in (first, second)]
    np.testing.assert_allclose(model.line_correlation, (parts[0][1] + parts[1][1]) / 2)
    np.testing.assert_allclose(model.variance_model, (parts[0][0] + parts[1][0]) / 2)
    # each channel's factor in its own block: channel 1 the first point's, channel 2 the second's
    own = [e.noise_model.relative_error.factor() for e in (first, second)]
    factor = model.relative_error.factor()
    rows = own[0].shape[0]
    assert factor.shape == (2, rows + own[1].shape[0], first.n_freq)
    np.testing.assert_array_equal(factor[0, :rows], own[0])
    np.testing.assert_array_equal(factor[1, rows:], own[1])
    assert not np.any(factor[0, rows:]) and not np.any(factor[1, :rows])
    assert joined.exponential_decay_s == 0.5 and model.averages == 3
    # without the force noise carried apart, the mixed correlations differ: dropped, and said
    bare = [replace(e, noise_model=replace(e.noise_model, relative_error=None)) for e in (first, second)]
    dropped = join_estimates(bare, [("1+Z", ["p1.csv"]), ("2+Z", ["p2.csv"])])
    assert dropped.noise_model.line_correlation is None and "line correlations differ" in dropped.join_note
    # the same estimate twice: one correlation, kept, as are the lag window and the variance model
    same = join_estimates([bare[0], replace(bare[0], reference_points=("2+Z",))],
                          [("1+Z", ["p1.csv"]), ("2+Z", ["p2.csv"])])
    np.testing.assert_array_equal(same.noise_model.line_correlation, first.noise_model.line_correlation)
    np.testing.assert_array_equal(same.noise_model.lag_window, first.noise_model.lag_window)
    np.testing.assert_array_equal(same.noise_model.variance_model, first.noise_model.variance_model)
    assert "differ" not in same.join_note


def test_a_single_output_estimates_response_noise_part_is_what_two_outputs_carry():
    # one output's noise model mixes response and force noise; an estimate of the same record with the output
    # twice carries the response noise's part alone (its force noise is the factor): the part taken out of the
    # mixed model is that, to rounding, where the mixed model holds
    record = _hits(0, seed=4)
    force, response = record.signals[0], record.signals[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        one, two = (modal.estimate_frf(force, outputs, record.sample_rate_hz, impact=True, window="exponential",
                                       exponential_decay_s=0.5, kind="accelerance")
                    for outputs in (response, np.vstack([response, response])))
    variance, correlation = _response_part(one.noise_model, np.atleast_2d(one.response))
    held = np.isfinite(variance)
    assert held.sum() > 100
    np.testing.assert_allclose(variance[held], two.noise_model.variance_model[held], rtol=1e-6)
    lines = np.flatnonzero(held)[:-64]
    np.testing.assert_allclose(correlation[:, lines], two.noise_model.line_correlation[:, lines], atol=1e-6)


def test_lag_windows_that_differ_are_dropped_and_close_ones_averaged():
    first, second = _estimate(0), _estimate(1, seed=1)
    lags = [e.noise_model.lag_window for e in (first, second)]
    joined = join_estimates([first, second], [("1+Z", ["a"]), ("2+Z", ["b"])])
    assert np.max(np.abs(lags[0] - lags[1])) < 0.01  # hits alike: one window within its tolerance
    np.testing.assert_allclose(joined.noise_model.lag_window, (lags[0] + lags[1]) / 2)
    shorter = replace(second, noise_model=replace(second.noise_model, lag_window=lags[1] * 0.9))
    dropped = join_estimates([first, shorter], [("1+Z", ["a"]), ("2+Z", ["b"])])
    assert dropped.noise_model.lag_window is None and "lag windows differ (by up to 0.1" in dropped.join_note


def test_records_influences_of_single_channels_are_not_carried_into_the_joint_fit():
    # a shaker moved between two points: each continuous estimate keeps its records' influences, which describe
    # its own channel's errors only
    estimates = []
    for point in (0, 1):
        record = replace(random_record(_plant(point), 40.0, seed=point, response_noise=1e-3,
                                       names=[f"{point + 1}+Z", "1+Z"]).record, source=f"s{point + 1}.csv")
        estimates.append(frf_from_time_record(record, _options(impact=False)))
    assert all(e.noise_model.record_influence is not None for e in estimates)
    joined = join_estimates(estimates, [("1+Z", ["s1.csv"]), ("2+Z", ["s2.csv"])])
    assert joined.noise_model.record_influence is None and "records' influences" in joined.join_note


def test_estimates_on_other_axes_or_windows_are_refused():
    first = _estimate(0)
    other = _estimate(1, "exponential", 0.5)
    with pytest.raises(FormatError, match="p2.csv: exponential window 0.5 s where p1.csv has None s"):
        join_estimates([first, other], [("1+Z", ["p1.csv"]), ("2+Z", ["p2.csv"])])
    cut = first.cropped(0.0, 200.0)
    with pytest.raises(FormatError, match="p2.csv: .* lines up to 200 Hz where p1.csv has .*expected one frequency"):
        join_estimates([first, cut], [("1+Z", ["p1.csv"]), ("2+Z", ["p2.csv"])])


def test_a_point_labelled_twice_is_averaged_as_takes_and_the_disagreement_said(roving, tmp_path):
    # p3.csv saved with its force channel named 2+Z by mistake: it becomes a take of point 2, whose two files then
    # hold two FRFs; the command says so instead of printing their average as point 2's shape entry
    text = roving[2].read_text().splitlines()
    mislabelled = tmp_path / "p3.csv"
    mislabelled.write_text("\n".join([text[0].replace("3+Z [N]", "2+Z [N]")] + text[1:]) + "\n")
    out = run_module("modal", "fit", roving[0], roving[1], mislabelled, "--impact", cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert f"{roving[1]}, {mislabelled}: all hit at 2+Z: averaged as takes of that point" in out.stderr
    warning = [ln for ln in out.stderr.splitlines() if "the takes' FRFs differ beyond their noise" in ln]
    assert len(warning) == 1 and f"({roving[1]}, {mislabelled}:" in warning[0]
