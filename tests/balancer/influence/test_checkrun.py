"""The check run after a correction (balancer.influence.checkrun): agreement within the readings' noise,
the mounting mistakes named, the trim."""
import json
import subprocess
import sys
import warnings

import h5py
import numpy as np
import pytest

import balancer
from balancer.influence import correction, influence_matrix
from balancer.influence.checkrun import CAUSES, check_run
from balancer.influence.job import balance, load_job
from balancer.influence.readings import amplitude_phase
from modal.errors import ParameterError, QualityWarning
from support.balancing import READINGS, inline_scene
from support.cli import run_module
from support.paths import ROOT


def _noisy(values, noise, rng):
    return values * (1 + noise * (rng.standard_normal(values.shape) + 1j * rng.standard_normal(values.shape)) / np.sqrt(2))


def _job(rng, n_readings, n_planes, noise, trial_effect):
    """A random linear rotor (alpha, unbalance) measured with relative reading noise; trials sized so the largest
    reading changes by ``trial_effect`` of the largest initial reading, at random angles."""
    alpha = rng.standard_normal((n_readings, n_planes)) + 1j * rng.standard_normal((n_readings, n_planes))
    unbalance = rng.standard_normal(n_planes) + 1j * rng.standard_normal(n_planes)
    clean = alpha @ unbalance
    trials = np.exp(2j * np.pi * rng.random(n_planes)) * trial_effect * np.abs(clean).max() / np.abs(alpha).max(axis=0)
    initial = _noisy(clean, noise, rng)
    runs = np.array([_noisy(alpha @ (unbalance + trials[j] * np.eye(n_planes)[j]), noise, rng) for j in range(n_planes)])
    return alpha, unbalance, trials, initial, runs


def _measured(initial, runs, trials):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)
        a = influence_matrix(initial, runs, trials)
        return a, correction(a, initial).unbalance_kg_m


def _check(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)
        return check_run(*args, **kwargs)


@pytest.mark.parametrize("n_readings, n_planes", [(3, 1), (4, 2)])
def test_a_correction_mounted_as_computed_rarely_disagrees(n_readings, n_planes):
    """Reading noise 5 % (the default assumed), trials moving the readings by 20 %: the limit is the bootstrap's
    99th percentile, so about 1 % of check runs exceed it (measured 0.3-2 % over 300 jobs per case, the plug-in
    bootstrap's own error). 10 or more of 200 has probability < 1 % at a 2 % rate: a limit that ignored the
    trial runs' errors in alpha (the miss is then 2-5x the after run's own noise) fails by far."""
    rng = np.random.default_rng(7)
    flagged = 0
    for _ in range(200):
        alpha, unbalance, trials, initial, runs = _job(rng, n_readings, n_planes, 0.05, 0.2)
        a, u = _measured(initial, runs, trials)
        after = _noisy(alpha @ (unbalance + u), 0.05, rng)
        flagged += not _check(a, initial, runs, trials, u, after).agrees
    assert flagged < 10


@pytest.mark.parametrize("mistake", ["mirrored_angles", "added_where_removed", "trial_left_on", "planes_swapped"])
def test_each_mounting_mistake_is_named(mistake):
    """Two planes, four readings, 2 % reading noise, trials moving the readings by 50 %, every mass mounted with the
    mistake (mirrored angles: the trials too, as a wrong convention would place them). Each mistake is named in most
    jobs (a mirrored correction whose angles lie near 0 or 180 deg, or a trial left on whose effect is within the
    noise, is harmless and not flagged); where another mistake fits the readings as well (a mirrored correction
    90 deg from its trials is also a reversed one) both are named, and a mistake that was not made is never named
    alone."""
    rng = np.random.default_rng(11)
    named, wrong = 0, 0
    for _ in range(60):
        alpha, unbalance, trials, initial, runs_true = _job(rng, 4, 2, 0.02, 0.5)
        if mistake == "mirrored_angles":  # trials mounted at the mirrored angles too
            runs_true = np.array([_noisy(alpha @ (unbalance + np.conj(trials[j]) * np.eye(2)[j]), 0.02, rng)
                                  for j in range(2)])
        a, u = _measured(initial, runs_true, trials)
        mounted = {"mirrored_angles": np.conj(u), "added_where_removed": -u, "planes_swapped": u[::-1],
                   "trial_left_on": u + trials * np.eye(2)[1]}[mistake]
        result = _check(a, initial, runs_true, trials, u, _noisy(alpha @ (unbalance + mounted), 0.02, rng))
        named += mistake in (result.cause,) + result.other_causes
        wrong += bool(result.cause) and mistake not in (result.cause,) + result.other_causes
        if result.cause == "trial_left_on":
            assert result.cause_plane == 2
        if result.cause:
            assert result.flags == ("check_run_disagrees",) and result.trim_kg_m.size == 0
    assert wrong == 0
    # named in 97 % (mirrored), 100 % (removed), 96 % (swapped, trial left on) of 300 such jobs; the bound is the
    # 0.1 % binomial quantile of 60 jobs at 93 %. With trials moving the readings by 30 % a trial left on changes
    # the check run by about what the trial runs' errors allow and is named in only 16 %.
    assert named >= 49


def test_an_unexplained_miss_updates_alpha_and_the_trim_balances_the_machine():
    """One plane whose influence changed between the trial and the check run (a speed or a support that moved):
    the true alpha is 1.6 times the measured one, 50 deg further. No mounting mistake explains the check run, so
    the trim uses alpha updated by it; for one plane the update makes alpha the true one, so the trim leaves the
    reading noise only (2 %), where the trim from the old alpha leaves about half the check run."""
    rng = np.random.default_rng(3)
    alpha, unbalance, trials, initial, runs = _job(rng, 3, 1, 0.0, 0.3)
    a, u = _measured(initial, runs, trials)
    true_alpha = alpha * 1.6 * np.exp(0.87j)
    after = _noisy(initial + true_alpha @ u, 0.02, rng)
    with pytest.warns(QualityWarning, match="no mounting mistake explains it"):
        result = check_run(a, initial, runs, trials, u, after)
    assert not result.agrees and result.cause == "" and result.alpha_updated
    left = np.abs(after + true_alpha @ result.trim_kg_m)
    old_trim = correction(a, after).unbalance_kg_m
    left_old = np.abs(after + true_alpha @ old_trim)
    assert left.max() < 0.05 * np.abs(after).max() < left_old.max()


def _with_after(tmp_path, after, digits=1):
    """The bundled job with the check run ``after`` (SI readings) as a readings file."""
    amplitude, phase = amplitude_phase(after, "um")
    path = tmp_path / "job.toml"
    path.write_text(READINGS.read_text() + f"\n[after]\namplitude = {[round(float(v), digits) for v in amplitude]}\n"
                    f"phase_deg = {[round(float(v), digits) for v in phase]}\n")
    return path


def test_the_bundled_job_judged_by_its_check_run(tmp_path):
    """A check run at the prediction plus 0.2 % of the initial readings agrees (no flag, no warning); one 30 %
    away (far outside 5 % reading noise, which allows about 21 % here) disagrees and is flagged."""
    job = load_job(READINGS)
    report = balance(job, "minmax")
    with warnings.catch_warnings():
        warnings.simplefilter("error", QualityWarning)
        near = balance(load_job(_with_after(tmp_path, report.residual + 0.002 * job.initial, 3)), "minmax")
    assert near.check.agrees and near.flags == () and near.check.discrepancy < near.check.discrepancy_limit
    with pytest.warns(QualityWarning, match="disagrees"):
        far = balance(load_job(_with_after(tmp_path, report.residual + 0.3 * job.initial)), "minmax")
    assert far.flags == ("check_run_disagrees",) and not far.check.agrees


def _after_file(tmp_path, mounted):
    """The bundled job with a check run of the masses ``mounted(report)`` (kg m per plane) on its own alpha."""
    job = load_job(READINGS)
    report = balance(job, "minmax")
    return _with_after(tmp_path, job.initial + report.alpha @ mounted(report))


def test_cli_shows_the_check_run_and_names_the_mistake(tmp_path):
    """`balancer influence` with a check run of the correction removed instead of added: the table has the measured
    column, the verdict names the mistake, the flag is listed, no trim is offered; --json carries the same."""
    path = _after_file(tmp_path, lambda r: -r.correction_kg_m)
    cmd = [sys.executable, "-m", "balancer", "influence", str(path), "--method", "minmax"]
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "measured after" in out.stdout and "flags: check_run_disagrees" in out.stdout
    assert CAUSES["added_where_removed"] in out.stdout and "trim (add)" not in out.stdout
    assert "warning:" in out.stderr
    doc = json.loads(run_module(*cmd[2:], "--json", cwd=ROOT).stdout)  # the same main, in this process
    check = doc["check_run"]
    assert check["cause"] == "added_where_removed" and check["agrees"] is False and check["trim"] == []
    assert check["discrepancy"] > check["discrepancy_limit"]
    assert all("measured_amplitude" in row for row in doc["readings"])


def test_cli_refuses_a_reading_noise_meant_as_percent(tmp_path):
    """--reading-noise is a fraction (0.05 for 5 %); 5 (meant as percent) is refused in one line."""
    path = _after_file(tmp_path, lambda r: r.correction_kg_m)
    out = run_module("balancer", "influence", path, "--reading-noise", 5, cwd=ROOT)
    assert out.returncode == 1 and out.stdout == ""
    assert out.stderr.startswith("error: reading_noise = 5") and len(out.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("value", [0, -0.1, 1.5, float("nan"), True])
def test_a_reading_noise_outside_0_1_is_refused_with_or_without_a_check_run(value):
    """The option is checked even when the job has no check run to judge (a typo is still a typo)."""
    job = load_job(READINGS)
    with pytest.raises(ParameterError, match="reading_noise"):
        balance(job, reading_noise=value)


def test_reading_noise_sets_the_limit():
    """The limit scales with the noise assumed: 1 % noise gives a limit about 5 times tighter than 5 %."""
    job = load_job(READINGS)
    report = balance(job, "least_squares")
    args = (report.alpha, job.initial, job.trial_runs, job.trial_unbalance_kg_m, report.correction_kg_m, report.residual)
    tight, loose = check_run(*args, reading_noise=0.01), check_run(*args, reading_noise=0.05)
    assert 3 < loose.discrepancy_limit / tight.discrepancy_limit < 7


def test_scene_reports_and_archives_the_check_run(tmp_path):
    """A scene's [balance] with [after]: the summary shows the check run, the archive holds it with units."""
    job = load_job(READINGS)
    report = balance(job, "minmax")
    amplitude, phase = amplitude_phase(job.initial - report.alpha @ report.correction_kg_m, "um")
    scene = inline_scene(tmp_path, after={"amplitude": [round(float(v), 1) for v in amplitude],
                                          "phase_deg": [round(float(v)) for v in phase]})
    with pytest.warns(QualityWarning, match="removed where it should be added"):
        run = balancer.run_scene(scene, out=tmp_path / "b.h5")
    assert "check run:" in run.summary and "check_run_disagrees" in run.summary
    check = balancer.read_archive(tmp_path / "b.h5")["balance"].report.check
    assert check.cause == "added_where_removed"
    with h5py.File(tmp_path / "b.h5") as f:
        group = f["balance/report/check"]
        assert group["measured"].attrs["units"] == "m" and group["discrepancy"].attrs["units"] == "1"


def test_the_correction_spread_is_what_repeating_the_job_gives():
    """One job's bootstrap (its readings taken for the truth, redrawn at the reading noise) against the truth:
    the same machine balanced 200 times with fresh 5 % reading errors (4 readings, 2 planes, trials moving the
    readings by 30 %). The reported standard deviations of mass and angle and the 90th percentile of the worst
    reading left are within 0.7-1.4 of the repeats' (measured 0.81-1.17 over three such cells: the plug-in's own
    error, second order in noise / trial effect; the repeats' SD rests on 200 draws, ±5 %). A spread that ignored
    the trial runs' errors (the initial readings' alone) gives 0.22 of the mass spread and fails."""
    from balancer.influence.bootstrap import correction_spread

    rng = np.random.default_rng(5)
    alpha, unbalance, trials, _, _ = _job(rng, 4, 2, 0.05, 0.3)
    corrections, left, reported = [], [], []
    for i in range(200):
        initial = _noisy(alpha @ unbalance, 0.05, rng)
        runs = np.array([_noisy(alpha @ (unbalance + trials[j] * np.eye(2)[j]), 0.05, rng) for j in range(2)])
        u = _measured(initial, runs, trials)[1]
        corrections.append(u)
        left.append(np.abs(alpha @ (unbalance + u)).max())
        if i < 20:
            reported.append(correction_spread(initial, runs, trials, np.ones(2), 0.05))
    corrections = np.array(corrections)
    angle = np.rad2deg(np.angle(corrections / corrections.mean(axis=0)))
    truth = {"mass": np.std(np.abs(corrections), axis=0), "angle": np.sqrt(np.mean(angle ** 2, axis=0)),
             "left": np.quantile(left, 0.9)}
    ratios = {"mass": np.median([s.mass_std_kg for s in reported], axis=0) / truth["mass"],
              "angle": np.median([s.angle_std_deg for s in reported], axis=0) / truth["angle"],
              "left": np.median([s.worst_residual_p90 for s in reported]) / truth["left"]}
    for name, ratio in ratios.items():
        assert np.all((0.7 < np.asarray(ratio)) & (np.asarray(ratio) < 1.4)), (name, ratio)


def test_every_output_says_how_far_the_readings_let_the_prediction_be_trusted(tmp_path):
    """The bundled job predicts 0.337 µm left; its readings (5 % noise) allow several µm: the text, JSON and scene
    summary say so, and the archive keeps it with units."""
    report = balance(load_job(READINGS), "minmax")
    assert report.spread.worst_residual_p90 > 5 * report.worst_residual
    out = run_module("balancer", "influence", READINGS, "--json", cwd=ROOT)
    spread = json.loads(out.stdout)["spread"]
    assert spread["reading_noise"] == 0.05 and len(spread["mass_std"]) == 2
    assert spread["worst_residual_p90"] == pytest.approx(report.spread.worst_residual_p90 * 1e6, rel=1e-9)  # µm
    run = balancer.run_scene(inline_scene(tmp_path), out=tmp_path / "b.h5")
    assert "at 5 % reading noise: plane 1 ±" in run.summary
    with h5py.File(tmp_path / "b.h5") as f:
        assert f["balance/report/spread/worst_residual_p90"].attrs["units"] == "m"
        assert f["balance/report/spread/mass_std_kg"].attrs["units"] == "kg"
