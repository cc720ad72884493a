"""Time files on the command line: `modal fit TIME_FILE`, `modal frf TIME_FILE --out`, and read_time."""
from __future__ import annotations

import gc
import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import modal
import modal.cli
from support.paths import REAL, ROOT
from modal.errors import FormatError
from modal.io.timedata import read_time
from support.cli import run_main
from support.timedata import DigitalModes

FS = 1024.0
PLANT = DigitalModes(np.array([40.0, 95.0]), np.array([0.03, 0.02]), np.array([[1.0, 0.5], [0.6, -0.8]]), FS)


def run(*args):
    """``python -m modal ARGS`` in this process (the exit code and messages are the point here)."""
    return run_main(modal.cli.main, args, cwd=ROOT)


def run_process(*args):
    """``python -m modal ARGS`` in a subprocess: the time-file commands as a user starts them."""
    env = {**os.environ, "MPLBACKEND": "Agg"}
    return subprocess.run([sys.executable, "-m", "modal", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120)


def _records(seed=0, n=2**16):
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(n)
    accel = PLANT.respond(force)  # displacement, m: written as such below
    return force, accel + 1e-3 * accel.std(axis=1, keepdims=True) * rng.standard_normal(accel.shape)


def write_uff_time(path, force, responses, binary=True):
    """A UFF file of 58b (or 58) time-response datasets: force (data type 13) first, then displacements (8)."""
    import pyuff

    open(path, "wb").close()  # pyuff's mode "overwrite" truncates again when it switches to binary: "add" instead
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pyuff leaves its file handles to the garbage collector
        _write_sets(pyuff.UFF(os.fspath(path)), force, responses, binary)
        gc.collect()


def _write_sets(uff, force, responses, binary):
    for k, (values, data_type, unit) in enumerate([(force, 13, "N")] + [(r, 8, "m") for r in responses]):
        uff.write_sets({
            "type": 58, "binary": int(binary), "id1": f"channel {k + 1}", "id2": "NONE", "id3": "NONE",
            "id4": "NONE", "id5": "NONE", "func_type": 1, "func_id": k + 1, "ver_num": 0, "load_case_id": 0,
            "rsp_ent_name": "NONE", "rsp_node": k + 1, "rsp_dir": 3, "ref_ent_name": "NONE", "ref_node": 0,
            "ref_dir": 0, "abscissa_spacing": 1, "abscissa_min": 0.0, "abscissa_inc": 1.0 / FS, "z_axis_value": 0.0,
            "abscissa_spec_data_type": 17, "abscissa_axis_lab": "Time", "abscissa_axis_units_lab": "s",
            "ordinate_spec_data_type": data_type, "ordinate_axis_lab": "NONE", "ordinate_axis_units_lab": unit,
            "orddenom_spec_data_type": 0, "orddenom_axis_lab": "NONE", "orddenom_axis_units_lab": "NONE",
            "z_axis_spec_data_type": 0, "x": np.arange(values.size) / FS, "data": np.asarray(values, float),
        }, mode="add", force_double=True)


def test_read_time_from_uff_58b(tmp_path):
    force, resp = _records()
    path = tmp_path / "hammer.uff"
    write_uff_time(path, force, resp)
    record = read_time(path)
    assert record.sample_rate_hz == pytest.approx(FS, rel=1e-12)
    assert record.quantities == ("force", "displacement", "displacement")
    assert record.names == ("1+Z", "2+Z", "3+Z")
    np.testing.assert_allclose(record.signals[0], force, rtol=1e-12)
    assert record.force_channels() == [0] and record.channel_index("2+Z") == 1 and record.channel_index(3) == 2


def test_real_58b_time_file_reads_and_fit_without_force_says_why():
    path = REAL / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff"
    record = read_time(path)
    assert record.signals.shape == (4, 222400) and record.sample_rate_hz == pytest.approx(3200.0)
    assert set(record.quantities) == {"acceleration"}
    out = run("fit", path)
    assert out.returncode == 1
    assert "no channel marked as force" in out.stderr and "--excitation" in out.stderr
    assert out.stderr.count("\n") == 1  # one line, no traceback


def test_fit_time_file_finds_the_modes(tmp_path):
    force, resp = _records()
    path = tmp_path / "random.uff"
    write_uff_time(path, force, resp)
    out = run_process("fit", path, "--segment-length", 4096, "--json")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    assert doc["kind"] == "receptance" and doc["n_channels"] == 2
    found = sorted({round(row["natural_frequency_hz"], 6) for row in doc["modes"]})
    np.testing.assert_allclose(found, PLANT.natural_frequency_hz, rtol=1e-3)
    # the excitation (point 1) is not a response point: no driving point, k c m undefined
    assert all("not_driving_point" in row["flags"] for row in doc["modes"])
    assert "H1 estimate" in out.stderr


def test_frf_command_writes_an_estimate_that_fit_reads_back(tmp_path):
    force, resp = _records(seed=1)
    path = tmp_path / "random.csv"
    table = np.column_stack([np.arange(force.size) / FS, force, resp.T])
    np.savetxt(path, table, delimiter=",", header="time,force [N],a [m],b [m]", comments="")
    out_h5 = tmp_path / "frf.h5"
    made = run("frf", path, "--excitation", "force", "--out", out_h5, "--segment-length", 2048, "--json")
    assert made.returncode == 0, made.stderr
    doc = json.loads(made.stdout)
    # column names that are not point ids say nothing of where the force stood: no reference points, so
    # nothing is taken for a driving point (or a transfer) later
    assert doc["averages"] == 63 and doc["reference_points"] == []
    back = modal.read_frf(out_h5)
    assert isinstance(back, modal.EstimatedFRF) and back.averages == 63
    direct = modal.estimate_frf(force, resp, FS, segment_length=2048)
    np.testing.assert_allclose(back.response, direct.response, rtol=1e-9)
    np.testing.assert_allclose(back.noise_std, direct.noise_std, rtol=1e-9)
    fitted = run("fit", out_h5, "--json")
    assert fitted.returncode == 0, fitted.stderr
    found = sorted({round(row["natural_frequency_hz"], 6) for row in json.loads(fitted.stdout)["modes"]})
    np.testing.assert_allclose(found, PLANT.natural_frequency_hz, rtol=1e-3)


def test_csv_time_axis_must_be_uniform(tmp_path):
    path = tmp_path / "bad.csv"
    t = np.arange(100) / FS
    t[50] += 0.3 / FS
    np.savetxt(path, np.column_stack([t, np.ones(100), np.ones(100)]), delimiter=",", header="time,f,a",
               comments="")
    with pytest.raises(FormatError, match="'time' is not uniformly increasing"):
        read_time(path)


def test_unknown_channel_names_the_choices(tmp_path):
    force, resp = _records(n=4096)
    path = tmp_path / "hammer.uff"
    write_uff_time(path, force, resp, binary=False)
    out = run("frf", path, "--excitation", "7+Z", "--out", tmp_path / "x.h5")
    assert out.returncode == 1 and "no channel '7+Z'" in out.stderr and "1=1+Z" in out.stderr
    assert not (tmp_path / "x.h5").exists()


def test_impact_file_fit_with_plots(tmp_path):
    from support.timedata import hammer_force

    n = int(8 * FS)
    force = hammer_force(n, FS, [0.5, 2.5, 2.51, 4.5, 6.5])
    resp = PLANT.respond(force)
    path = tmp_path / "hammer.uff"
    write_uff_time(path, force, resp)
    plot = tmp_path / "fit.png"
    out = run("fit", path, "--impact", "--response", 2, "--segment-length", 1024, "--plot", plot, "--json")
    assert out.returncode == 0, out.stderr
    assert "hit 2 at 2.501 s rejected: double hit" in out.stderr  # the trigger: force above 5 % of its peak
    assert plot.exists() and (tmp_path / "fit_estimate.png").exists() and (tmp_path / "fit_hits.png").exists()
    found = sorted({round(row["natural_frequency_hz"], 6) for row in json.loads(out.stdout)["modes"]})
    np.testing.assert_allclose(found, PLANT.natural_frequency_hz, rtol=1e-3)


@pytest.mark.parametrize("fmt", ["mat", "hdf5"])
def test_read_time_from_mat_and_hdf5(tmp_path, fmt):
    force, resp = _records(n=4096)
    signals = np.vstack([force, resp])
    names = ["hammer", "p1", "p2"]
    if fmt == "mat":
        from scipy.io import savemat

        path = tmp_path / "rec.mat"
        savemat(path, {"signals": signals, "sample_rate_hz": FS, "names": np.array(names, dtype=object),
                       "units": np.array(["N", "mm", "mm"], dtype=object)})
    else:
        import h5py

        path = tmp_path / "rec.h5"
        with h5py.File(path, "w") as fh:
            ds = fh.create_dataset("signals", data=signals)
            ds.attrs["names"] = names
            ds.attrs["units"] = ["N", "mm", "mm"]
            fh.create_dataset("time", data=np.arange(signals.shape[1]) / FS)
    record = read_time(path)
    assert record.names == tuple(names) and record.quantities == ("force", "displacement", "displacement")
    assert record.sample_rate_hz == pytest.approx(FS, rel=1e-9)
    np.testing.assert_allclose(record.signals[1], resp[0] * 1e-3, rtol=1e-12)  # mm -> m at the edge
    assert record.units == ("N", "m", "m")


def test_an_accelerometer_named_as_the_excitation_is_refused():
    out = run("fit", REAL / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff", "--excitation", 1)
    assert out.returncode == 1 and out.stderr.count("\n") == 1, out.stderr
    assert "channel 1 (1+Z#1, acceleration in m/s^2) is named as the excitation but measured acceleration" \
        in out.stderr and "expected a force channel" in out.stderr


def test_roles_on_a_hammer_csv_match_what_its_header_says(tmp_path):
    from dataclasses import replace

    from modal.io.timewrite import write_time
    from modal.synthetic import impact_record

    record = impact_record(PLANT, [0.5, 2.5, 4.5], 6.0, names=["hammer", "a1", "a2"], seed=1).record
    path = tmp_path / "hammer.csv"
    write_time(record, path)
    wrong = run("frf", path, "--excitation", 2, "--out", tmp_path / "x.h5")
    assert wrong.returncode == 1 and wrong.stderr.count("\n") == 1
    assert "channel 2 (a1, acceleration in m/s^2) is named as the excitation" in wrong.stderr
    assert "does not say" not in wrong.stderr  # the header says [m/s^2] and [N]
    # a force column without a unit: accepted as the excitation, with a warning that says so
    unknown = tmp_path / "unknown.csv"
    write_time(replace(record, quantities=(None, "acceleration", "acceleration"), units=(None, "m/s^2", "m/s^2")),
               unknown)
    out = run("frf", unknown, "--excitation", 1, "--impact", "--out", tmp_path / "y.h5")
    assert out.returncode == 0, out.stderr
    assert "warning: " in out.stderr and "channel 1 (hammer, unknown quantity) is taken as the excitation" in out.stderr


def test_time_commands_on_files_that_are_not_whole_time_records(tmp_path):
    # a two-channel 58b cut in half ends exactly after the force dataset: nothing says it was cut, but the
    # message lists what the file holds
    force, resp = _records(n=4096)
    path = tmp_path / "half.uff"
    write_uff_time(path, force, resp[:1])
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2])
    out = run("frf", path, "--out", tmp_path / "x.h5")
    assert out.returncode == 1 and out.stderr.count("\n") == 1
    assert "holds 1 channel(s) (channel 1 (1+Z, force in N))" in out.stderr and "cut short" in out.stderr
    frf_file = ROOT / "data" / "synthetic" / "demo_frf.csv"
    out = run("frf", frf_file, "--out", tmp_path / "y.h5")
    assert out.returncode == 1 and out.stderr.count("\n") == 1
    assert "an FRF file" in out.stderr and "expected a time file" in out.stderr


def test_clipping_is_reported_on_the_command_line(tmp_path):
    from modal.io.timewrite import write_time
    from modal.synthetic import DigitalModes, impact_record, random_record

    plant = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], 2048.0)
    # hits clipped at 100 N (flat tops) and the full scale declared in the file: those hits are named and dropped
    hammer = impact_record(plant, 0.5 + 2.0 * np.arange(6), 12.0, pulse_width_s=0.003, amplitude_variation=0.2,
                           full_scale=[100.0, None, None], force_noise=0.002, response_noise=0.002,
                           names=["hammer", "a1", "a2"], seed=1)
    path = tmp_path / "hammer.csv"
    write_time(hammer.record, path)
    out = run("frf", path, "--impact", "--out", tmp_path / "h.h5", "--json")
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stderr.splitlines() if "rejected: overload (clipped)" in ln]
    assert len(lines) == 5 and all("force hammer at or beyond 99.9 % of its full scale 100" in ln for ln in lines)
    assert json.loads(out.stdout)["averages"] == 1
    # a shaker record whose response clipped: estimated, with a warning naming the channel
    shaker = random_record(plant, 32.0, full_scale=[None, 3.0, None], declare_full_scale=False, seed=2,
                           names=["force", "a1", "a2"])
    assert shaker.clipped_samples[1] > 0
    path = tmp_path / "shaker.csv"
    write_time(shaker.record, path)
    out = run("frf", path, "--out", tmp_path / "s.h5", "--json")
    assert out.returncode == 0, out.stderr
    assert "warning: " in out.stderr and "response a1 clipped at 3 (flat tops" in out.stderr
    doc = json.loads(out.stdout)
    assert any("response a1 clipped at 3 (flat tops" in w for w in doc["warnings"])
    # and as data beside the warnings: the channel, how, and how long
    assert [(o["channel"], o["how"]) for o in doc["overloads"]] == [("response a1", "flat tops")] and doc["unrelated"] == []


def test_a_hammer_record_fitted_without_impact_says_so(tmp_path):
    # the shipped hammer record, read as a continuous one (the user forgot --impact): the fit runs, and a
    # warning names the hits and the option that estimates them as such
    out = run("fit", ROOT / "data" / "synthetic" / "hammer.csv", "--json", "--archive", tmp_path / "a.h5")
    assert out.returncode == 0, out.stderr
    warning = [ln for ln in out.stderr.splitlines() if ln.startswith("warning: ")]
    assert len(warning) == 1 and "short pulse(s)" in warning[0] and "--impact" in warning[0]
    # the warning travels with the results: in the JSON document and in the archive beside the fit
    import h5py

    from modal.archive import read_warnings

    assert json.loads(out.stdout)["warnings"] == [warning[0].removeprefix("warning: ")]
    with h5py.File(tmp_path / "a.h5", "r") as f:
        fits = [name for name in f if name.startswith("identify_")]
        assert fits and all(read_warnings(f[name]) == (warning[0].removeprefix("warning: "),) for name in fits)
    clean = run("fit", ROOT / "data" / "synthetic" / "hammer.csv", "--impact", "--json")
    assert "warning: " not in clean.stderr and json.loads(clean.stdout)["warnings"] == []


def test_hammer_hits_saved_in_several_files_are_averaged_as_one_test(tmp_path):
    # the shipped hammer record (eight hits, 1.25 s apart) saved as two files cut in the quiet between hits 4
    # and 5: `modal fit` of the two files averages the same eight hits as the whole record, table for table
    lines = (ROOT / "data" / "synthetic" / "hammer.csv").read_text().splitlines()
    header, rows = lines[0], lines[1:]
    cut = 5120  # 5.0 s: hit 4's record ends at 4.93 s, hit 5 starts at 5.2 s
    first, second = tmp_path / "hit_a.csv", tmp_path / "hit_b.csv"
    first.write_text("\n".join([header] + rows[:cut]) + "\n")
    t0 = float(rows[cut].split(",")[0])
    second.write_text("\n".join([header] + [",".join([repr(float(r.split(",")[0]) - t0)] + r.split(",")[1:])
                                            for r in rows[cut:]]) + "\n")
    both = run("fit", first, second, "--impact", "--json")
    whole = run("fit", ROOT / "data" / "synthetic" / "hammer.csv", "--impact", "--json")
    assert both.returncode == 0 and whole.returncode == 0, both.stderr
    assert "8 average(s)" in both.stderr
    modes = [json.loads(out.stdout)["modes"] for out in (both, whole)]
    assert [m["natural_frequency_hz"] for m in modes[0]] == pytest.approx(
        [m["natural_frequency_hz"] for m in modes[1]], rel=1e-9)
    # a take given twice (a copy in the folder, or the same name twice): averaged with itself its noise looked
    # smaller, the fit turned model_inadequate and found a mode at 470 Hz; refused naming both files
    copy = tmp_path / "hit_a_copy.csv"
    copy.write_bytes(first.read_bytes())
    out = run("fit", first, copy, second, "--impact")
    assert out.returncode == 1 and out.stderr.count("\n") == 1
    assert f"{copy}: holds the same bytes as {first}; expected each of the takes once" in out.stderr
    # a file of other channels is not a take of the same test
    other = tmp_path / "other.csv"
    other.write_text("\n".join([header.replace("1+Z [m/s^2]", "2+Z [m/s^2]")] + rows[:cut]) + "\n")
    out = run("fit", first, other, "--impact")
    assert out.returncode == 1 and out.stderr.count("\n") == 1
    assert "other.csv: channel 2 (names) is '2+Z'" in out.stderr and "expected the same channels" in out.stderr


def test_a_band_above_the_files_nyquist_frequency_names_the_sample_rate(tmp_path):
    # a random-excitation MAT file whose fs is 1.024 (kHz written as a number): nothing in the record contradicts
    # it (no hits), so it is read with a warning; a band in Hz above its Nyquist frequency (0.512 Hz) then says
    # which rate it lies above instead of "band holds 0 lines"
    from scipy.io import savemat

    force, displacement = _records(n=2**14)
    path = tmp_path / "random.mat"
    savemat(path, {"signals": np.vstack([force, displacement]), "fs": FS / 1000,
                   "units": np.array(["N", "m", "m"], dtype=object)})
    out = run("fit", path, "--band", 30, 50)
    assert out.returncode == 1 and "Traceback" not in out.stderr
    assert "field 'fs' gives a sample rate of 1.024 Hz" in out.stderr
    error = [line for line in out.stderr.splitlines() if line.startswith("error: ")]
    assert error == [f"error: {path}: --band 30 50 Hz lies above the Nyquist frequency 0.512 Hz of the file's sample "
                     "rate 1.024 Hz; expected bands below it (is the file's sample rate in kHz?)"]


#: the modes of :func:`_ringing_takes`: 40 and 95 Hz at ζ 0.2 and 0.3 %, unit modal mass at the driving point
RINGING = DigitalModes([40.0, 95.0], [0.002, 0.003], [[1.0, 0.5]], FS)


def _ringing_takes(folder):
    """Three 1 s hammer takes, one hit each 0.1 s in, of modes that ring for seconds (decay times 2 and 0.6 s)."""
    from dataclasses import replace

    from modal.io.timewrite import write_time
    from modal.synthetic import impact_record

    paths = []
    for k in range(3):
        take = impact_record(RINGING, [0.1], 1.0, seed=20 + k, names=["1+Z", "1+Z"], response_noise=1e-3,
                             force_noise=1e-3).record
        paths.append(folder / f"take{k}.csv")
        write_time(replace(take, source=paths[-1].name), paths[-1])
    return paths


def test_hammer_takes_cut_short_while_ringing_are_refused_with_the_window_that_fixes_them(tmp_path):
    # three 1 s takes, one hit each 0.1 s in, a 0.2 % mode still at a third of its peak when the record ends:
    # `modal fit` printed m = 1.50 ± 0.03 kg for 1 kg (flag resolution_limited only); now every hit is refused
    # as not decayed, with the exponential window as the way out, and that window gives the mass back
    paths = _ringing_takes(tmp_path)
    out = run("fit", *paths, "--impact")
    assert out.returncode == 1 and out.stderr.count("error: ") == 1 and out.stdout == ""
    error = out.stderr.splitlines()[-1]
    assert "every hit was rejected" in error and error.count("response not decayed within the record") == 3
    assert "--window exponential --exponential-decay-s" in error
    fixed = run("fit", *paths, "--impact", "--window", "exponential", "--exponential-decay-s", "0.1", "--json")
    assert fixed.returncode == 0, fixed.stderr
    first = min(json.loads(fixed.stdout)["modes"], key=lambda row: abs(row["natural_frequency_hz"] - 40.0))
    # the mass within 4 of its standard errors (1/kg constant of mode 1 is 1.0)
    assert abs(first["mass_kg"] - 1.0) <= 4 * first["std"]["mass_kg"]


def test_a_hammer_file_with_force_and_response_swapped_says_so(tmp_path):
    # the shipped hammer record with its two columns' data exchanged (cables swapped at the recorder): the error
    # was "every hit was rejected (hit 1 ... double hit; ...)" for all eight hits
    lines = (ROOT / "data" / "synthetic" / "hammer.csv").read_text().splitlines()
    swapped = tmp_path / "swapped.csv"
    rows = [line.split(",") for line in lines[1:]]
    swapped.write_text("\n".join([lines[0]] + [",".join([t, a, f]) for t, f, a in rows]) + "\n")
    out = run("fit", swapped, "--impact")
    assert out.returncode == 1 and out.stderr.count("error: ") == 1 and out.stdout == ""
    error = out.stderr.splitlines()[-1]
    assert error.startswith(f"error: {swapped}: force 1+Z is no train of hammer pulses") and "look swapped" in error
    assert "double hit" not in error


def test_hammer_takes_at_several_force_levels_of_a_nonlinear_structure_are_warned_of(tmp_path):
    # four takes of two hits each at 30, 60, 120 and 240 N on a structure whose frequencies rise 1 % from 0 to
    # 240 N: `modal fit` printed 40.349 ± 0.008 Hz and ζ 1.03 ± 0.04 % with no word that the hits disagree
    from dataclasses import replace

    from modal.io.timewrite import write_time
    from modal.synthetic import impact_record

    paths = []
    for k, level in enumerate([30.0, 60.0, 120.0, 240.0]):
        scale = 1 + 0.01 * level / 240.0
        plant = DigitalModes([40.0 * scale, 95.0 * scale], [0.01, 0.02], [[1.0, 0.5]], FS)
        take = impact_record(plant, [0.5, 4.5], 8.0, amplitude_n=level, seed=60 + k, names=["1+Z", "1+Z"],
                             response_noise=1e-3, force_noise=1e-3).record
        paths.append(tmp_path / f"level{k}.csv")
        write_time(replace(take, source=paths[-1].name), paths[-1])
    out = run("fit", *paths, "--impact")
    assert out.returncode == 0, out.stderr
    warning = [ln for ln in out.stderr.splitlines() if "changes with the force of the hit" in ln]
    assert len(warning) == 1 and warning[0].startswith("warning: ") and "from 30 to 240" in warning[0]
    # one level alone: nothing to compare, no warning
    single = run("fit", paths[3], "--impact")
    assert single.returncode == 0 and "changes with the force" not in single.stderr


def test_the_global_method_takes_the_exponential_window_damping_out_too(tmp_path):
    # the global fit left the window's damping in its poles while the estimate line says "its damping is removed":
    # ζ 4.17 ± 0.004 % and c 21.2 N s/m for 0.2 % and 1.0 N s/m at 40 Hz with τ = 0.1 s (1/(ωτ) = 4 %)
    paths = _ringing_takes(tmp_path)
    options = ("--impact", "--window", "exponential", "--exponential-decay-s", "0.1", "--json")
    for method in ("global", "nls"):
        out = run("fit", *paths, *options, "--method", method)
        assert out.returncode == 0, out.stderr
        rows = json.loads(out.stdout)["modes"]
        for fn, zeta in zip(RINGING.natural_frequency_hz, RINGING.damping_ratio):
            row = min(rows, key=lambda r: abs(r["natural_frequency_hz"] - fn))
            # within 4 of its standard errors, and the window's share said
            assert abs(row["damping_ratio"] - zeta) <= 4 * row["std"]["damping_ratio"], (method, row)
            assert row["window_damping_ratio"] == pytest.approx(1 / (2 * np.pi * fn * 0.1), rel=0.01)


def test_an_exponential_window_that_flattens_every_peak_is_named_as_the_cause(tmp_path):
    # τ = 0.01 s adds ζ = 1/(2π f τ) = 40 % at 40 Hz: no peak stands, and the error only asked for bands
    out = run("fit", *_ringing_takes(tmp_path), "--impact", "--window", "exponential", "--exponential-decay-s", "0.01")
    assert out.returncode == 1 and out.stderr.count("error: ") == 1
    error = out.stderr.splitlines()[-1]
    assert "no resonance peak found" in error and "the exponential window (tau = 0.01 s)" in error
    assert "10 % or more below 159.2 Hz" in error  # 1/(0.2 π τ)


def test_a_shaker_force_with_an_offset_is_not_called_hammer_hits(tmp_path):
    # an offset of 5 standard deviations on a shaker's force (an amplifier's, a sensor settling) made `modal fit`
    # call its upper tail "179 short pulses, as hammer hits are" and advise --impact; the offset is no pulse
    from modal.io.timewrite import write_time
    from modal.synthetic_time import random_record

    record = random_record(PLANT, 30.0, force_rms_n=10.0, response_noise=0.02, names=["1+Z", "1+Z", "2+Z"],
                           seed=3).record
    signals = record.signals.copy()
    signals[0] += 5 * signals[0].std()
    path = tmp_path / "shaker_offset.csv"
    from dataclasses import replace
    write_time(replace(record, signals=signals), path)
    out = run("fit", path)
    assert out.returncode == 0, out.stderr
    assert "warning" not in out.stderr, out.stderr


def test_a_shaker_record_cut_into_two_records_is_warned(tmp_path):
    # `modal fit` on a 6 s shaker record with 4096-sample segments and no overlap averages 2 records: damping
    # 0.68 +- 0.056 % for 2.0 % with no word but resolution_limited; now the estimate says why not to trust it
    from modal.io.timewrite import write_time
    from modal.synthetic_time import random_record

    path = tmp_path / "short.csv"
    write_time(random_record(PLANT, 8.0, force_rms_n=10.0, response_noise=0.02, names=["1+Z", "1+Z", "2+Z"],
                             seed=3).record, path)
    out = run("fit", path, "--segment-length", 4096, "--overlap", 0)
    assert out.returncode == 0, out.stderr
    assert f"warning: {path}: the FRF is averaged over 2 records" in out.stderr
    assert "--segment-length N" in out.stderr
