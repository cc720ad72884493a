"""The scene's stages (balancer.scene.stages) wired together: the drive's hand-over to the rotor; a time record
in [frf] estimated with `modal fit`'s options and carried to the balancing studies."""

import pytest

from balancer import run_scene

from support.scenes import DRIVE, ADB, scene


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


# ---- a time record in a scene: the hammer test to the balancing studies ----------------------------------------

def _generator():
    import importlib.util

    from support.paths import SYNTHETIC

    spec = importlib.util.spec_from_file_location("generate", SYNTHETIC / "generate.py")
    generate = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate)
    return generate


def test_hammer_scene_hands_the_records_k_c_m_to_the_studies(tmp_path):
    """data/synthetic/hammer_scene.toml: the rig's hammer record (exact discrete time, generate.py) → FRF → modes →
    rotor → ball balancer and field balancing. The rotor's k, c and M lie within 3 reported standard errors of the
    record's truth: if the errors are right, each z is near standard normal and |z| < 3 holds with 99.7 %
    probability; beyond that the errors would understate the scatter (over 60 records made like this one, with other
    seeds, the z of f, ζ, k, c, m each scattered with a standard deviation of 1.1)."""
    from modal.archive import read_archive
    from modal.estimate import EstimatedFRF
    from support.paths import SYNTHETIC

    generate = _generator()
    run = run_scene(SYNTHETIC / "hammer_scene.toml", out=tmp_path / "hammer.h5", plots_dir=tmp_path / "plots")
    assert {s for s, v in run.stages.items() if v == "ran"} == {"frf", "identify", "rotor", "adb_stability",
                                                                   "balance"}
    frf = run.results["frf"]
    assert isinstance(frf, EstimatedFRF) and frf.averages == len(generate.HAMMER_HIT_TIMES_S) and not frf.rejected
    assert frf.response_points == ("1+Z",) and frf.reference_points == ("1+Z",)  # the driving point, from the ids
    rotor = run.results["rotor"]
    balls = rotor.params.n * rotor.params.m  # the test was made with the balls in
    truth = {"M": generate.RIG_MASS_KG - balls, "k": generate.RIG_STIFFNESS_N_PER_M, "c": generate.RIG_DAMPING_N_S_PER_M}
    for name, true in truth.items():
        value, std = getattr(rotor.params, name), getattr(rotor.std, name)
        assert 0 < std < 0.05 * true, (name, std)  # an error was carried over, and a small one
        assert abs(value - true) < 3 * std, (name, value, true, std)
    # the studies took them: the simulated balancing's model uses the identified k, c, M
    assert run.results["balance"].study is not None
    archived = read_archive(tmp_path / "hammer.h5")
    assert isinstance(archived["frf"], EstimatedFRF) and archived["frf"].averages == frf.averages
    assert {p.rsplit("/", 1)[1] for p in run.plot_paths} >= {"frf_estimate.png", "identify_fit.png"}
    assert "estimated from" in run.summary and f"{frf.averages} average(s)" in run.summary


def test_a_scene_estimates_the_frf_modal_fit_estimates(tmp_path):
    """One vocabulary: the [frf] time keys are `modal fit`'s time options (same names, same channel numbers from 1),
    and a scene gives the FRF that `modal fit` does with the same options."""
    import numpy as np

    from balancer.scene.schema import SCHEMA
    from balancer.scene.stages import TIME_FRF_OPTIONS
    from modal.cli import build_parser
    from modal.estimate import ESTIMATORS, WINDOWS
    from modal.fitting import FitOptions
    from modal.time_frf import TIME_OPTIONS, frf_from_time
    from support.paths import SYNTHETIC

    assert TIME_FRF_OPTIONS == TIME_OPTIONS and set(TIME_OPTIONS) <= set(SCHEMA["frf"])
    fit = build_parser()._subparsers._group_actions[0].choices["fit"]
    assert set(TIME_OPTIONS) <= {a.dest for a in fit._actions}
    for name, choices in (("estimator", ESTIMATORS), ("window", WINDOWS)):
        cli = next(a for a in fit._actions if a.dest == name)
        assert set(cli.choices) == set(choices)
        assert [SCHEMA["frf"][name](c) for c in choices] == list(choices)
    options = {"impact": True, "excitation": 1, "estimator": "Hv", "window": "exponential", "exponential_decay_s": 0.3}
    run = run_scene(scene(frf={"file": str(SYNTHETIC / "hammer.csv"), **options}, outputs={"tables": ["frf"]}))
    cli_options = FitOptions(**{**options, "excitation": "1"})
    expected, *_ = frf_from_time(SYNTHETIC / "hammer.csv", cli_options.namespace())
    got = run.results["frf"]
    assert got.estimator == "Hv" and got.window == "exponential" and got.exponential_decay_s == 0.3
    assert np.array_equal(got.response, expected.response) and np.array_equal(got.noise_std, expected.noise_std)


def _time_scene(tmp_path, **frf):
    from support.paths import SYNTHETIC

    return scene(frf={"file": str(SYNTHETIC / "hammer.csv"), **frf}, outputs={"tables": ["frf"]})


@pytest.mark.parametrize("frf, words", [
    ({"excitation": 3}, ["key 'frf.excitation' = 3", "no channel", "1..2"]),
    ({"excitation": 0}, ["key 'frf.excitation' = 0", "a channel number from 1"]),
    ({"response": [1, 5]}, ["key 'frf.response[1]' = 5", "1..2"]),
    ({"excitation": 2}, ["channel 2 (1+Z, acceleration in m/s^2) is named as the excitation"]),
    ({"frequency_step": 1.0}, ["key 'frf.frequency_step' applies to an FRF file", "time record"]),
    ({"overlap": 1.0}, ["key 'frf.overlap' = 1.0", "0 <= f < 1"]),
    ({"window": "hamming"}, ["key 'frf.window'", "'force'"]),
    # a hammer record's impact options without impact = true: refused in the check (was one line naming neither the
    # scene nor its key once the estimate ran: "error: field 'window': 'force' is for impact records")
    ({"window": "force"}, ["key 'frf'", "frf.window 'force' is for impact records", "frf.impact as well"]),
    ({"window": "hann", "exponential_decay_s": 0.3}, ["frf.exponential_decay_s is for impact records"]),
])
def test_a_time_record_in_a_scene_is_checked_before_any_work(tmp_path, frf, words):
    from balancer.scene import parse_scene
    from modal.errors import SceneError

    with pytest.raises(SceneError) as caught:
        parse_scene(_time_scene(tmp_path, **frf), source="s.toml")
    message = str(caught.value)
    assert message.startswith("s.toml: key 'frf")
    for word in words:
        assert word in message, message


def test_time_options_belong_to_a_time_record(tmp_path):
    from balancer.scene import parse_scene
    from modal.errors import SceneError
    from support.scenes import SYNTH_FRF

    with pytest.raises(SceneError, match="key 'frf.impact' applies to a time record"):
        parse_scene(scene(frf={**SYNTH_FRF, "impact": True}, outputs={"tables": ["frf"]}), source="s.toml")

def test_a_file_without_point_ids_gives_k_c_M_once_its_driving_point_is_declared(tmp_path):
    import numpy as np
    import pytest

    from balancer.scene.schema import parse_scene
    from modal.errors import SceneError
    from modal.io import write_frf
    from modal.synthetic import add_noise, modal_frf

    # a driving-point accelerance saved without point ids: nothing in the file says where the response was
    truth = modal_frf(np.linspace(0.25, 200.0, 800), [15.6, 120.0], [0.05, 0.02], [0.96, 0.35], kind="accelerance")
    write_frf(add_noise(truth, 0.002, seed=5), tmp_path / "plain.csv")
    rotor = {"M": "identified:mode1.mass", "k": "identified:mode1.stiffness", "c": "identified:mode1.damping",
             "e": 0.0005}

    def run(identify):
        config = scene(frf={"file": "plain.csv"}, identify=identify, rotor=rotor, adb=ADB, outputs={"tables": ["rotor"]})
        return run_scene(parse_scene(config, source=str(tmp_path / "s.toml"), folder=tmp_path))

    with pytest.raises(SceneError, match=r"declare it with driving_point = CHANNEL under \[identify\] \(counted "
                                         r"from 1\)"):
        run({"method": "nls"})
    with pytest.raises(SceneError, match=r"'identify.driving_point' = 2: no such channel; expected a channel "
                                         r"number 1\.\.1"):
        run({"method": "nls", "driving_point": 2})
    with pytest.raises(SceneError, match=r"'identify.channel' = 0: .*counted from 1"):
        run({"method": "nls", "driving_point": 1, "channel": 0})
    done = run({"method": "nls", "driving_point": 1, "channel": 1})
    mode = done.results["identify"].modes[0]
    assert done.results["rotor"].params.k == mode.stiffness_n_per_m
    # the modal mass of the first mode, 1/0.96 kg, within 3 of its standard errors
    assert abs(mode.mass_kg - 1 / 0.96) < 3 * mode.std.mass_kg


def _split_hammer_record(tmp_path):
    """The shipped hammer record saved as two files cut in the quiet between hits 4 and 5 (5.0 s)."""
    from support.paths import SYNTHETIC

    lines = (SYNTHETIC / "hammer.csv").read_text().splitlines()
    header, rows = lines[0], lines[1:]
    first, second = tmp_path / "hit_a.csv", tmp_path / "hit_b.csv"
    first.write_text("\n".join([header] + rows[:5120]) + "\n")
    t0 = float(rows[5120].split(",")[0])
    second.write_text("\n".join([header] + [",".join([repr(float(r.split(",")[0]) - t0)] + r.split(",")[1:])
                                            for r in rows[5120:]]) + "\n")
    return first, second


def test_a_scene_takes_a_hammer_test_saved_one_file_per_part(tmp_path):
    """[frf] file = [...] of time records: takes of one test, estimated as one, as `modal fit a b` does; a file
    of other channels is refused when the scene is read, naming it."""
    import numpy as np

    from balancer.scene import parse_scene
    from modal.errors import SceneError
    from modal.fitting import FitOptions
    from modal.time_frf import frf_from_time

    first, second = _split_hammer_record(tmp_path)
    options = {"impact": True, "window": "force"}
    config = scene(frf={"file": [str(first), str(second)], **options}, outputs={"tables": ["frf"]})
    run = run_scene(config, out=tmp_path / "takes.h5")
    expected, *_ = frf_from_time([first, second], FitOptions(**options).namespace())
    got = run.results["frf"]
    assert got.averages == expected.averages == 8
    assert np.array_equal(got.response, expected.response)
    # the archive's stage hash covers every take: a run on the same files reuses it, a changed take reruns
    assert run_scene(config, out=tmp_path / "again.h5", archive=tmp_path / "takes.h5").stages["frf"] == "reused"
    second.write_text("# the second take\n" + second.read_text())
    assert run_scene(config, out=tmp_path / "changed.h5", archive=tmp_path / "takes.h5").stages["frf"] == "ran"
    other = tmp_path / "other.csv"
    other.write_text(first.read_text().replace("1+Z [m/s^2]", "2+Z [m/s^2]", 1))
    with pytest.raises(SceneError, match=r"^s\.toml: key 'frf\.file' = .*other\.csv: channel 2 \(names\) is '2\+Z'"):
        parse_scene(scene(frf={"file": [str(first), str(other)], **options}, outputs={"tables": ["frf"]}),
                    source="s.toml")


def _roving_scene(tmp_path, files, **identify):
    """A scene over roving-hammer files in ``tmp_path``, the rotor's M, k, c from the driving point's mode 1."""
    from balancer.scene import parse_scene
    from support.scenes import ROTOR

    config = scene(frf={"file": [f.name for f in files], "impact": True}, identify={"method": "nls", **identify},
                   rotor={**ROTOR, "mass_includes_balls": False}, adb=ADB, outputs={"tables": ["rotor"]})
    return parse_scene(config, source=str(tmp_path / "s.toml"), folder=tmp_path)


def test_a_scene_takes_a_roving_hammer_test_as_modal_fit_does(tmp_path):
    """[frf] file = [p1, p2, p3], one file per hit point (the accelerometer at point 1): each point estimated from
    its own file and the FRFs joined, as `modal fit p1 p2 p3 --impact` does; k, c, M come from the driving point
    (hammer and accelerometer both at point 1), the one channel that has them."""
    import numpy as np
    import scipy.linalg

    from modal.errors import SceneError
    from modal.fitting import FitOptions
    from modal.roving import RovingEstimate
    from modal.time_frf import frf_from_time
    from support.roving import DAMPING, MASS, STIFFNESS, roving_files

    files = roving_files(tmp_path)
    run = run_scene(_roving_scene(tmp_path, files))
    frf = run.results["frf"]
    expected, *_ = frf_from_time(files, FitOptions(impact=True).namespace())
    assert isinstance(frf, RovingEstimate) and frf.reference_points == ("1+Z", "2+Z", "3+Z")
    np.testing.assert_array_equal(frf.response, expected.response)
    np.testing.assert_array_equal(frf.noise_std, expected.noise_std)
    identified = run.results["identify"]
    assert identified.settings["roving_hammer"] == expected.join_note
    assert list(identified[0].driving_point) == [True, False, False]
    # the truth at point 1: mode 1's mass-normalised shape φ gives m = 1/φ₁², k = ω² m, c = φᵀCφ m
    eigenvalues, shapes = scipy.linalg.eigh(STIFFNESS, MASS)
    shape = shapes[:, 0]
    mass = 1.0 / shape[0] ** 2
    truth = {"M": mass, "k": eigenvalues[0] * mass, "c": shape @ DAMPING @ shape * mass}
    rotor = run.results["rotor"]
    for name, true in truth.items():
        value, std = getattr(rotor.params, name), getattr(rotor.std, name)
        # the fit's one-sigma errors: 4 of them leave a chance of 6e-5 per value
        assert 0 < std < 0.05 * true and abs(value - true) <= 4 * std, (name, value, true, std)
    # the other channels (the hammer at points 2 and 3) give no k, c, M: [identify] channel picks one
    with pytest.raises(SceneError, match=r"key 'rotor\.M' = 'identified:mode1\.mass' is not defined for that "
                                         r"channel"):
        run_scene(_roving_scene(tmp_path, files, channel=2))


def test_a_scene_refuses_files_that_are_not_one_roving_hammer_test(tmp_path):
    """Files whose hammer moved but whose accelerometer moved too (or whose rate differs) are no roving-hammer
    test: refused when the scene is read, in one line naming the scene file, the key and the file, as
    `modal fit` refuses them."""
    import subprocess
    import sys

    from balancer.scene import parse_scene
    from modal.errors import SceneError
    from support.roving import hits, roving_files, write

    first = roving_files(tmp_path)[0]
    moved = write(tmp_path / "moved.csv", hits(1, seed=3, response="2+Z"))
    (tmp_path / "s.toml").write_text(f"""[frf]\nfile = ["{first.name}", "{moved.name}"]\nimpact = true\n"""
                                     """[outputs]\ntables = ["identify"]\n""")
    out = subprocess.run([sys.executable, "-m", "balancer", "run", str(tmp_path / "s.toml"), "--out",
                          str(tmp_path / "o.h5")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 1 and out.stderr.count("\n") == 1, out.stderr
    assert out.stderr.startswith(f"error: {tmp_path / 's.toml'}: key 'frf.file' = ['p1.csv', 'moved.csv']: "
                                 f"{moved}: response channel 2 (names) is '2+Z' where {first} has '1+Z'; expected "
                                 "the same accelerometers"), out.stderr
    assert not (tmp_path / "o.h5").exists()
    faster = write(tmp_path / "fast.csv", hits(1, seed=3, rate=2048.0))
    with pytest.raises(SceneError, match=r"^s\.toml: key 'frf\.file' = .*fast\.csv: sample rate 2048 Hz where "
                                         r".*p1\.csv has 1024 Hz; expected one rate"):
        parse_scene(scene(frf={"file": [first.name, faster.name], "impact": True}, outputs={"tables": ["frf"]}),
                    source="s.toml", folder=tmp_path)


def test_a_scene_reads_frf_files_on_one_axis_as_one_frf(tmp_path):
    """[frf] file = [...] of FRF files: their channels on one frequency axis, as `modal fit a b` reads them."""
    import numpy as np

    from modal.io import read_frf, write_frf
    from modal.synthetic import modal_frf

    frequency = np.linspace(1.0, 200.0, 400)
    paths = []
    for k, constant in enumerate([1.0, 0.4]):
        path = tmp_path / f"point{k + 1}.csv"
        write_frf(modal_frf(frequency, [40.0, 120.0], [0.02, 0.01], [constant, -constant], kind="accelerance"), path)
        paths.append(path)
    run = run_scene(scene(frf={"file": [str(p) for p in paths]}, outputs={"tables": ["frf"]}))
    expected = read_frf(paths)
    assert run.results["frf"].n_channels == 2
    np.testing.assert_array_equal(run.results["frf"].response, expected.response)


def test_a_hammer_record_in_volts_hands_no_k_c_m_to_the_studies(tmp_path):
    """Force and response recorded in V (sensitivities not applied): the modes are identified, but k, c, M in SI
    cannot be, so the rotor that refers to them is refused in one line saying why, even with accept_flagged."""
    from modal.errors import SceneError
    from support.paths import SYNTHETIC
    from support.scenes import ROTOR

    lines = (SYNTHETIC / "hammer.csv").read_text().splitlines()
    volts = tmp_path / "volts.csv"
    volts.write_text("\n".join(["time [s],1+Z [V],1+Z [V]"] + lines[1:]) + "\n")
    config = scene(frf={"file": str(volts), "impact": True, "excitation": 1, "kind": "accelerance"},
                   identify={"method": "nls", "accept_flagged": True}, rotor=dict(ROTOR), adb=dict(ADB),
                   outputs={"tables": ["rotor"]})
    with pytest.warns(UserWarning) as said, pytest.raises(
            SceneError, match=r"key 'rotor\.(M|k|c)' = 'identified:mode1\.\w+' is not defined for that channel "
                              r"\(flags: units_unknown\); the FRF's unit"):
        run_scene(config)
    messages = " ".join(str(w.message) for w in said)
    assert "is taken as the excitation" in messages and "k, c, m are not given (flag units_unknown)" in messages


@pytest.mark.parametrize("given", [{"M": 1.5}, {"k": 6.0e3}])
def test_a_rotor_mixing_given_and_identified_values_warns_of_a_frequency_the_test_did_not_find(given):
    """SYNTH_FRF's mode 1 (15.6 Hz, A = 0.96 1/kg: m = 1.042 kg with the two 20 g balls, k = 1.0e4 N/m). A rotor
    mass of 1.5 kg (or a stiffness of 6 kN/m) with the test's k (or M) gives a rotor 18 % (or 23 %) below the
    measured frequency: warned, naming the key. The rig's own mass (1.0 kg without balls) gives 15.6 Hz: silent."""
    import warnings

    from modal.errors import ModalWarning
    from support.scenes import ROTOR, SYNTH_FRF

    config = scene(frf=SYNTH_FRF, rotor={**ROTOR, **given}, adb=ADB, outputs={"tables": ["rotor"]})
    with pytest.warns(ModalWarning, match=rf"key 'rotor\.{next(iter(given))}': the rotor's natural frequency "
                                          r"sqrt\(k/\(M \+ n m\)\) = 1[23]\.\d+ Hz differs by -(18|23) % from "
                                          r"mode 1's 15\.6 Hz"):
        run_scene(config)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModalWarning)
        run_scene(scene(frf=SYNTH_FRF, rotor={**ROTOR, "M": 1.0}, adb=ADB, outputs={"tables": ["rotor"]}))
