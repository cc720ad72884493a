"""Scene files checked before any work (balancer.scene.schema): every bad scene gets one clear error."""
import copy

import pytest

from balancer import run_scene

from modal.errors import SceneError
from support.scenes import SYNTH_FRF, ROTOR, ADB, COMPRESSOR, DRIVE

#: seed 000's compressor body on its three mounts (data/synthetic/demo_scene.toml): it sags 0.85 mm
BODY = {"mass_kg": 16.3, "inertia_kg_m2": [[0.067, 0.0, -0.001], [0.0, 0.059, 0.0], [-0.001, 0.0, 0.0405]],
        "crank_centre_m": [0.005, 0.008, 0.005], "damping_ratio": 0.05}
MOUNTS = [{"position_m": position, "stiffness_n_per_m": [30500.0, 30500.0, 63000.0]}
          for position in ([0.0, 0.076, -0.056], [-0.052, -0.060, -0.056], [0.052, -0.060, -0.056])]


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
    # a reference to another quantity would be read in the wrong unit (a stiffness of 1e4 N/m as a 1e4 kg rotor)
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB,
      "rotor": {**ROTOR, "M": "identified:mode1.stiffness"}}, "'rotor.M' = 'identified:mode1.stiffness': expected a mass"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB,
      "rotor": {**ROTOR, "c": "identified:mode1.mass"}}, "expected a damping"),
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB, "rotor": {**ROTOR, "k": "drive:speed"}},
     "expected a stiffness: a number or \"identified:modeN.stiffness\" or \"drive:stiffness\""),
    ({"outputs": {"tables": ["mounts"]}, "frf": SYNTH_FRF, "compressor": {**COMPRESSOR, "mounts": [
        {"position_m": [0.0, 0.0, 0.0], "stiffness_n_per_m": "identified:mode1.damping"}]}}, "expected a stiffness"),
    # M, k and c of different modes make a rotor whose natural frequency the test did not find
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": ADB,
      "rotor": {**ROTOR, "M": "identified:mode2.mass"}}, "M from mode 2, k from mode 1, c from mode 1; expected M, k "
     "and c of one mode"),
    # pulley and shaft diameters in mm written as m: a 4869 m/s belt, a 25 m shaft on 1.3 m
    ({"outputs": {"tables": ["drive"]}, "drive": {**DRIVE, "stages": [{**DRIVE["stages"][0], "driver_diameter_m": 100.0,
                                                                      "driven_diameter_m": 120.0,
                                                                      "center_distance_m": 300.0}]}},
     "key 'drive': driver_diameter_m = 100 m at 930 rpm runs the belt at 4869 m/s"),
    ({"outputs": {"tables": ["drive"]}, "drive": {**DRIVE, "shaft": {**DRIVE["shaft"], "diameter_m": 25.0}}},
     "key 'drive.shaft': diameter_m = 25 m is not below the shaft's length_m = 1.3 m"),
    # a crank radius in mm written as m (2340 m/s mean piston speed), crank masses in g written as kg (245 kg of
    # moving parts in a 16.3 kg compressor): refused before any stage runs
    ({"outputs": {"tables": ["compressor"]}, "compressor": {**COMPRESSOR, "crank_radius_m": 11.9, "rod_length_m": 50.0}},
     "key 'compressor.crank_radius_m' = 11.9 m at 2950 rpm moves the piston at 2340 m/s on average; expected below 30"),
    ({"outputs": {"tables": ["mounts"]}, "compressor": {
        **COMPRESSOR, "rotating_mass_kg": 96.656, "reciprocating_mass_kg": 148.344,
        "body": {"mass_kg": 16.3, "inertia_kg_m2": [[0.067, 0, 0], [0, 0.059, 0], [0, 0, 0.0405]],
                 "crank_centre_m": [0.005, 0.008, 0.005]},
        "mounts": [{"position_m": [0.0, 0.076, -0.056], "stiffness_n_per_m": [3e4, 3e4, 6e4]}]}},
     "key 'compressor.body.mass_kg' = 16.3 kg is not above the crank's moving masses (245 kg)"),
    # the race radius in mm (50 m) or cm (5 m) written as m: balls at 2-5 km/s, beyond a steel ring's burst speed
    ({"outputs": {"tables": ["adb_stability"]}, "frf": SYNTH_FRF, "adb": {**ADB, "R": 50.0}, "rotor": ROTOR},
     "key 'adb.R' = 50 m at 98.0185 rad/s (the rotor's natural frequency) moves the balls at 4901 m/s"),
    ({"outputs": {"tables": ["adb_response"]}, "frf": SYNTH_FRF, "rotor": ROTOR,
      "adb": {**ADB, "R": 5.0, "response": {"speed_end_rad_s": 400.0, "ramp_s": 1.0}}},
     "key 'adb.R' = 5 m at 400 rad/s (the response's top speed) moves the balls at 2000 m/s"),
    # mount stiffness in kN/m written as N/m, the body's mass in g written as kg: the body would sink 0.85 m
    ({"outputs": {"tables": ["mounts"]}, "compressor": {**COMPRESSOR, "body": BODY, "mounts": [
        {**mount, "stiffness_n_per_m": [k / 1000 for k in mount["stiffness_n_per_m"]]} for mount in MOUNTS]}},
     "key 'compressor.mounts': the 16.3 kg body would sag 0.846 m"),
    ({"outputs": {"tables": ["mounts"]}, "compressor": {**COMPRESSOR, "body": {**BODY, "mass_kg": 16300.0},
                                                        "mounts": MOUNTS}},
     "key 'compressor.mounts': the 16300 kg body would sag 0.846 m"),
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


def test_the_bodys_own_mounts_pass_the_sag_check(tmp_path):
    # the same body and mounts as the refused scenes above, in their units: 0.85 mm of sag, no error
    run = run_scene(copy.deepcopy({"outputs": {"tables": ["mounts"]},
                                   "compressor": {**COMPRESSOR, "body": BODY, "mounts": MOUNTS}}),
                    out=tmp_path / "o.h5")
    assert run.stages["mounts"] == "ran"


def test_a_compressor_slower_than_any_machine_is_warned(tmp_path):
    """2950 rpm written as rev/s (49.2): the balance fraction is the same, the forces 3600 times too small; a
    piston moving at 0.04 m/s on average (the slowest machines run about 0.5 m/s) is warned, and the warning is
    kept with the stage; the compressor at its speed is not."""
    from modal.errors import ModalWarning

    slow = {"outputs": {"tables": ["compressor"]}, "compressor": {**COMPRESSOR, "speed_rpm": 49.2}}
    with pytest.warns(ModalWarning, match=r"'compressor.speed_rpm' = 49.2 rpm .* moves the piston at 0.039 m/s"):
        run = run_scene(copy.deepcopy(slow), out=tmp_path / "slow.h5")
    assert list(run.warnings) == ["compressor"]
    normal = run_scene(copy.deepcopy({**slow, "compressor": COMPRESSOR}), out=tmp_path / "normal.h5")
    assert normal.warnings == {}
