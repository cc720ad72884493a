"""Time files (modal.io.timedata.read_time, modal.io.timewrite.write_time): every layout read back exactly,
and every damaged or hostile file refused in one line naming the file, the dataset or column, and the fault."""
from __future__ import annotations

import gc
import os
import time
import warnings
from dataclasses import replace

import numpy as np
import pytest

from modal.errors import FormatError, ModalWarning
from modal.io.timedata import read_time
from modal.io.timewrite import write_time
from modal.synthetic import DigitalModes, impact_record
from support.paths import REAL
from support.refusals import assert_refused as refused

FS = 1024.0
PLANT = DigitalModes([40.0, 95.0], [0.03, 0.02], [[1.0, 0.5], [0.6, -0.8]], FS)
REAL_58B = REAL / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff"


def _record(**kwargs):
    return impact_record(PLANT, [0.5, 2.5], 4.0, force_noise=0.01, response_noise=0.01, seed=1, **kwargs).record


def assert_refused(path, *fragments) -> str:
    """read_time refuses ``path``: one line naming the file, each fragment, and what was expected; no warning."""
    return refused(path, read_time, *fragments)


def _uff(path, channels, binary=True, spacing=1, x=None):
    """Datasets 58/58b of time data with pyuff: (values, data type, unit) per channel."""
    import pyuff

    open(path, "wb").close()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        uff = pyuff.UFF(os.fspath(path))
        for k, (values, data_type, unit) in enumerate(channels):
            uff.write_sets({
                "type": 58, "binary": int(binary), "id1": f"ch {k + 1}", "id2": "NONE", "id3": "NONE",
                "id4": "NONE", "id5": "NONE", "func_type": 1, "func_id": k + 1, "ver_num": 0, "load_case_id": 0,
                "rsp_ent_name": "NONE", "rsp_node": k + 1, "rsp_dir": 3, "ref_ent_name": "NONE", "ref_node": 0,
                "ref_dir": 0, "abscissa_spacing": spacing, "abscissa_min": 0.0, "abscissa_inc": 1 / FS,
                "z_axis_value": 0.0, "abscissa_spec_data_type": 17, "abscissa_axis_lab": "Time",
                "abscissa_axis_units_lab": "s", "ordinate_spec_data_type": data_type, "ordinate_axis_lab": "NONE",
                "ordinate_axis_units_lab": unit, "orddenom_spec_data_type": 0, "orddenom_axis_lab": "NONE",
                "orddenom_axis_units_lab": "NONE", "z_axis_spec_data_type": 0,
                "x": np.arange(len(values)) / FS if x is None else x, "data": np.asarray(values, float),
            }, mode="add", force_double=True)
        del uff
        gc.collect()


def _three_channels(n=2048):
    rng = np.random.default_rng(0)
    return [(rng.standard_normal(n), 13, "N"), (rng.standard_normal(n), 12, "m/s^2"),
            (rng.standard_normal(n), 12, "m/s^2")]


# ------------------------------------------------------------------ round trips
@pytest.mark.parametrize("name, fmt", [("r.csv", None), ("r.uff", None), ("r.mat", None), ("r.h5", None),
                                       ("r58.uff", "uff58")])
def test_write_time_reads_back(tmp_path, name, fmt):
    record = _record(full_scale=[400.0, None, None], names=["1+Z", "2+Z", "3+Z"])
    path = tmp_path / name
    write_time(record, path, format=fmt)
    back = read_time(path)
    assert back.names == record.names and back.quantities == record.quantities and back.units == record.units
    assert back.sample_rate_hz == FS  # ASCII UFF keeps 1/1024 s to 6 digits: read as the whole number
    # binary and text at 17 digits are exact; ASCII UFF writes 12 significant digits (E20.12)
    tolerance = 5e-12 * np.max(np.abs(record.signals)) if fmt == "uff58" else 0.0
    np.testing.assert_allclose(back.signals, record.signals, rtol=0, atol=tolerance)
    # UFF has no field for the converter's range; the others declare it
    assert back.full_scale == (None if name.endswith(".uff") else (400.0, None, None))


def test_csv_full_scale_is_converted_with_its_unit(tmp_path):
    path = tmp_path / "r.csv"
    t = np.arange(64) / FS
    rows = "\n".join(f"{ti!r},{np.sin(ti).item()!r},{np.cos(ti).item()!r}" for ti in t.tolist())
    path.write_text(f"# full_scale: 2, nan\ntime,f [kN],a [g]\n{rows}\n")
    record = read_time(path)
    assert record.full_scale == (2000.0, None) and record.units == ("N", "m/s^2")


# ------------------------------------------------------------------ UFF
def test_uff_cut_short_names_the_dataset_and_says_it_ends_early(tmp_path):
    data = REAL_58B.read_bytes()
    path = tmp_path / "cut.uff"
    path.write_bytes(data[:int(0.8 * len(data))])  # within the 4th of 4 datasets
    assert_refused(path, "dataset 4 has no closing '    -1' line", "ends early")


def test_uff_dataset_with_fewer_samples_than_it_says(tmp_path):
    path = tmp_path / "short.uff"
    _uff(path, _three_channels(), binary=False)
    text = path.read_text().splitlines()
    last_open = max(k for k, ln in enumerate(text) if ln == "    -1" and k < len(text) - 1)
    # drop 20 data lines (80 samples) of the last dataset, keeping its closing line
    path.write_text("\n".join(text[:last_open + 20] + text[last_open + 40:]) + "\n")
    assert_refused(path, "dataset 3", "num_pts", "2048 samples", "ends early")


@pytest.mark.parametrize("binary", [True, False])
def test_uff_explicit_uniform_abscissa_is_read(tmp_path, binary):
    # pyuff 2.5 writes spacing 0 (an abscissa for every sample) when asked to; ASCII keeps each time to 6 digits
    channels = _three_channels()
    path = tmp_path / "x.uff"
    _uff(path, channels, binary=binary, spacing=0)
    record = read_time(path)
    assert record.sample_rate_hz == FS and record.n_samples == 2048
    np.testing.assert_allclose(record.signals[1], channels[1][0], rtol=5e-12)


def test_uff_explicit_uneven_abscissa_is_refused(tmp_path):
    x = np.arange(2048) / FS
    x[100:] += 0.3 / FS
    path = tmp_path / "uneven.uff"
    _uff(path, _three_channels(), spacing=0, x=x)
    assert_refused(path, "dataset 1", "abscissa_spacing 0", "from sample 100 to 101", "one rate")


def test_uff_zero_time_step_is_refused(tmp_path):
    path = tmp_path / "zero.uff"
    _uff(path, _three_channels())
    data = bytearray(path.read_bytes())
    # record 7 (the 9th line of each dataset): columns 44-56 hold the abscissa increment (E13.5)
    start = 0
    while (start := data.find(b"    -1\n    58b", start)) >= 0:
        line = start
        for _ in range(8):
            line = data.index(b"\n", line) + 1
        data[line + 43:line + 56] = b"  0.00000e+00"
        start = data.index(b"    -1", start + 10) + 6
    path.write_bytes(bytes(data))
    assert_refused(path, "dataset 1", "abscissa_inc", "time step 0.0 s", "positive step")


@pytest.mark.parametrize("token", ["inf", "-inf", "1.79769313486e+308"])
def test_ascii_uff_holding_infinity_is_refused_without_numpy_warnings(tmp_path, token):
    path = tmp_path / "inf.uff"
    _uff(path, _three_channels(), binary=False)
    lines = path.read_text().splitlines()
    second = [k for k, ln in enumerate(lines) if ln.strip().startswith("58")][1]
    data_line = lines[second + 12]  # the first data line of dataset 2: four E20.12 fields
    lines[second + 12] = data_line[:20] + f"{token:>20}" + data_line[40:]
    path.write_text("\n".join(lines) + "\n")
    assert_refused(path, "dataset 2", "sample 2", "expected finite samples")


def test_frf_uff_is_not_a_time_file(tmp_path):
    from modal.io import write_frf
    from modal.synthetic import modal_frf

    path = tmp_path / "frf.uff"
    write_frf(modal_frf(np.arange(1.0, 101.0), [40.0], [0.02], [1.0], kind="accelerance"), path)
    assert_refused(path, "function type 4", "modal fit", "expected a time file")


# ------------------------------------------------------------------ MAT, HDF5
def test_mat_channels_of_different_lengths(tmp_path):
    from scipy.io import savemat

    path = tmp_path / "ragged.mat"
    cell = np.empty(2, dtype=object)
    cell[0], cell[1] = np.ones(1000), np.ones(900)
    savemat(path, {"signals": cell, "sample_rate_hz": FS})
    assert_refused(path, "field 'signals', channel 2: 900 samples", "channel 1 has 1000", "one length for every channel")


def test_mat_cell_of_equal_channels_is_read(tmp_path):
    from scipy.io import savemat

    path = tmp_path / "cell.mat"
    cell = np.empty(2, dtype=object)
    cell[0], cell[1] = np.arange(10.0), -np.arange(10.0)
    savemat(path, {"signals": cell, "sample_rate_hz": FS, "units": np.array(["N", "mm"], dtype=object)})
    record = read_time(path)
    np.testing.assert_array_equal(record.signals, [np.arange(10.0), -1e-3 * np.arange(10.0)])


def test_damaged_mat_size_is_refused_at_once(tmp_path):
    # a bit flip in a cell's dimensions in a 1.8 kB file made the time reader allocate 2.2 GB for 14 s:
    # the sizes whosmat lists are checked against the file's size first (as the FRF reader does)
    path = tmp_path / "damaged.mat"
    write_time(_record(names=["f", "a", "b"]).__class__(np.ones((3, 64)), FS, ("f", "a", "b"),
                                                            ("force", None, None), ("N", None, None)), path)
    data = bytearray(path.read_bytes())
    name = data.index(b"names")
    dims = name - 8 - 8  # the dimensions subelement: its tag, then two int32, then the name's tag
    assert data[dims - 8] == 5 and int.from_bytes(data[dims + 4:dims + 8], "little") == 3  # miINT32, 1 x 3
    data[dims + 4:dims + 8] = (268435457).to_bytes(4, "little")
    path.write_bytes(bytes(data))
    start = time.perf_counter()
    assert_refused(path, "variable 'names' claims shape (1, 268435457)", f"{len(data)}-byte file")
    # not a timing test: it ends long before a multi-gigabyte allocation could (seconds, on a loaded machine)
    assert time.perf_counter() - start < 10


def test_mat_unknown_quantity_name_is_refused(tmp_path):
    from scipy.io import savemat

    path = tmp_path / "q.mat"
    savemat(path, {"signals": np.ones((2, 16)), "fs": FS, "quantities": np.array(["force", "accel"], dtype=object)})
    assert_refused(path, "field 'quantities', channel 2: 'accel'", "acceleration")


def test_hdf5_dataset_larger_than_the_file_is_refused(tmp_path):
    import h5py

    path = tmp_path / "big.h5"
    with h5py.File(path, "w") as fh:
        fh.create_dataset("signals", shape=(2, 10**9), dtype="f8", chunks=(1, 1024))  # claims 16 GB, stores nothing
        fh.create_dataset("sample_rate_hz", data=FS)
    assert_refused(path, "dataset /signals claims shape (2, 1000000000)", "an undamaged file")


# ------------------------------------------------------------------ CSV
def test_ragged_csv_names_the_line(tmp_path):
    path = tmp_path / "ragged.csv"
    rows = [f"{k / FS!r},{k}.0,{-k}.0" for k in range(40)]
    rows[17] = f"{17 / FS!r},17.0"
    path.write_text("time,force [N],a [m/s^2]\n" + "\n".join(rows) + "\n")
    assert_refused(path, "line 19: 2 columns", "expected 3 like the header")


def test_csv_cut_short_in_its_last_line_says_so(tmp_path):
    path = tmp_path / "cut.csv"
    rows = [f"{k / FS!r},{k}.0,{-k}.0" for k in range(40)]
    path.write_text("time,force [N],a [m/s^2]\n" + "\n".join(rows) + f"\n{40 / FS!r},40.0")
    assert_refused(path, "line 42: 2 columns (the last line: is the file cut short?)", "expected 3 like the header")


def test_csv_text_in_a_sample_names_line_and_column(tmp_path):
    path = tmp_path / "text.csv"
    rows = [f"{k / FS!r},{k}.0,{-k}.0" for k in range(40)]
    rows[5] = f"{5 / FS!r},5.0,oops"
    path.write_text("time,force [N],a [m/s^2]\n" + "\n".join(rows) + "\n")
    assert_refused(path, "line 7, column 'a [m/s^2]': 'oops' is not a number")


def test_frf_csv_is_not_a_time_file(tmp_path):
    from modal.io import write_frf
    from modal.synthetic import modal_frf

    path = tmp_path / "frf.csv"
    write_frf(modal_frf(np.linspace(1, 100, 50), [40.0], [0.02], [1.0], kind="accelerance"), path)
    assert_refused(path, "an FRF file", "expected a time file", "modal fit")
    bare = tmp_path / "bare.csv"
    bare.write_text("frequency_hz,re,im\n1,0.5,0.1\n2,0.4,0.2\n3,0.3,0.3\n")
    assert_refused(bare, "column 1 is 'frequency_hz'", "an FRF", "expected a time file")



@pytest.mark.parametrize("header, factor", [("time [ms]", 1e3), ("t (ms)", 1e3), ("time_us", 1e6), ("Time [s]", 1.0)])
def test_csv_time_column_in_its_own_unit(tmp_path, header, factor):
    from modal.io.timedata import is_time_file

    path = tmp_path / "unit.csv"
    rows = [f"{factor * k / FS!r},{float(np.sin(k))!r},{float(np.cos(k))!r}" for k in range(64)]
    path.write_text(f"{header},force [N],a [m/s^2]\n" + "\n".join(rows) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a unit given: no word about it
        record = read_time(path)
    assert is_time_file(path)
    assert record.sample_rate_hz == pytest.approx(FS, rel=1e-9)


def test_csv_time_column_without_unit_holding_milliseconds_is_named(tmp_path):
    from modal.errors import QualityWarning

    # milliseconds read as seconds: 1.024 Hz, far below what vibration is sampled at; said, with the fix
    path = tmp_path / "ms.csv"
    rows = [f"{1e3 * k / FS!r},{float(np.sin(k))!r},{float(np.cos(k))!r}" for k in range(64)]
    path.write_text("time,force [N],a [m/s^2]\n" + "\n".join(rows) + "\n")
    with pytest.warns(QualityWarning, match=r"ms\.csv: field 'time' gives no unit.*1\.024 Hz.*'time \[ms\]'"):
        read_time(path)
    seconds = tmp_path / "s.csv"
    seconds.write_text("time,force [N],a [m/s^2]\n" + "\n".join(
        f"{k / FS!r},{float(np.sin(k))!r},{float(np.cos(k))!r}" for k in range(64)) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # seconds at 1024 Hz: no word
        assert read_time(seconds).sample_rate_hz == pytest.approx(FS, rel=1e-9)


@pytest.mark.parametrize("layout", ["trailing comma", "semicolon and decimal comma", "tab and decimal comma"])
def test_csv_spreadsheet_exports_read_as_the_plain_file(tmp_path, layout):
    # exports that end every line with the delimiter, or write a decimal comma with ';' or tab delimiters
    # (European locales), hold the same numbers as the plain file
    plain = tmp_path / "plain.csv"
    write_time(_record(), plain)
    lines = plain.read_text().splitlines()
    if layout == "trailing comma":
        text = [line + "," for line in lines]
    else:
        delimiter = ";" if layout.startswith("semicolon") else "\t"
        text = [lines[0].replace(",", delimiter)] + [ln.replace(",", delimiter).replace(".", ",") for ln in lines[1:]]
    path = tmp_path / "export.csv"
    path.write_text("\n".join(text) + "\n")
    got, expected = read_time(path), read_time(plain)
    assert got.names == expected.names and got.units == expected.units
    assert got.sample_rate_hz == expected.sample_rate_hz
    np.testing.assert_array_equal(got.signals, expected.signals)


def test_written_csv_has_one_line_ending(tmp_path):
    path = tmp_path / "r.csv"
    write_time(_record(), path)
    assert b"\r" not in path.read_bytes()

# ------------------------------------------------------------------ channel roles
def test_roles_refuse_an_accelerometer_as_the_excitation():
    record = read_time(REAL_58B)
    with pytest.raises(FormatError, match=r"channel 1 \(1\+Z#1, acceleration in m/s\^2\) is named as the "
                                          r"excitation but measured acceleration; expected a force channel"):
        record.check_roles([0], [1, 2, 3])


def test_roles_accept_an_unknown_excitation_with_a_warning_and_refuse_a_force_response():
    base = _record(names=["hammer", "a", "b"])
    unknown = replace(base, quantities=(None, "acceleration", "acceleration"), units=("V", "m/s^2", "m/s^2"))
    with pytest.warns(ModalWarning, match=r"channel 1 \(hammer, unknown quantity in V\) is taken as the excitation"):
        assert unknown.check_roles([0], [1, 2]) == "acceleration"
    two_forces = replace(base, quantities=("force", "acceleration", "force"), units=("N", "m/s^2", "N"))
    with pytest.raises(FormatError, match=r"channel 3 \(b, force in N\) is a response but measured force"):
        two_forces.check_roles([0], [1, 2])
    mixed = replace(base, quantities=("force", "acceleration", None))
    with pytest.raises(FormatError, match="different quantities"):
        mixed.check_roles([0], [1, 2])
    with pytest.raises(FormatError, match="both the excitation and a response"):
        base.check_roles([0], [0, 1])


def test_the_documented_csv_example_reads_as_documented(tmp_path):
    from support.paths import ROOT

    doc = (ROOT / "docs" / "estimate.md").read_text()
    block = doc.split("**CSV.**", 1)[1].split("```", 2)[1]
    path = tmp_path / "doc.csv"
    path.write_text(block.lstrip("\n"))
    record = read_time(path)
    assert record.names == ("hammer", "p1", "p2") and record.sample_rate_hz == pytest.approx(2000.0)
    assert record.quantities == ("force", "acceleration", "acceleration")
    assert record.full_scale == (500.0, None, 50 * 9.80665)  # g → m/s²: the declared level too
    assert record.signals[2, 1] == pytest.approx(0.012 * 9.80665)


def test_a_unit_that_contradicts_the_data_type_is_refused(tmp_path):
    # record 9 says excitation force (13) but labels the unit m/s^2: which one is wrong cannot be told
    channels = _three_channels()
    channels[0] = (channels[0][0], 13, "m/s^2")
    path = tmp_path / "contradiction.uff"
    _uff(path, channels)
    assert_refused(path, "dataset 1", "record 9, field ordinate_axis_units_lab", "'m/s^2' is of acceleration",
           "measured force")


@pytest.mark.parametrize("suffix, field", [(".mat", "field 'sample_rate_hz'"), (".h5", "field 'sample_rate_hz'"),
                                           (".uff", "the time step (record 7, abscissa_inc)"),
                                           (".csv", "column 'time [s]'")])
def test_a_rate_in_khz_is_refused_where_the_hammer_hits_contradict_it(tmp_path, suffix, field):
    # 1024 samples/s stored as 1.024 (kHz written as a number in Hz): every file read it as 1.024 Hz, and the fit
    # gave modes at 0.0156 Hz with k 1000² too small, unflagged. At that rate the 2 ms hits last 2 s each, which no
    # hammer hit does: refused, naming the field the rate came from
    record = replace(_record(), sample_rate_hz=FS / 1000)
    path = tmp_path / f"khz{suffix}"
    write_time(record, path)
    message = assert_refused(path, field, "1.024 samples/s", "2 hit(s) of force channel 1 last ", "at most 0.1 s")
    # the part of a 2 ms half-sine above the trigger threshold, 1000 times too long: between 1 and 2 s
    assert 1.0 <= float(message.split(" last ")[1].split(" s ")[0]) <= 2.0, message
    assert ("kHz" in message) != ("'time [ms]'" in message)  # the hint that fits where the rate came from
    # the same file at its true rate reads without a word, and so do hits as long as a soft tip's (20 ms)
    for record in (_record(), _record(pulse_width_s=0.02)):
        write_time(record, path)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert read_time(path).sample_rate_hz == pytest.approx(FS, rel=1e-9)


def test_a_time_column_named_in_ms_that_holds_seconds_is_refused(tmp_path):
    # the shipped hammer record with its header edited to 'time [ms]' (the column holds seconds): read at
    # 1.024 MHz, its 2 ms hits lasted 2 µs and every one was rejected as a "double hit"; no hammer hit is shorter
    # than a steel tip's 0.1 ms, so the column's unit is refused, with the way out
    from support.paths import SYNTHETIC

    lines = (SYNTHETIC / "hammer.csv").read_text().splitlines()
    path = tmp_path / "ms.csv"
    path.write_text("\n".join([lines[0].replace("time [s]", "time [ms]"), *lines[1:]]) + "\n")
    message = assert_refused(path, "column 'time [ms]' gives 1.024e+06 samples/s", "8 hit(s) of force channel 1",
                             "expected hammer hits of at least 2e-05 s", "name it 'time [s]'")
    assert float(message.split(" last ")[1].split(" s ")[0]) < 1e-5, message
    # the column named as it is reads without a word; a column in ms that holds ms, too
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_time(SYNTHETIC / "hammer.csv").sample_rate_hz == pytest.approx(1024.0)
        rows = [line.split(",") for line in lines[1:]]
        path.write_text("\n".join([lines[0].replace("time [s]", "time [ms]")]
                                   + [",".join([repr(1000 * float(t)), *rest]) for t, *rest in rows]) + "\n")
        assert read_time(path).sample_rate_hz == pytest.approx(1024.0)


def test_a_mat_rate_and_time_vector_that_disagree_are_refused(tmp_path):
    from scipy.io import savemat

    from modal.errors import QualityWarning

    record = _record()
    time = np.arange(record.signals.shape[1]) / FS
    path = tmp_path / "both.mat"
    units = np.array(["N", "m/s^2", "m/s^2"], dtype=object)
    savemat(path, {"signals": record.signals, "fs": FS / 1000, "time": time, "units": units})
    assert_refused(path, "field 'fs' is 1.024 but field 'time' steps 0.000976562 s (1024 Hz)", "in kHz?")
    # agreeing to a single-precision time vector's rounding: read
    savemat(path, {"signals": record.signals, "fs": FS, "time": time.astype(np.float32), "units": units})
    assert read_time(path).sample_rate_hz == FS
    # a rate in kHz without hits to contradict it (responses only): read, and named
    savemat(path, {"signals": record.signals[1:], "fs": FS / 1000, "units": units[1:]})
    with pytest.warns(QualityWarning, match=r"both\.mat: field 'fs' gives a sample rate of 1\.024 Hz.*write it in Hz"):
        read_time(path)
