"""What a new user meets first (issue 20): multi-channel plots, the toolkit reading its own
archives, units on every archived number, flags that do not contradict each other."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.lines import Line2D

from modal import identify
from modal.errors import FormatError, ModalError
from modal.flags import INFORMATIONAL
from modal.io import read_frf
from modal.plots import MAX_DRAWN_CHANNELS, model_response, plot_fit
from modal.synthetic import add_noise, modal_frf

from support.cli import run_module

ROOT = Path(__file__).resolve().parents[1]
REAL = sorted((ROOT / "data" / "real").glob("pyuff_meas_point_*.txt"))


def run(module, *args, cwd=None):
    """``python -m MODULE ARGS`` as a user runs it; the other tests run the command in-process (``run_module``)."""
    return subprocess.run([sys.executable, "-m", module, *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=180)


def _three_channel(n_channels=3, seed=3):
    rng = np.random.default_rng(seed)
    constants = rng.normal(size=(n_channels, 2)) * np.array([1.0, 0.5])
    constants[0] = np.abs(constants[0])  # channel 0 is a driving point
    frf = modal_frf(np.linspace(20, 300, 1201), [80.0, 190.0], [0.02, 0.015], constants, kind="mobility")
    return add_noise(frf, 1e-4, seed=seed)


def _identify(frf, method="nls"):
    import warnings

    from modal.errors import QualityWarning, ResolutionWarning

    with warnings.catch_warnings():  # flags are not what these tests are about
        warnings.simplefilter("ignore", QualityWarning)
        warnings.simplefilter("ignore", ResolutionWarning)
        return identify(frf, method)


def _lines(ax):
    return [line for line in ax.get_lines() if isinstance(line, Line2D) and np.asarray(line.get_xdata()).size > 2]


# ---- item 1: plots of multi-channel FRFs ---------------------------------------------------------------------

def test_multichannel_plot_draws_every_channel_with_its_model():
    frf = _three_channel()
    result = _identify(frf)
    fig = plot_fit(frf, result)
    ax_mag = fig.axes[0]
    model = model_response(frf, result)
    drawn = [np.asarray(line.get_ydata()) for line in _lines(ax_mag)]
    for ch in range(frf.n_channels):  # the data and the model of every channel are on the magnitude panel
        assert any(d.shape == (frf.n_freq,) and np.allclose(d, np.abs(frf.channels[ch])) for d in drawn)
        assert any(d.shape == (frf.n_freq,) and np.allclose(d, np.abs(model[ch])) for d in drawn)
    assert len(fig.axes) == 2 + len(result)  # magnitude, phase, one Nyquist panel per mode


def test_channel_option_draws_one_channel_and_rejects_a_missing_one():
    frf = _three_channel()
    result = _identify(frf)
    fig = plot_fit(frf, result, channel=2)
    drawn = [np.asarray(line.get_ydata()) for line in _lines(fig.axes[0])]
    assert len(drawn) == 2  # data and model of channel 2 only
    assert np.allclose(drawn[0], np.abs(frf.channels[2]))
    with pytest.raises(ModalError, match="channel 5 does not exist"):
        plot_fit(frf, result, channel=5)


def test_many_channels_show_the_rms_magnitude():
    frf = _three_channel(n_channels=MAX_DRAWN_CHANNELS + 4)
    result = _identify(frf)
    fig = plot_fit(frf, result)
    drawn = [np.asarray(line.get_ydata()) for line in _lines(fig.axes[0])]
    rms = np.sqrt(np.mean(np.abs(frf.channels) ** 2, axis=0))
    assert len(drawn) == 2 and np.allclose(drawn[0], rms)


def test_nyquist_model_circle_is_smooth():
    """The model circle is drawn with at most a few degrees between points (was a visible polygon)."""
    frf = modal_frf(np.linspace(20, 300, 281), [100.0], [0.002], [1.0], kind="mobility")  # 0.4 Hz wide, 1 Hz lines
    result = _identify(frf)
    fig = plot_fit(frf, result)
    line = [ln for ln in fig.axes[2].get_lines() if ln.get_linestyle() == "-"][0]
    z = np.asarray(line.get_xdata()) + 1j * np.asarray(line.get_ydata())
    centre = 0.5 * (z[np.argmax(np.abs(z - z[0]))] + z[0])  # the circle passes near the origin
    steps = np.abs(np.diff(np.unwrap(np.angle(z - centre))))
    assert np.degrees(steps.max()) < 5.0


def test_method_all_draws_every_method():
    frf = _three_channel(n_channels=1)
    results = [_identify(frf, m) for m in ("nls", "circle", "halfpower")]
    fig = plot_fit(frf, results)
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    for method in ("nls", "circle", "halfpower"):
        assert any(method in label for label in labels)


# ---- every archive the toolkit writes (items 1, 2, 4) ---------------------------------------------------------

@pytest.fixture(scope="module")
def archives(tmp_path_factory, dask_cluster):
    """Run every command that writes an archive, once; the batch on the session's Dask cluster
    (tests/modal/batch/test_cluster.py and test_formats.py run the embedded one). A process of its own, as a
    user runs it, for one command of each kind: the fit with its plot, the batch (whose stderr holds what
    Dask logs) and the scene with its plotting process; the others call the same ``main`` here."""
    out = tmp_path_factory.mktemp("archives")
    beam = [*REAL, "--frequency-step", "1", "--kind", "accelerance"]
    # a hammer record (the shipped real time file has no force channel: it cannot give an FRF)
    from modal.io.timewrite import write_time
    from modal.synthetic import DigitalModes, impact_record

    plant = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], 2048.0)
    uff = out / "hammer.uff"
    write_time(impact_record(plant, [0.5, 2.5, 4.5], 6.0, force_noise=0.002, response_noise=0.002,
                             names=["1+Z", "1+Z", "2+Z"]).record, uff)
    # name: (in a process of its own, program, *arguments)
    commands = {
        "fit_all.h5": (True, "modal", "fit", *beam, "--method", "all", "--plot", out / "beam.png",
                       "--archive", out / "fit_all.h5"),
        "fit_global.h5": (False, "modal", "fit", *beam, "--method", "global", "--archive", out / "fit_global.h5"),
        # one group per file, copied from per-file parts (issue 18)
        "batch.h5": (True, "modal", "batch", *beam, "--method", "all", "--scheduler", dask_cluster[0],
                     "--out", out / "batch.h5"),
        "estimate.h5": (False, "modal", "frf", uff, "--impact", "--out", out / "estimate.h5"),
        "demo.h5": (True, "balancer", "run", ROOT / "data" / "synthetic" / "demo_scene.toml", "--out", out / "demo.h5",
                    "--plots", out / "demo_plots"),
        "balance.h5": (False, "balancer", "run", ROOT / "data" / "synthetic" / "balance_scene.toml",
                       "--out", out / "balance.h5", "--plots", out / "balance_plots"),
    }
    for name, (own_process, module, *args) in commands.items():
        done = (run if own_process else run_module)(module, *args, cwd=out)
        assert done.returncode == 0, f"{name}: {done.stderr}"
        assert "Traceback" not in done.stderr
    return out


def test_real_beam_plot_archive_and_read_back(archives, tmp_path):
    """The three real beam files fitted with --plot and --archive in one command; the archive read back."""
    assert (archives / "beam.png").stat().st_size > 10_000
    back = run_module("modal", "fit", archives / "fit_all.h5", "--json")
    assert back.returncode == 0, back.stderr
    assert '"n_channels": 3' in back.stdout
    one = run_module("modal", "fit", *REAL, "--frequency-step", "1", "--kind", "accelerance", "--channel", "1",
                     "--plot", tmp_path / "ch1.png")
    assert one.returncode == 0, one.stderr


def test_scene_archive_is_an_frf_input(archives):
    archive = archives / "demo.h5"
    frf = read_frf(archive)
    assert frf.n_channels == 1 and frf.kind == "accelerance"
    fit = run_module("modal", "fit", archive)
    assert fit.returncode == 0, fit.stderr
    assert "1 channel(s)" in fit.stdout


def test_every_number_in_every_archive_has_units(archives):
    import h5py

    missing, files = [], sorted(archives.glob("*.h5"))
    assert len(files) == 6
    for path in files:
        with h5py.File(path, "r") as f:
            def visit(name, node, path=path):
                if isinstance(node, h5py.Dataset) and node.dtype.kind in "biufc" and "units" not in node.attrs:
                    missing.append(f"{path.name}:{name}")
            f.visititems(visit)
    assert missing == []
    with h5py.File(archives / "demo.h5", "r") as f:
        assert f["adb_stability/max_real_part_per_s"].attrs["units"] == "1/s"  # was "s"
        assert f["identify/modes/0/modal_constant"].attrs["units"] == "1/kg"
        assert f["identify/modes/0/band_hz/0"].attrs["units"] == "Hz"
        assert f["rotor/params/k"].attrs["units"] == "N/m" and f["rotor/params/M"].attrs["units"] == "kg"
        assert f["identify/modes/0/damping_ratio"].attrs["units"] == "1"
    with h5py.File(archives / "batch.h5", "r") as f:
        assert len(f["files"]) == 3 and f["files/0/results/0/modes/0/natural_frequency_hz"].attrs["units"] == "Hz"
        assert f["batch/wall_time_s"].attrs["units"] == "s" and f["files/2/n_lines"].attrs["units"] == "1"


def test_archive_without_frf_says_what_it_holds(tmp_path):
    from modal.archive import write_archive

    result = _identify(_three_channel(n_channels=1))
    path = write_archive(tmp_path / "results.h5", {"identify": result, "speed_rpm": 1500.0})
    with pytest.raises(FormatError, match=r"holds no FRF \(it holds identify \(IdentificationResult\), speed_rpm"):
        read_frf(path)
    out = run_module("modal", "fit", path)
    assert out.returncode == 1 and out.stderr.startswith("error: ") and "holds no FRF" in out.stderr


# ---- item 3: each flag defined once, no result contradicts itself -------------------------------------------

def test_every_flag_has_a_meaning_and_an_action_and_the_docs_table_is_current():
    from modal.flag_table import flags_markdown
    from modal.flags import FLAG_ACTION, FLAG_TEXT

    assert set(FLAG_ACTION) == set(FLAG_TEXT)
    assert all(text.strip() for text in FLAG_ACTION.values())
    docs = (ROOT / "docs" / "flags.md").read_text()
    assert docs == flags_markdown(), "docs/flags.md is stale: run `python -m modal.flag_table > docs/flags.md`"


def _all_results():
    """Results of every method on driving-point, transfer and mixed FRFs, synthetic and real."""
    frfs = [_three_channel()]  # channel 0 positive constants, others mixed signs; no point ids
    frfs.append(modal_frf(np.linspace(20, 300, 1201), [80.0, 190.0], [0.02, 0.015], [[1.0, 0.5], [0.3, -0.4]],
                          kind="mobility", response_points=["1+Z", "2+Z"], reference_points=["1+Z", "1+Z"]))
    frfs.append(read_frf(REAL, frequency_step=1.0, kind="accelerance"))
    out = []
    for frf in frfs:
        for method in ("nls", "circle", "halfpower", "global"):
            out.append(_identify(frf, method))
        out.append(_identify_driving(frf, method="nls"))
    return out


def _identify_driving(frf, method):
    import warnings

    from modal.errors import QualityWarning, ResolutionWarning

    driving = np.zeros(frf.n_channels, bool)
    driving[0] = True  # declared: channel 0 is the driving point
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QualityWarning)
        warnings.simplefilter("ignore", ResolutionWarning)
        return identify(frf, method, driving_point=driving)


def test_no_result_carries_contradictory_flags():
    from modal.flags import contradictions

    found = {}
    n_rows = 0
    for result in _all_results():
        for row in result.rows():
            n_rows += 1
            bad = contradictions(row)
            if bad:
                found[(result.method, row["mode"], row["channel"])] = bad
    assert n_rows > 50 and found == {}


def test_contradictions_are_detected():
    """The checker itself: the combination the issue reported is caught."""
    from modal.flags import contradictions

    row = {"flags": ["not_driving_point"], "driving_point": True, "stiffness_n_per_m": 1.0,
           "damping_n_s_per_m": 1.0, "mass_kg": 1.0}
    assert contradictions(row) == ["driving_point is true with flag not_driving_point"]
    row.update(driving_point=False, flags=["complex_mode"])
    assert len(contradictions(row)) == 4  # the flag and three physical parameters of a transfer channel


# ---- item 9: --driving-point, and the assumption shown in the table --------------------------------------------

def test_driving_point_option_and_unknown_driving_point_in_table(tmp_path):
    declared = run_module("modal", "fit", *REAL, "--frequency-step", "1", "--kind", "accelerance",
                          "--driving-point", "1", "--json")
    assert declared.returncode == 0, declared.stderr
    import json

    doc = json.loads(declared.stdout)
    rows = doc["modes"]
    # channels counted from 1 on the command line and in its output
    assert {r["channel"] for r in rows} == {1, 2, 3}
    assert {r["channel"] for r in rows if r["driving_point"]} == {1}
    assert doc["driving_point"] == {"known_from": "declared", "channels": [1]}
    # the real beam's channel 1 is no driving point (its constants change sign): declared one, it says so and
    # gives no k, c, m (a true driving point's do: plain.csv below)
    assert all(r["stiffness_n_per_m"] is None for r in rows)
    assert all("driving_point_contradicted" in r["flags"] for r in rows if r["channel"] == 1)
    for wrong in ("0", "4"):
        bad = run_module("modal", "fit", *REAL, "--frequency-step", "1", "--kind", "accelerance", "--driving-point",
                         wrong)
        assert bad.returncode == 1 and f"--driving-point {wrong}: no such channel; expected a channel number 1..3" \
            in bad.stderr, bad.stderr
    frf = modal_frf(np.linspace(20, 300, 801), [100.0], [0.02], [1.0], kind="receptance")
    from modal.io import write_frf

    write_frf(add_noise(frf, 1e-4, seed=2), tmp_path / "plain.csv")  # no point ids: nothing says where it was
    table = run_module("modal", "fit", tmp_path / "plain.csv")
    assert table.returncode == 0, table.stderr
    assert "driving_point_unknown" in table.stdout and "not_driving_point" not in table.stdout
    assert "k, c, m: n/a, the driving point is unknown" in table.stdout and "--driving-point" in table.stdout
    unknown = json.loads(run_module("modal", "fit", tmp_path / "plain.csv", "--json").stdout)
    assert unknown["driving_point"]["known_from"] == "unknown" and unknown["driving_point"]["channels"] == []
    assert "--driving-point" in unknown["driving_point"]["how_to_declare"]
    assert all(r["stiffness_n_per_m"] is None and r["mass_kg"] is None for r in unknown["modes"])
    declared = json.loads(run_module("modal", "fit", tmp_path / "plain.csv", "--json", "--driving-point", "1").stdout)
    assert declared["driving_point"] == {"known_from": "declared", "channels": [1]}
    assert all(r["stiffness_n_per_m"] is not None and not r["flags"] for r in declared["modes"]), declared["modes"]
    plot = run_module("modal", "fit", tmp_path / "plain.csv", "--plot", tmp_path / "p.png", "--channel", "2")
    assert plot.returncode == 1 and "--channel 2: no such channel; expected 1..1" in plot.stderr
    assert not (tmp_path / "p.png").exists()


# ---- item 7: temporaries of killed writers are cleaned, errors name the target ------------------------------------

_WRITER = """
import sys, time
from modal.io._atomic import atomic_path
with atomic_path(sys.argv[1]) as tmp:
    tmp.write_bytes(b"half an archive")
    print(tmp, flush=True)
    time.sleep(60)
"""


def _start_writer(target):
    proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(target)], stdout=subprocess.PIPE, text=True)
    tmp = Path(proc.stdout.readline().strip())
    assert tmp.exists() and tmp.parent == target.parent
    return proc, tmp


def test_killed_writer_temporary_is_cleaned_on_the_next_write(tmp_path):
    import signal

    from modal.archive import read_archive, write_archive

    target = tmp_path / "result.h5"
    dead, dead_tmp = _start_writer(target)
    dead.send_signal(signal.SIGKILL)  # kill -9 in the middle of the write
    dead.wait(timeout=30)
    dead.stdout.close()
    assert dead_tmp.exists()  # what the issue saw: the killed writer's temporary is left behind
    write_archive(target, {"speed_rpm": 1500.0})
    assert not dead_tmp.exists()  # cleaned by the next write
    assert read_archive(target)["speed_rpm"] == 1500.0
    live, live_tmp = _start_writer(target)  # another writer of the same target, still running
    try:
        write_archive(target, {"speed_rpm": 1500.0})
        assert live_tmp.exists()  # a live writer's file is not touched
    finally:
        live.kill()
        live.wait(timeout=30)
        live.stdout.close()
    leftovers = sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp"))
    assert leftovers == [live_tmp.name]  # killed in turn: the next write cleans it
    write_archive(target, {"speed_rpm": 1.0})
    assert not any(p.name.endswith(".tmp") for p in tmp_path.iterdir())


@pytest.mark.parametrize("option, name", [("--archive", "out.h5"), ("--plot", "out.png")])
def test_write_errors_name_the_target_not_the_temporary(tmp_path, option, name):
    (tmp_path / "a_file").write_text("not a folder")
    frf = modal_frf(np.linspace(20, 300, 801), [100.0], [0.02], [1.0], kind="receptance")
    from modal.io import write_frf

    write_frf(frf, tmp_path / "plain.csv")
    for folder in ("missing", "a_file"):
        target = tmp_path / folder / name
        out = run_module("modal", "fit", tmp_path / "plain.csv", option, target)
        assert out.returncode == 1
        assert out.stderr.startswith(f"error: {target}:") and ".tmp" not in out.stderr, out.stderr


# ---- item 5: overflow-scale data -----------------------------------------------------------------------------

@pytest.mark.parametrize("scale", [1e307, 1e-300])
def test_extreme_scale_fits_like_unit_scale(scale):
    """Identification is scale-invariant: H*g gives the same poles, A*g and k, c, m / g; no numpy warnings
    (pytest turns them into errors), no phantom modes."""
    from modal.frf import FRF

    base = add_noise(modal_frf(np.linspace(10, 400, 1001), [50, 120, 300], [0.01, 0.02, 0.03], [1, 0.5, 2.0],
                               kind="mobility"), 0.001, seed=1)
    gain = scale / np.abs(base.response).max()
    big = FRF(base.frequency_hz, base.response * gain, kind="mobility")
    for method in ("nls", "circle", "halfpower", "global"):
        ref, got = _identify(base, method), _identify(big, method)
        assert len(got) == len(ref)
        # gain is not a power of two: the data differ by rounding (1e-16 relative), the fits by its effect
        assert np.allclose([m.natural_frequency_hz for m in got], [m.natural_frequency_hz for m in ref], rtol=1e-9)
        assert np.allclose([m.damping_ratio for m in got], [m.damping_ratio for m in ref], rtol=1e-6)
        a_ref = np.array([complex(m.modal_constant) for m in ref])
        a_got = np.array([complex(m.modal_constant) for m in got]) / gain
        assert np.allclose(a_got, a_ref, rtol=1e-6, equal_nan=True)
        assert np.allclose([m.mass_kg * gain for m in got], [m.mass_kg for m in ref], rtol=1e-6,
                           equal_nan=True)


def test_overflow_scale_csv_on_the_command_line(tmp_path):
    from modal.frf import FRF
    from modal.io import write_frf

    base = add_noise(modal_frf(np.linspace(10, 400, 1001), [50, 120, 300], [0.01, 0.02, 0.03], [1, 0.5, 2.0],
                               kind="mobility"), 0.001, seed=1)
    write_frf(FRF(base.frequency_hz, base.response * (5e306 / np.abs(base.response).max()), kind="mobility"),
              tmp_path / "big.csv")
    out = run_module("modal", "fit", tmp_path / "big.csv", "--json", "--plot", tmp_path / "big.png")
    assert out.returncode == 0, out.stderr
    assert "encountered" not in out.stderr and "RuntimeWarning" not in out.stderr  # no bare numpy warnings
    import json

    modes = json.loads(out.stdout)["modes"]
    assert [round(m["natural_frequency_hz"]) for m in modes] == [50, 120, 300]  # no phantom mode


# ---- item 6: scenes say which mode they used and refuse flagged ones; one option vocabulary ----------------------

_BEAM_SCENE = """
[scene]
name = "beam"

[frf]
file = "{file}"
frequency_step = 1.0        # the option of `modal fit --frequency-step`, same name
kind = "accelerance"

[identify]
method = "nls"
driving_point = 1           # the file holds no point ids: declared, counted from 1
{accept}

[rotor]
M = "identified:mode{mode}.mass"
k = "identified:mode{mode}.stiffness"
c = "identified:mode{mode}.damping"
e = 0.0005
mass_includes_balls = false

[adb]
m = 0.02
n = 2
R = 0.05
D = 0.001

[outputs]
tables = ["identify", "rotor"]
archive = true
"""


def _driving_point_file(tmp_path):
    """A driving-point accelerance on 1 Hz lines as the beam's: two clean modes, then a pair 1 % apart that nls takes
    for one mode (flagged model_inadequate)."""
    path = tmp_path / "driving_point.txt"
    if not path.exists():  # the beam files' layout: one complex value per line, no frequency axis
        frf = modal_frf(np.arange(1001.0), [100.0, 300.0, 600.0, 606.0], [0.02, 0.005, 0.01, 0.01],
                        [1.0, 0.5, 0.8, 0.6], kind="accelerance")
        path.write_text("".join(f"{complex(v)!r}\n" for v in np.atleast_2d(add_noise(frf, 1e-4, seed=3).response)[0]))
    return path


def _beam_scene(tmp_path, mode, accept=""):
    path = tmp_path / f"beam_{mode}_{bool(accept)}.toml"
    path.write_text(_BEAM_SCENE.format(file=_driving_point_file(tmp_path).as_posix(), mode=mode, accept=accept))
    return path


def _beam_flags(tmp_path):
    frf = read_frf(_driving_point_file(tmp_path), frequency_step=1.0, kind="accelerance")
    from modal.flags import INFORMATIONAL

    return [sorted(set(m.flags) - INFORMATIONAL) for m in _identify_driving(frf, "nls")]


def test_scene_refuses_a_flagged_mode_and_says_which_mode_it_used(tmp_path):
    flags = _beam_flags(tmp_path)
    flagged = next(i for i, f in enumerate(flags) if f) + 1
    refused = run_module("balancer", "run", _beam_scene(tmp_path, flagged), "--out", tmp_path / "a.h5", cwd=tmp_path)
    assert refused.returncode == 1, refused.stderr
    assert f"mode {flagged} (" in refused.stderr and "is flagged" in refused.stderr
    assert "identify.accept_flagged = true" in refused.stderr
    accepted = run_module("balancer", "run", _beam_scene(tmp_path, flagged, "accept_flagged = true"),
                          "--out", tmp_path / "b.h5", cwd=tmp_path)
    assert accepted.returncode == 0, accepted.stderr
    assert f"k = 'identified:mode{flagged}.stiffness' (mode {flagged} at " in accepted.stdout
    assert "(accepted: identify.accept_flagged)" in accepted.stdout
    clean = [i + 1 for i, f in enumerate(flags) if not f]
    if clean:  # a clean mode runs without the explicit choice and names itself
        ok = run_module("balancer", "run", _beam_scene(tmp_path, clean[0]), "--out", tmp_path / "c.h5", cwd=tmp_path)
        assert ok.returncode == 0, ok.stderr
        assert f"(mode {clean[0]} at " in ok.stdout and "flags: none" in ok.stdout


def test_scene_and_cli_share_the_read_options():
    """Every read option of `modal fit` is a key of a scene's [frf] table, under the same name."""
    from balancer.scene.schema import SCHEMA
    from balancer.scene.stages import FRF_READ_OPTIONS
    from modal.cli import build_parser

    fit = build_parser()._subparsers._group_actions[0].choices["fit"]
    cli = {a.dest for a in fit._actions} & {"kind", "frequency_axis", "frequency_step", "frequency_start", "layout",
                                            "delimiter", "decimal", "dataset"}
    assert cli == set(FRF_READ_OPTIONS) and cli <= set(SCHEMA["frf"])
    axis = next(a for a in fit._actions if a.dest == "frequency_axis")
    assert set(axis.choices) <= {"hz", "khz", "rad/s", "cpm", "rpm"}
    for unit in axis.choices:
        assert SCHEMA["frf"]["frequency_axis"](unit) == unit


# ---- item 9: the README's CLI reference is generated from the parsers ---------------------------------------------

def test_readme_cli_reference_matches_the_parsers():
    from balancer.cli_synopsis import BEGIN, END, synopsis

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index(BEGIN):readme.index(END) + len(END) + 1]
    assert section == synopsis(), ("README.md's CLI reference is stale: run "
                                   "`python -m balancer.cli_synopsis --write README.md`")
    for option in ("--frequency-step", "--driving-point", "--channel", "--archive", "--out", "--grade"):
        assert f"  {option}" in section  # every option is documented, these among them


# ---- item 8: plots a user can read ---------------------------------------------------------------------------

def test_flagged_models_and_modes_are_labelled_in_the_plot():
    """On the real beam (< 0.1 line per half-power band) the circle fit is flagged on every mode and its model lies
    10-100x off the data: the legend and the Nyquist titles say so, so the overlay reads as a flagged estimate,
    not as a drawing error; the clean nls modes carry no mark."""
    frf = read_frf(REAL[0], frequency_step=1.0, kind="accelerance").cropped(10.0, 1000.0)
    results = [_identify(frf, m) for m in ("nls", "circle")]
    fig = plot_fit(frf, results)
    labels = {line.get_label() for line in fig.axes[0].get_lines()}
    n = len(results[1].modes)
    assert f"model (circle; {n} of {n} modes flagged)" in labels, labels
    nls_flagged = [m for m in results[0].modes if set(m.flags) - INFORMATIONAL]
    assert any(label.startswith("model (nls") for label in labels)
    titles = [ax.get_title() for ax in fig.axes[2:]]
    assert sum(t.endswith("flagged") for t in titles) == len(nls_flagged)  # the titles follow the first result


def test_ball_angles_are_not_drawn_across_the_panel_at_the_wrap():
    """A ball passing ±180° was drawn as a vertical line across the whole panel (the demo's ball-angle plot was
    a comb): consecutive drawn points now differ by less than 180°, and every sample is still drawn."""
    from balancer.adb import ADBParameters, simulate
    from balancer.adb.plots import plot_ball_angles

    params = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
    run_ = simulate(params, 2 * params.natural_frequency_rad_s, 1.0, n_samples=1001)
    wrapped = np.degrees(np.angle(np.exp(1j * run_.ball_angles_rad)))
    assert np.any(np.abs(np.diff(wrapped, axis=0)) > 180)  # the case does wrap
    fig = plot_ball_angles(run_)
    balls = [ln for ln in fig.axes[0].get_lines() if ln.get_label().startswith("ball")]
    assert len(balls) == 2
    for line, column in zip(balls, wrapped.T):
        y = np.asarray(line.get_ydata(), float)
        assert np.nanmax(np.abs(np.diff(y))) < 180
        assert np.array_equal(y[np.isfinite(y)], column)


def _overlapping_tick_labels(fig):
    """(axis title, label, label) of neighbouring tick labels whose drawn boxes overlap, after rendering."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    found = []
    for ax in fig.axes:
        for ticks in (ax.get_xticklabels(), ax.get_yticklabels()):
            boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in ticks if t.get_visible() and t.get_text()]
            for (a, box_a), (b, box_b) in zip(boxes, boxes[1:]):
                if box_a.overlaps(box_b):
                    found.append((ax.get_title(), a, b))
    return found


def test_tick_labels_do_not_overlap_on_the_real_beam_plot():
    """Six Nyquist panels side by side over the real beam's 1000 lines, every method: no two tick labels of an
    axis overlap once drawn (they did on small panels with long numbers)."""
    frf = read_frf(REAL[0], frequency_step=1.0, kind="accelerance")
    fig = plot_fit(frf, [_identify(frf, m) for m in ("nls", "circle", "halfpower")])
    assert _overlapping_tick_labels(fig) == []
    # the check sees overlaps: 30 long labels on a narrow axis
    from matplotlib.figure import Figure

    crowded = Figure(figsize=(2, 2))
    ax = crowded.add_subplot()
    ax.set_xticks(np.linspace(0, 1, 30), [f"{v:.6f}" for v in np.linspace(0, 1, 30)])
    assert _overlapping_tick_labels(crowded)


def test_nyquist_panels_of_the_real_beam_are_readable():
    """The real beam's three channels, global fit (eight modes, three flagged, titles naming channel and flag): no
    title runs into another title, a neighbouring panel or its tick labels; the axes say their unit (mobility, with
    the panel's power of ten); a legend says which is data and which model; the model is drawn densely across the
    resonance, where the 1 Hz lines hold a point or two (half-power width 2 zeta f_n = 0.05 Hz at 51.5 Hz)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    frf = read_frf(REAL, frequency_step=1.0, kind="accelerance")
    result = _identify(frf, "global")
    fig = plot_fit(frf, result)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    panels = fig.axes[2:]
    assert len(panels) == len(result.modes) and any("flagged" in ax.get_title() for ax in panels)
    titles = [ax.title.get_window_extent(renderer).padded(2 * fig.dpi / 72) for ax in panels]  # 2 pt clear around
    figure_box = fig.bbox
    for i, (ax, box) in enumerate(zip(panels, titles)):
        assert figure_box.x0 <= box.x0 and box.x1 <= figure_box.x1, ax.get_title()  # not cut off at the edge
        for j, other in enumerate(panels):
            if j != i:
                assert not box.overlaps(titles[j]), (ax.get_title(), other.get_title())
                assert not box.overlaps(other.get_window_extent(renderer)), (ax.get_title(), other.get_title())
                for label in other.get_xticklabels() + other.get_yticklabels() + [other.xaxis.label]:
                    if label.get_visible() and label.get_text():
                        assert not box.overlaps(label.get_window_extent(renderer)), (ax.get_title(), label.get_text())
        assert not ax.xaxis.get_offset_text().get_text() and not ax.yaxis.get_offset_text().get_text()
        assert ax.get_xlabel().startswith("Re Y [") and ax.get_xlabel().endswith("m/s/N]"), ax.get_xlabel()
    legend = [t.get_text() for t in panels[0].get_legend().get_texts()]
    assert legend[0] == "data" and legend[1] == "model (global)" and "model at f_n" in legend
    mode = result.modes[0]
    model = next(line for line in panels[0].get_lines() if line.get_label() == "model (global)")
    data = next(line for line in panels[0].get_lines() if line.get_label() == "data")
    half_power = mode.damping_ratio * mode.natural_frequency_hz  # half the half-power width, Hz
    near_data = np.count_nonzero(np.abs(frf.frequency_hz - mode.natural_frequency_hz) <= half_power)
    z_model = np.asarray(model.get_xdata()) + 1j * np.asarray(model.get_ydata())
    z_data = np.asarray(data.get_xdata()) + 1j * np.asarray(data.get_ydata())
    # the circle: its points reach across a diameter far larger than the data's few points near resonance span
    assert near_data <= 1 and len(z_model) > 100
    assert np.ptp(z_model.real) > 3 * np.ptp(z_data.real)


def test_a_plot_names_the_unit_the_frf_carries():
    """An FRF in another unit than the kind's SI one (counts over volts) is labelled so, never m/s^2/N."""
    frf = modal_frf(np.linspace(20, 300, 281), [100.0], [0.02], [1.0], kind="accelerance")
    from dataclasses import replace

    odd = replace(frf, units="counts/V")
    fig = plot_fit(odd, _identify(odd))
    unit_of = re.compile(r"Re Y \[(?:10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+ )?(.*)\]")  # the panel's power of ten, then the unit
    assert fig.axes[0].get_ylabel() == "|H| [counts/V]"
    assert unit_of.fullmatch(fig.axes[2].get_xlabel()).group(1) == "counts/V·s", fig.axes[2].get_xlabel()
    assert unit_of.fullmatch(plot_fit(frf, _identify(frf)).axes[2].get_xlabel()).group(1) == "m/s/N"
