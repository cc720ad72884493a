"""Scenes: only needed stages run, unchanged stages are reused, archives round-trip,
writers survive SIGKILL, and bad scenes get one clear error."""
import copy
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from balancer import read_archive, run_scene
from balancer.adb import stable_speed_intervals
from balancer.scene import STAGES
from support.scenes import DRIVE
from modal import FRF
from modal.errors import SceneError

SYNTH_FRF = {"synthetic": {"natural_frequency_hz": [15.6, 120.0], "damping_ratio": [0.05, 0.02],
                           "modal_constant": [0.96, 0.35], "kind": "accelerance", "f_min_hz": 0.0,
                           "f_max_hz": 200.0, "n_lines": 800, "noise": 0.002, "seed": 5}}
ROTOR = {"M": "identified:mode1.mass", "k": "identified:mode1.stiffness", "c": "identified:mode1.damping",
         "e": 0.0005, "mass_includes_balls": True}
ADB = {"m": 0.02, "n": 2, "R": 0.05, "D": 0.001, "stability": {"speed_max_ratio": 3.0, "grid_points": 400}}
COMPRESSOR = {"crank_radius_m": 0.0119, "rod_length_m": 0.05, "rotating_mass_kg": 0.096656,
              "reciprocating_mass_kg": 0.148344, "speed_rpm": 2950.0}


def scene(**sections):
    return copy.deepcopy(sections)


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


def test_cli_json_and_exit_codes(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(textwrap.dedent("""
        [compressor]
        crank_radius_m = 0.035
        rod_length_m = 0.140
        rotating_mass_kg = 0.55
        reciprocating_mass_kg = 1.13
        speed_rpm = 1000.0
        [outputs]
        tables = ["compressor"]
        """))
    cmd = [sys.executable, "-m", "balancer", "run", str(path), "--json", "--out", str(tmp_path / "o.h5")]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    # stdout is a pipe (block-buffered) and `run` leaves by os._exit after flushing: the whole document arrives
    doc = json.loads(out.stdout)
    assert doc["stages"] == {s: ("ran" if s == "compressor" else "skipped") for s in STAGES}
    # seed 004: 285.5 N at the optimum (crank_drive.md)
    assert abs(doc["results"]["compressor"]["max_force_n"] - 285.5) < 0.05
    path.write_text("[outputs]\ntables = ['compressor']\n")
    bad = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "s.toml" in bad.stderr
    usage = subprocess.run([sys.executable, "-m", "balancer", "run"], capture_output=True, text=True, timeout=60)
    assert usage.returncode == 2


BAD_SCENES = [
    ({"outputs": {"tables": ["compressor"]}, "compresor": {}}, "unknown key 'compresor'"),
    ({"outputs": {"tables": ["compressor"]}, "compressor": {**COMPRESSOR, "spead_rpm": 1}}, "unknown key 'compressor.spead_rpm'"),
    ({"outputs": {"tables": ["compressor"]}, "compressor": {k: v for k, v in COMPRESSOR.items() if k != "speed_rpm"}},
     "'compressor.speed_rpm' is missing"),
    ({"outputs": {"tables": ["compressor"]}, "compressor": {**COMPRESSOR, "speed_rpm": "2950 rpm"}},
     "'compressor.speed_rpm' = '2950 rpm': expected a number"),
    ({"outputs": {"tables": ["compressor"]}, "compressor": {**COMPRESSOR, "rotating_mass_kg": -1.0}}, "expected a number >= 0"),
    ({"outputs": {"tables": ["compressor"]}, "compressor": {**COMPRESSOR, "speed_rpm": True}}, "expected a number"),
    ({"outputs": {"tables": ["compresor"]}, "compressor": COMPRESSOR}, "'outputs.tables'"),
    ({"outputs": {}}, "outputs"),
    ({"compressor": COMPRESSOR}, "'outputs' is missing"),
    ({"outputs": {"tables": ["adb_stability"]}, "rotor": ROTOR}, "needs section [adb]"),
    ({"outputs": {"tables": ["adb_stability"]}, "rotor": ROTOR, "adb": ADB}, "refers to stage 'identify'"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB,
      "rotor": {**ROTOR, "k": "identified:mode1.stifness"}}, "identified field"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB, "rotor": {**ROTOR, "k": "measured:k"}},
     "reference like"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB, "rotor": {**ROTOR, "M": "drive:speed"}},
     "reference to identified"),
    ({"outputs": {"tables": ["identify"]}, "frf": {"file": "x.csv", **SYNTH_FRF}}, "both 'file' and 'synthetic'"),
    ({"outputs": {"tables": ["identify"]}, "frf": {"kind": "mobility"}}, "needs 'file'"),
    ({"outputs": {"tables": ["identify"]}, "frf": {"file": "missing.csv"}}, "missing.csv"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB, "rotor": {**ROTOR, "k": "identified:mode7.stiffness"}},
     "found 2 mode(s), expected at least 7"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "identify": {"channel": 3}, "adb": ADB, "rotor": ROTOR},
     "'identify.channel' = 3"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": {**ADB, "m": 0.0001}, "rotor": ROTOR},
     "cannot balance"),
    ({"outputs": {"tables": ["identify"]}, "frf": {"synthetic": {**SYNTH_FRF["synthetic"], "damping_ratio": [0.05]}}},
     "one per natural frequency"),
    ({"outputs": {"tables": ["mounts"]}, "compressor": COMPRESSOR}, "needs section [compressor.body]"),
]


@pytest.mark.parametrize("config, message", BAD_SCENES, ids=[m[:30] for _, m in BAD_SCENES])
def test_bad_scenes_give_one_clear_error(tmp_path, config, message):
    path = tmp_path / "bad.toml"
    import tomllib  # noqa: F401  (the dict form and the file form go through the same validation)

    with pytest.raises(SceneError) as info:
        from balancer.scene.schema import parse_scene

        run_scene(parse_scene(copy.deepcopy(config), source=str(path), folder=tmp_path), out=tmp_path / "o.h5")
    text = str(info.value)
    assert message in text, text
    assert text.startswith(str(path)) and "\n" not in text


def test_invalid_toml_and_missing_scene(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[compressor\nspeed_rpm = 1\n")
    with pytest.raises(SceneError, match="broken.toml: not valid TOML"):
        run_scene(path)
    with pytest.raises(SceneError, match="no such scene file"):
        run_scene(tmp_path / "none.toml")


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


def test_drive_hands_speed_and_stiffness_to_the_rotor():
    config = scene(drive=DRIVE, rotor={"M": 2.0, "k": "drive:stiffness", "c": 20.0, "e": 1e-4},
                   adb={**ADB, "response": {"speed_rad_s": "drive:speed", "t_end_s": 0.2}},
                   outputs={"tables": ["rotor", "drive"]})
    run = run_scene(config)
    assert {s for s, v in run.stages.items() if v == "ran"} == {"drive", "rotor"}
    handover = run.results["drive"].handover
    # docs/drive.md worked example: 775 rpm = 81.158 rad/s, overhung 25 mm shaft: k = 403.2 kN/m
    assert abs(handover.speed_rad_s - 81.158) < 1e-3
    assert abs(handover.stiffness_n_per_m / 403.2e3 - 1) < 5e-4
    assert run.results["rotor"].params.k == handover.stiffness_n_per_m
