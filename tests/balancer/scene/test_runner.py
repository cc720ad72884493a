"""The scene runner (balancer.scene.runner): only needed stages run, unchanged stages are reused, archives
round-trip and their writers survive SIGKILL."""

import os
import signal

import time

import numpy as np
import pytest

from balancer import read_archive, run_scene
from balancer.adb import stable_speed_intervals
from balancer.scene import STAGES
from balancer.scene.schema import parse_scene

from modal import FRF
from support.scenes import SYNTH_FRF, ROTOR, ADB, COMPRESSOR, scene


def full_scene(tmp_path):
    return scene(frf=SYNTH_FRF, identify={"method": "nls"}, rotor=ROTOR, adb=ADB, compressor=COMPRESSOR,
                 outputs={"tables": ["identify", "adb_stability", "compressor"], "archive": True})


def test_compressor_only_runs_no_identification_or_balancer(tmp_path):
    run = run_scene(scene(compressor=COMPRESSOR, frf=SYNTH_FRF, rotor=ROTOR, adb=ADB,
                          outputs={"tables": ["compressor"]}))
    assert run.stages["compressor"] == "ran"
    assert {s for s, v in run.stages.items() if v != "skipped"} == {"compressor"}
    assert abs(run.results["compressor"].optimum.max_force_n - 109.522005) < 1e-4


def test_identification_only_runs_no_balancer_stage(tmp_path):
    run = run_scene(scene(frf=SYNTH_FRF, identify={}, rotor=ROTOR, adb=ADB, compressor=COMPRESSOR,
                          outputs={"tables": ["identify"]}))
    assert {s for s, v in run.stages.items() if v == "ran"} == {"frf", "identify"}
    assert set(run.stages) == set(STAGES)


def test_reuse_and_exact_downstream_rerun(tmp_path):
    config = full_scene(tmp_path)
    first = run_scene(config, out=tmp_path / "a.h5")
    ran = {s for s, v in first.stages.items() if v == "ran"}
    assert ran == {"frf", "identify", "rotor", "adb_stability", "compressor"}
    # the rotor carries the identified mode 1 (accelerance, A = 0.96 1/kg at 15.6 Hz, zeta 5 %):
    # m = 1/A holds the two balls (mass_includes_balls), k = m wn^2, c = 2 zeta m wn; the
    # noise (0.2 %) leaves them within 5 of their standard errors (6e-7 per value if calibrated)
    rotor = first.results["rotor"]
    m_identified, wn = 1 / 0.96, 2 * np.pi * 15.6
    truth = {"M": m_identified - 2 * 0.02, "k": m_identified * wn**2, "c": 2 * 0.05 * m_identified * wn}
    for name, value in truth.items():
        assert abs(getattr(rotor.params, name) - value) <= 5 * getattr(rotor.std, name), (name, value)
    mode = first.results["identify"][0]
    assert (rotor.params.k, rotor.params.c) == (mode.stiffness_n_per_m, mode.damping_n_s_per_m)
    assert rotor.params.M == mode.mass_kg - 2 * 0.02
    # the summary says the balls were taken off the identified mass (its value differs from the mode's m)
    assert f"M = {mode.mass_kg:.6g} kg identified less the 2 balls" in rotor.sources[0]
    config_without = {**config, "rotor": {**config["rotor"], "mass_includes_balls": False}}
    assert "balls" not in run_scene(config_without, out=tmp_path / "w.h5").results["rotor"].sources[0]
    assert (rotor.params.m, rotor.params.n, rotor.params.R, rotor.params.D, rotor.params.e) == (0.02, 2, 0.05, 0.001, 5e-4)
    # the stage's stable interval is exactly what a direct call with those parameters gives
    direct = stable_speed_intervals(rotor.params, 3.0 * rotor.params.natural_frequency_rad_s, grid_points=400)
    stage = first.results["adb_stability"].intervals
    np.testing.assert_array_equal(stage.intervals_rad_s, direct.intervals_rad_s)
    assert stage.intervals_rad_s.shape == (1, 2) and 1.0 < stage.intervals_ratio[0, 0] < 3.0
    second = run_scene(config, out=tmp_path / "b.h5", archive=tmp_path / "a.h5")
    assert {s: v for s, v in second.stages.items() if v != "skipped"} == {s: "reused" for s in ran}
    # change the ball drag: the rotor and its stability rerun, identification and compressor do not
    config["adb"]["D"] = 0.002
    third = run_scene(config, out=tmp_path / "c.h5", archive=tmp_path / "b.h5")
    assert {s for s, v in third.stages.items() if v == "ran"} == {"rotor", "adb_stability"}
    assert {s for s, v in third.stages.items() if v == "reused"} == {"frf", "identify", "compressor"}
    assert third.results["rotor"].params.D == 0.002


def test_a_stage_rerun_on_an_estimated_frf_has_the_estimate_not_its_archived_copy(tmp_path):
    """The hammer scene run, then run again with an identification option changed and the first archive: the
    archive holds the FRF and its noise but not its noise model or record influences, and identification on the
    archived copy moved mode 3 from 310.000 to 310.006 Hz (its errors too) against the same scene run afresh. The
    FRF is estimated again whenever identification reruns, and the results equal a fresh run's."""
    from support.paths import SYNTHETIC

    config = parse_scene({**_raw(SYNTHETIC / "hammer_scene.toml"), "outputs": {"tables": ["identify"]}},
                         source=str(SYNTHETIC / "hammer_scene.toml"), folder=SYNTHETIC)
    run_scene(config, out=tmp_path / "a.h5")
    changed = _raw(SYNTHETIC / "hammer_scene.toml")
    changed["identify"]["max_modes"] = 2
    changed["outputs"] = {"tables": ["identify"]}
    changed = parse_scene(changed, source=str(SYNTHETIC / "hammer_scene.toml"), folder=SYNTHETIC)
    again = run_scene(changed, out=tmp_path / "b.h5", archive=tmp_path / "a.h5")
    assert again.stages["frf"] == "ran" and again.stages["identify"] == "ran"
    fresh = run_scene(changed, out=tmp_path / "c.h5")
    _assert_same(again.results["identify"], fresh.results["identify"])
    # an unchanged scene still reuses both
    same = run_scene(changed, out=tmp_path / "d.h5", archive=tmp_path / "b.h5")
    assert (same.stages["frf"], same.stages["identify"]) == ("reused", "reused")


def _raw(path):
    import tomllib

    return tomllib.loads(path.read_text())


def _assert_same(a, b, where="result"):
    if isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, where
        assert np.array_equal(a, b, equal_nan=True), where
    elif isinstance(a, FRF):  # equal data and metadata; `source` says where it was read from
        assert a == b, where
    elif hasattr(a, "__dataclass_fields__"):
        assert type(a) is type(b), where
        for name in a.__dataclass_fields__:
            _assert_same(getattr(a, name), getattr(b, name), f"{where}.{name}")
    elif isinstance(a, (tuple, list)):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and np.isnan(a):
        assert np.isnan(b), where
    else:
        assert a == b and type(a) is type(b), where


def test_archive_round_trip_bit_exact(tmp_path):
    run = run_scene(full_scene(tmp_path), out=tmp_path / "a.h5")
    back = read_archive(tmp_path / "a.h5")
    assert set(back.items) == {s for s, v in run.stages.items() if v == "ran"}
    for stage, result in run.results.items():
        _assert_same(result, back[stage], stage)
        assert back.inputs_hash[stage] == run.inputs_hash[stage]
    assert back.attrs["schema_version"].startswith("1.")


def _write_new(target, data, ready):
    from modal.archive import write_archive

    ready.set()
    write_archive(target, data)


def test_sigkill_during_write_never_damages_the_previous_archive(tmp_path):
    """A forked writer (modules already imported, so it starts at once) is SIGKILLed at
    random moments of a ~0.2 s write; the target must always be the old or the new archive."""
    import multiprocessing

    from modal.archive import write_archive

    fork = multiprocessing.get_context("fork")
    target = tmp_path / "a.h5"
    write_archive(target, {"big": np.arange(10.0), "label": "old"})
    old = target.read_bytes()
    rng = np.random.default_rng(0)
    data = {"big": rng.standard_normal(600_000), "label": "new"}
    outcomes = {"old": 0, "new": 0}
    for trial in range(24):
        ready = fork.Event()
        proc = fork.Process(target=_write_new, args=(target, data, ready))
        proc.start()
        assert ready.wait(10)
        time.sleep(rng.uniform(0.0, 0.25))
        os.kill(proc.pid, signal.SIGKILL)
        proc.join(10)
        archive = read_archive(target)  # always opens
        if target.read_bytes() == old:
            outcomes["old"] += 1
        else:
            assert archive["label"] == "new" and np.array_equal(archive["big"], data["big"])
            outcomes["new"] += 1
            write_archive(target, {"big": np.arange(10.0), "label": "old"})
            old = target.read_bytes()
    # the kills must have hit writes in progress, or the test proves nothing
    assert outcomes["old"] >= 5, outcomes


# ---- where the outputs go ----------------------------------------------------------------------------------------

def test_a_plots_folder_for_a_scene_listing_no_plots_draws_every_stages_figures(tmp_path):
    """--plots DIR was ignored when [outputs] listed no plots: it now draws the figures of every stage the scene runs,
    and says so; a scene none of whose stages draws says why nothing was drawn."""
    import pytest

    said = []
    run = run_scene(scene(frf=SYNTH_FRF, identify={}, rotor=ROTOR, adb=ADB, outputs={"tables": ["adb_stability"]}),
                    plots_dir=tmp_path / "plots", progress=said.append)
    drawn = sorted(p.name for p in (tmp_path / "plots").iterdir())
    assert drawn == ["adb_stability_stability.png", "identify_fit.png"]  # the synthetic FRF's own plot draws nothing
    assert sorted(os.path.basename(p) for p in run.plot_paths) == drawn
    assert any("lists none" in line and "identify" in line for line in said), said
    with pytest.warns(UserWarning, match=r"none: no plot drawn: the stages this scene runs \(rotor\) draw no figure"):
        quiet = run_scene(scene(rotor={"M": 1.0, "k": 1e4, "c": 1.0, "e": 1e-4}, adb=ADB, outputs={"tables": ["rotor"]}),
                          plots_dir=tmp_path / "none")
    assert quiet.plot_paths == () and not (tmp_path / "none").exists()


def test_a_missing_output_folder_is_reported_before_any_work(tmp_path, monkeypatch):
    import pytest

    from modal.errors import ArchiveError, PlotError, SceneError

    said = []
    config = full_scene(tmp_path)
    with pytest.raises(ArchiveError, match="the folder .*missing does not exist; expected an existing folder"):
        run_scene(config, out=tmp_path / "missing" / "a.h5", progress=said.append)
    (tmp_path / "a_file").write_text("")
    with pytest.raises(ArchiveError, match="a_file is not a folder"):
        run_scene(config, out=tmp_path / "a_file" / "a.h5", progress=said.append)
    with pytest.raises(PlotError, match="the folder .*missing does not exist"):
        run_scene({**config, "outputs": {"plots": ["identify"]}}, out=tmp_path / "a.h5",
                  plots_dir=tmp_path / "missing" / "plots", progress=said.append)
    assert said == [] and not (tmp_path / "missing").exists()  # no stage ran
    # nothing is made before the work: a scene that fails leaves no default out/ behind
    monkeypatch.chdir(tmp_path)
    broken = {**config, "frf": {"file": "no_such.csv"}}
    with pytest.raises(SceneError, match="no_such.csv"):
        run_scene(broken, progress=said.append)
    assert not (tmp_path / "out").exists()
    # the plots' own folder is made inside an existing one, and the default out/ is made
    run = run_scene({**config, "outputs": {"plots": ["identify"], "archive": True}}, plots_dir=tmp_path / "plots")
    assert (tmp_path / "plots" / "identify_fit.png").exists() and run.archive_path == os.path.join("out", "scene.h5")
    assert (tmp_path / "out" / "scene.h5").is_file()


def test_a_stages_warnings_are_kept_in_the_run_the_summary_and_the_archive(tmp_path):
    """A rotor whose given mass (1.5 kg) with the test's stiffness puts its natural frequency 18 % below the
    measured mode warns (tests/balancer/scene/test_stages.py). The warning is shown as it comes and kept: in the
    run's ``warnings`` by stage, counted on the stage's line of the summary and repeated after the tables (the
    numbers above stand on it), archived with the stage and given back when the stage is reused."""
    import warnings

    from modal.archive import read_warnings
    from modal.errors import ModalWarning

    import h5py

    config = scene(frf=SYNTH_FRF, rotor={**ROTOR, "M": 1.5}, adb=ADB, outputs={"tables": ["rotor"], "archive": True})
    with pytest.warns(ModalWarning, match="key 'rotor.M': the rotor's natural frequency"):
        first = run_scene(config, out=tmp_path / "a.h5")
    assert set(first.warnings) == {"rotor"} and len(first.warnings["rotor"]) == 1
    said = first.warnings["rotor"][0]
    assert "key 'rotor.M': the rotor's natural frequency" in said
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # what a script that silences warnings shows; the record keeps them
        assert run_scene(config, out=tmp_path / "quiet.h5").warnings == first.warnings
    lines = first.summary.splitlines()
    assert any(line.split()[:2] == ["rotor", "ran"] and line.endswith(", 1 warning") for line in lines)
    assert lines[lines.index("warnings:") + 1] == f"  [rotor] {said}"
    with h5py.File(tmp_path / "a.h5", "r") as f:
        assert read_warnings(f["rotor"]) == (said,) and read_warnings(f["identify"]) == ()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # reused: not computed again, so not warned again
        second = run_scene(config, out=tmp_path / "b.h5", archive=tmp_path / "a.h5")
    assert second.stages["rotor"] == "reused" and second.warnings == {"rotor": (said,)}
    with h5py.File(tmp_path / "b.h5", "r") as f:
        assert read_warnings(f["rotor"]) == (said,)
    clean = run_scene(scene(frf=SYNTH_FRF, rotor={**ROTOR, "M": 1.0}, adb=ADB, outputs={"tables": ["rotor"]}))
    assert clean.warnings == {} and "warnings:" not in clean.summary.splitlines()
