"""Balancing jobs as users write them (balancer.influence.job): readings files, and the scene's [balance]."""
from __future__ import annotations

import h5py
import numpy as np
import pytest

from balancer.influence.job import balance, load_job, parse_job
from modal.errors import FormatError, ParameterError, SceneError

from support.balancing import READINGS, inline_scene


def test_bundled_readings_give_the_rotor_unbalance_back():
    """The file was made from a rotor with 3.6 g m at 60 deg and 2.4 g m at 250 deg (radius 0.15 m),
    readings rounded to 0.1 um and 1 deg: the correction is 24 g at 240 deg and 16 g at 70 deg
    to the rounding (0.5 deg of phase ~ 1 % on these vectors)."""
    report = balance(load_job(READINGS), "least_squares", holes=12)
    np.testing.assert_allclose(report.correction_mass_kg * 1e3, [24.0, 16.0], rtol=0.02)
    np.testing.assert_allclose(report.correction_angle_deg, [240.0, 70.0], atol=1.0)
    assert report.worst_residual < 0.02 * report.worst_initial
    rebuilt = report.split_mass_kg @ np.exp(1j * np.deg2rad(report.positions_deg)) * report.radius_m
    np.testing.assert_allclose(rebuilt, report.correction_kg_m, rtol=1e-12)


def test_csv_readings_equal_inline_readings(tmp_path):
    job = load_job(READINGS)
    rows = ["run,amplitude,phase_deg"]
    for name, values in [("initial", job.initial), ("trial1", job.trial_runs[0]), ("trial2", job.trial_runs[1])]:
        amplitude = np.abs(values) * 1e6
        phase = np.rad2deg(np.angle(values))
        rows += [f"{name},{float(a)!r},{float(p)!r}" for a, p in zip(amplitude, phase)]
    (tmp_path / "runs.csv").write_text("\n".join(rows) + "\n")
    config = {"units": "um", "mass_units": "g", "radius_m": 0.15, "readings": "runs.csv",
              "trial": [{"mass": 20.0, "angle_deg": 0.0}, {"mass": 20.0, "angle_deg": 0.0}]}
    from_csv = parse_job(config, "job.toml", tmp_path)
    np.testing.assert_allclose(from_csv.initial, job.initial, rtol=1e-13)
    np.testing.assert_allclose(from_csv.trial_runs, job.trial_runs, rtol=1e-13)


@pytest.mark.parametrize("csv", [False, True])
def test_phases_written_in_radians_are_warned(tmp_path, csv):
    """The bundled job's 12 phases written in radians (0.94 for 54°, ..., 4.69 for 269°): a correction at the wrong angle with no
    word before. The same job in degrees (and in a CSV file) reads silently."""
    import tomllib
    import warnings

    from modal.errors import ModalWarning

    config = tomllib.loads(READINGS.read_text())
    runs = [config["initial"], *config["trial"]]
    if csv:
        rows = ["run,amplitude,phase_deg"] + [f"{name},{a},{np.deg2rad(p):.2f}" for name, run in
                                               zip(["initial", "trial1", "trial2"], runs)
                                               for a, p in zip(run["amplitude"], run["phase_deg"])]
        (tmp_path / "runs.csv").write_text("\n".join(rows) + "\n")
        radians = {**config, "readings": "runs.csv"}
        radians.pop("initial")
        radians["trial"] = [{k: v for k, v in t.items() if k in ("mass", "angle_deg")} for t in config["trial"]]
    else:
        radians = tomllib.loads(READINGS.read_text())
        for run in [radians["initial"], *radians["trial"]]:
            run["phase_deg"] = [round(float(np.deg2rad(p)), 2) for p in run["phase_deg"]]
    with pytest.warns(ModalWarning, match=r"key 'phase_deg': all 12 phases lie within ±2π \(largest 4\.69\); "
                                          r"expected degrees"):
        parse_job(radians, "job.toml", tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModalWarning)
        parse_job(config, "job.toml", tmp_path)


@pytest.mark.parametrize("edit, key", [
    (lambda c: c.pop("units"), "units"),
    (lambda c: c["trial"][0].pop("mass"), "trial[0].mass"),
    (lambda c: c.pop("trial"), "trial"),
    (lambda c: c["trial"][1].__setitem__("amplitude", [1.0, 2.0]), "trial[1].amplitude"),
    (lambda c: c["initial"].__setitem__("phase_deg", [1.0, 2.0, float("nan"), 4.0]), "initial.phase_deg"),
    (lambda c: c.__setitem__("radius_m", [0.1, 0.2, 0.3]), "radius_m"),
    (lambda c: c.__setitem__("colour", "red"), "colour"),
    (lambda c: c["trial"][0].__setitem__("amplitude", list(c["initial"]["amplitude"])) or
     c["trial"][0].__setitem__("phase_deg", list(c["initial"]["phase_deg"])), "trial_runs[0]"),
])
def test_bad_readings_files_name_the_key(edit, key):
    import tomllib

    config = tomllib.loads(READINGS.read_text())
    edit(config)
    with pytest.raises(ParameterError) as info:
        balance(parse_job(config, "job.toml"))
    message = str(info.value)
    assert "\n" not in message and key in message, message


def test_unreadable_readings_file(tmp_path):
    with pytest.raises(FormatError, match="no such readings file"):
        load_job(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text("units = ")
    with pytest.raises(FormatError, match="bad.toml: not valid TOML"):
        load_job(tmp_path / "bad.toml")


def test_scene_balance_section_inline(tmp_path):
    import balancer

    run = balancer.run_scene(inline_scene(tmp_path), out=tmp_path / "b.h5", plots_dir=tmp_path / "plots")
    assert run.stages["balance"] == "ran"
    report = run.results["balance"].report
    assert report.method == "minmax" and report.iso is not None
    assert "[balance]" in run.summary and "ISO 21940-11 G 2.5" in run.summary
    assert (tmp_path / "plots" / "balance_polar.png").stat().st_size > 10_000
    back = balancer.read_archive(tmp_path / "b.h5")["balance"].report
    np.testing.assert_array_equal(back.correction_kg_m, report.correction_kg_m)
    with h5py.File(tmp_path / "b.h5") as f:
        missing = []
        f["balance"].visititems(lambda name, node: missing.append(name) if isinstance(node, h5py.Dataset)
                                and node.dtype.kind not in "OSU" and "units" not in node.attrs else None)
        assert missing == []  # every numeric dataset carries units
        assert f["balance/report/residual"].attrs["units"] == "m"
        assert f["balance/report/alpha"].attrs["units"] == "m/(kg m)"
    again = balancer.run_scene(inline_scene(tmp_path), out=tmp_path / "b2.h5", archive=tmp_path / "b.h5")
    assert again.stages["balance"] == "reused"


def test_scene_balance_errors_before_any_work(tmp_path):
    import balancer

    scene = inline_scene(tmp_path)
    scene["balance"]["trial"][1]["amplitude"] = [1.0, 2.0]
    with pytest.raises(SceneError, match=r"balance\.trial\[1\]\.amplitude"):
        balancer.run_scene(scene)
    scene = inline_scene(tmp_path, method="median")
    with pytest.raises(SceneError, match="balance.method"):
        balancer.run_scene(scene)


def test_scene_rounds_the_split_to_its_weight_resolution(tmp_path):
    """[balance] weight_resolution (in mass_units) rounds every mass on a hole to a multiple of it, and says so."""
    import balancer

    run = balancer.run_scene(inline_scene(tmp_path, weight_resolution=0.5), out=tmp_path / "b.h5")
    report = run.results["balance"].report
    grams = report.split_mass_kg * 1e3
    assert report.weight_resolution_kg == pytest.approx(0.5e-3)
    assert np.allclose(grams / 0.5, np.round(grams / 0.5), rtol=0, atol=1e-9) and grams.max() > 0
    assert "(to 0.5 g)" in run.summary
