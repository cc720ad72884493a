"""Broken input: every kind gives one FormatError (or FRFValidationError) naming the file,
the field or line, and what was expected; never a raw NumPy/pyuff/h5py traceback."""
from __future__ import annotations

import os

import numpy as np
import pytest

from modal.errors import FormatError, FRFValidationError, ModalWarning
from modal.frf import FRF
from modal.io import read_frf, write_frf
from modal.synthetic import modal_frf

FREQ = 2.0 + 0.25 * np.arange(41)


def _frf(n_channels: int = 1, kind: str = "accelerance", freq=FREQ) -> FRF:
    const = np.arange(1, 2 * n_channels + 1, dtype=float).reshape(n_channels, 2)
    return modal_frf(freq, [5.0, 9.0], [0.02, 0.03], const if n_channels > 1 else const[0], kind=kind,
                     response_points=[f"{i + 1}+Z" for i in range(n_channels)],
                     reference_points=["1+Z"] * n_channels)


def _check_fails(path, *fragments, error=FormatError, **hints) -> str:
    """Read ``path``; check the error type, one line, the file name and each fragment."""
    with pytest.raises(error) as info:
        read_frf(path, **hints)
    exc = info.value
    msg = str(exc)
    assert type(exc) is error, type(exc)
    assert "\n" not in msg, msg
    assert str(path) in msg, msg
    assert "expected" in msg, msg
    for frag in fragments:
        assert frag in msg, f"{frag!r} not in {msg!r}"
    assert exc.__cause__ is None or isinstance(exc.__cause__, FormatError)  # `from None`: no foreign chain
    return msg


def _write(tmp_path, name: str, text: str | bytes):
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


# ================================================================ any file
def test_nonexistent_path(tmp_path):
    _check_fails(tmp_path / "missing.csv", "no such file")


def test_directory_instead_of_a_file(tmp_path):
    _check_fails(tmp_path, "is a directory")


def test_empty_file(tmp_path):
    _check_fails(_write(tmp_path, "empty.uff", ""), "empty file (0 bytes)")


def test_binary_garbage(tmp_path):
    garbage = np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes() + b"\x00"
    _check_fails(_write(tmp_path, "garbage.bin", garbage), "binary content")


def test_unknown_hint_is_a_type_error(tmp_path):
    path = tmp_path / "ok.csv"
    write_frf(_frf(), path)
    with pytest.raises(TypeError, match="knd"):
        read_frf(path, knd="mobility")


def test_write_with_unknown_extension(tmp_path):
    with pytest.raises(FormatError, match=r"extension '\.xyz'.*expected"):
        write_frf(_frf(), tmp_path / "h.xyz")
    with pytest.raises(FormatError, match="format='wav'"):
        write_frf(_frf(), tmp_path / "h.csv", format="wav")
    assert os.listdir(tmp_path) == []


# ================================================================ CSV / text
def _canonical(tmp_path, n_channels: int = 1) -> tuple[os.PathLike, list[str]]:
    path = tmp_path / "h.csv"
    write_frf(_frf(n_channels), path)
    return path, path.read_text().splitlines()


def test_blank_lines_only(tmp_path):
    _check_fails(_write(tmp_path, "blank.csv", "\n   \n\t\n"), "line 1", "only blank lines")


def test_only_a_header(tmp_path):
    _check_fails(_write(tmp_path, "hdr.csv", "frequency_hz,re,im\n"), "line 1", "only a header")


def test_only_metadata_lines(tmp_path):
    path, lines = _canonical(tmp_path)
    header_at = lines.index("frequency_hz,re_0,im_0")
    _write(tmp_path, "h.csv", "\n".join(lines[:header_at + 1]) + "\n")
    _check_fails(path, f"line {header_at + 1}", "no data lines")


def test_text_in_a_number_field(tmp_path):
    path, lines = _canonical(tmp_path)
    n = lines.index("frequency_hz,re_0,im_0") + 5
    parts = lines[n - 1].split(",")
    parts[1] = "abc"
    lines[n - 1] = ",".join(parts)
    _write(tmp_path, "h.csv", "\n".join(lines))
    _check_fails(path, f"line {n}", "column 're_0'", "'abc' is not a number")


def test_empty_field(tmp_path):
    _check_fails(_write(tmp_path, "gap.csv", "f,re,im\n1,2,3\n2,,3\n"), "line 3", "column 're'", "is empty")


def test_nan_value(tmp_path):
    _check_fails(_write(tmp_path, "nan.csv", "# kind: mobility\nf,re,im\n1,2,3\n2,nan,3\n"),
           "line 4", "column 're'", "not finite")


def test_inf_value(tmp_path):
    _check_fails(_write(tmp_path, "inf.csv", "# kind: mobility\nf,re,im\n1,2,3\n2,1,-inf\n"),
           "line 4", "column 'im'", "not finite")


def test_duplicate_frequencies(tmp_path):
    _check_fails(_write(tmp_path, "dup.csv", "f,re,im\n1,2,3\n2,1,1\n2,1,1\n3,0,1\n"),
           "frequency_hz", "duplicate", error=FRFValidationError, kind="mobility")


def test_unsorted_frequencies_are_sorted_with_a_warning(tmp_path):
    path = _write(tmp_path, "unsorted.csv", "f,re,im\n1,1,0\n3,3,0\n2,2,0\n")
    with pytest.warns(ModalWarning, match="sorted"):
        frf = read_frf(path, kind="receptance")
    assert list(frf.frequency_hz) == [1, 2, 3] and list(frf.response.real) == [1, 2, 3]


def test_negative_frequency(tmp_path):
    _check_fails(_write(tmp_path, "neg.csv", "f,re,im\n-1,2,3\n2,1,1\n"), "frequency_hz", "negative",
           error=FRFValidationError, kind="mobility")


def test_mismatched_column_counts(tmp_path):
    _check_fails(_write(tmp_path, "cols.csv", "f,re,im\n1,2,3\n2,1\n3,1,1\n"), "line 3", "2 columns", "expected 3")


def test_header_and_data_disagree(tmp_path):
    _check_fails(_write(tmp_path, "hd.csv", "f,re,im,extra\n1,2,3\n2,1,1\n"), "line 2", "names 4")


def test_columns_do_not_pair_up(tmp_path):
    _check_fails(_write(tmp_path, "pairs.csv", "1,2,3,4\n2,1,1,1\n"), "4 columns", "odd number",
           layout="re_im", kind="mobility")


def test_unknown_kind_in_file(tmp_path):
    path, lines = _canonical(tmp_path)
    _write(tmp_path, "h.csv", "\n".join(lines).replace("# kind: accelerance", "# kind: stiffness"))
    _check_fails(path, "line 2 (field kind)", "unknown FRF kind 'stiffness'")


def test_unknown_kind_hint(tmp_path):
    _check_fails(_write(tmp_path, "k.csv", "f,re,im\n1,2,3\n2,1,1\n"), "hint kind=", "'flexibility'",
           kind="flexibility")


def test_kind_missing(tmp_path):
    _check_fails(_write(tmp_path, "nokind.csv", "f,re,im\n1,2,3\n2,1,1\n"), "cannot be determined", "kind=")


def test_kind_hint_contradicts_file(tmp_path):
    path, _ = _canonical(tmp_path)
    _check_fails(path, "says accelerance", "kind='mobility'", kind="mobility")


def test_real_columns_without_header_are_ambiguous(tmp_path):
    _check_fails(_write(tmp_path, "amb.txt", "1 2 3\n2 1 1\n"), "line 1", "layout=", kind="mobility")


def test_decimal_comma_without_the_hint(tmp_path):
    text = "Frequency [Hz];Real;Imag\n1,0;0,5;0,25\n2,0;0,75;-1,5\n"
    path = _write(tmp_path, "komma.csv", text)
    _check_fails(path, "line 2", "'1,0' is not a number", "decimal=','", kind="receptance")
    frf = read_frf(path, kind="receptance", decimal=",")
    assert list(frf.frequency_hz) == [1.0, 2.0] and list(frf.response) == [0.5 + 0.25j, 0.75 - 1.5j]


def test_newer_canonical_version(tmp_path):
    path, lines = _canonical(tmp_path)
    _write(tmp_path, "h.csv", "\n".join(lines).replace("modalbal-frf-csv 1", "modalbal-frf-csv 2"))
    _check_fails(path, "line 1 (field format)", "version 2")


def test_channel_count_disagrees_with_metadata(tmp_path):
    path, lines = _canonical(tmp_path, n_channels=2)
    head = [ln for ln in lines if ln.startswith("#")]
    body = [",".join(ln.split(",")[:3]) for ln in lines if not ln.startswith("#")]
    _write(tmp_path, "h.csv", "\n".join(head + body))
    _check_fails(path, "field channels", "holds 1")


def test_point_ids_not_a_list(tmp_path):
    path, lines = _canonical(tmp_path)
    _write(tmp_path, "h.csv", "\n".join(lines).replace('["1+Z"]', "1+Z, 2+Z", 1))
    _check_fails(path, "field response_points", "JSON list")


def test_complex_column_without_frequency_lines(tmp_path):
    _check_fails(_write(tmp_path, "c.txt", "(1+2j)\n(2-1j)\n"), "no frequency column", "frequency_step=",
           kind="accelerance")


def test_unknown_frequency_unit(tmp_path):
    _check_fails(_write(tmp_path, "u.csv", "f,re,im\n1,2,3\n2,1,1\n"), "hint frequency_axis=", "'furlongs'",
           kind="mobility", frequency_axis="furlongs")


# ================================================================ UFF
def _uff_lines(tmp_path, n_channels: int = 1, name: str = "h.uff") -> tuple[os.PathLike, list[str]]:
    path = tmp_path / name
    write_frf(_frf(n_channels), path)
    return path, path.read_text().splitlines()


def _start(lines: list[str]) -> int:
    """Index of the first dataset's '    58' line (record r is at _start + r)."""
    return next(i for i, ln in enumerate(lines) if ln.strip() == "58")


def _set_record6_func_type(lines: list[str], code: int) -> list[str]:
    out = list(lines)
    for i, ln in enumerate(out):
        if ln.strip() == "58":
            out[i + 6] = f"{code:5d}" + out[i + 6][5:]
    return out


@pytest.mark.parametrize("code,name", [(1, "time response"), (2, "auto spectrum"), (3, "cross spectrum"),
                                       (12, "spectrum"), (6, "coherence")])
def test_uff_non_frf_function_types(tmp_path, code, name):
    path, lines = _uff_lines(tmp_path)
    _write(tmp_path, "h.uff", "\n".join(_set_record6_func_type(lines, code)) + "\n")
    _check_fails(path, "dataset 1 (line 8, record 6, field func_type)", f"function type {code} ({name}) is not an FRF",
           "expected 4 (frequency response function)")


def test_uff_frf_with_coherence_reads_the_frf_only(tmp_path):
    path, lines = _uff_lines(tmp_path, n_channels=2)
    second = [i for i, ln in enumerate(lines) if ln.strip() == "58"][1]
    lines[second + 6] = f"{6:5d}" + lines[second + 6][5:]
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    frf = read_frf(path)
    assert frf.n_channels == 1 and frf.response_points == ("1+Z",)
    _check_fails(path, "dataset 2", "function type 6 (coherence)", dataset=2)


def test_uff_kind_not_determinable(tmp_path):
    path, lines = _uff_lines(tmp_path)
    i = _start(lines) + 9  # record 9: ordinate numerator
    lines[i] = f"{0:10d}" + lines[i][10:]
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    _check_fails(path, "record 9", "0 (unknown)/13 (excitation force)", "kind= (--kind)")
    assert read_frf(path, kind="accelerance").kind == "accelerance"


def test_uff_truncated_file(tmp_path):
    path, lines = _uff_lines(tmp_path)
    _write(tmp_path, "h.uff", "\n".join(lines[:-1]) + "\n")
    _check_fails(path, "line 1", "no complete dataset", "'    -1'")
    path, lines = _uff_lines(tmp_path, n_channels=2)
    _write(tmp_path, "h.uff", "\n".join(lines[:-5]) + "\n")
    _check_fails(path, "dataset 2 has no closing '    -1' line")


def test_uff_truncated_data_records(tmp_path):
    path, lines = _uff_lines(tmp_path)
    _write(tmp_path, "h.uff", "\n".join(lines[:20] + lines[-1:]) + "\n")
    _check_fails(path, "record 7, field num_pts", "says 41 points", "hold 14")


def test_uff_odd_value_count(tmp_path):
    path, lines = _uff_lines(tmp_path)
    lines[-2] = lines[-2][:20]  # the last line loses its imaginary part
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    _check_fails(path, "field num_pts", "says 41 points", "hold 40")  # pyuff drops the unpaired value


def test_uff_wrong_record_length(tmp_path):
    path, lines = _uff_lines(tmp_path)
    i = _start(lines) + 7  # record 7 cut after its first field
    lines[i] = lines[i][:10]
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    _check_fails(path, "line 9, record 7, field num_pts", "'' is not an integer")


def test_uff_text_in_a_data_field(tmp_path):
    path, lines = _uff_lines(tmp_path)
    lines[16] = "        not-a-number" + lines[16][20:]
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    _check_fails(path, "line 17, data record", "'not-a-number' is not a number")


def test_uff_text_in_a_header_field(tmp_path):
    path, lines = _uff_lines(tmp_path)
    i = _start(lines) + 6
    lines[i] = lines[i][:41] + "      node" + lines[i][51:]
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    _check_fails(path, "record 6, field rsp_node", "'node' is not an integer")


def test_uff_nan_in_data(tmp_path):
    path, lines = _uff_lines(tmp_path)
    lines[16] = f"{'nan':>20s}" + lines[16][20:]
    _write(tmp_path, "h.uff", "\n".join(lines) + "\n")
    _check_fails(path, "dataset 1", "not finite")


def test_uff_datasets_on_different_axes(tmp_path):
    a, b = tmp_path / "a.uff", tmp_path / "b.uff"
    write_frf(_frf(), a)
    write_frf(_frf(freq=FREQ + 1.0), b)
    both = _write(tmp_path, "both.uff", a.read_text() + b.read_text())
    _check_fails(both, "dataset 2", "differs from dataset 1", "dataset=")
    assert read_frf(both, dataset=2).frequency_hz[0] == FREQ[0] + 1.0
    _check_fails(both, "hint dataset=7", "1..2", dataset=7)


def test_uff_real_ordinate_is_not_an_frf(tmp_path):
    import pyuff

    path = tmp_path / "real.uff"
    pyuff.UFF(str(path)).write_sets([{
        "type": 58, "func_type": 4, "rsp_node": 1, "rsp_dir": 3, "ref_node": 1, "ref_dir": 3,
        "abscissa_spacing": 1, "abscissa_spec_data_type": 18, "ordinate_spec_data_type": 12,
        "orddenom_spec_data_type": 13, "x": FREQ, "data": np.abs(_frf().response)}], mode="add")
    _check_fails(path, "field ord_data_type", "4 (real double)", "complex")


def test_uff_without_dataset_58(tmp_path):
    import pyuff

    path = tmp_path / "header_only.uff"
    pyuff.UFF(str(path)).write_sets([{"type": 151, "model_name": "beam", "description": "no data",
                                      "db_app": "x", "program": "y"}], mode="add")
    _check_fails(path, "no dataset 58", "types 151")


def test_uff58b_damaged_binary(tmp_path):
    path = tmp_path / "b.uff"
    write_frf(_frf(), path, format="uff58b")
    raw = path.read_bytes()
    cut = raw.index(b"    -1", 10)
    _write(tmp_path, "b.uff", raw[:cut - 100] + raw[cut:])
    _check_fails(path, "field num_pts", "says 41 points")


# ================================================================ MATLAB
def test_mat_missing_variable(tmp_path):
    import scipy.io

    path = tmp_path / "m.mat"
    scipy.io.savemat(path, {"f": FREQ, "Y": _frf().response})
    msg = _check_fails(path, "no variable 'response' or 'frf' or 'FRF' or 'H' or 'h' for the response",
                 "the file has: Y (1x41 complex), f (1x41 double)", "variables=")
    assert "f (1x41 double)" in msg
    _check_fails(path, "no variable 'omega'", variables={"frequency": "omega", "response": "Y"})


def test_mat_response_not_complex(tmp_path):
    import scipy.io

    path = tmp_path / "m.mat"
    scipy.io.savemat(path, {"f": FREQ, "H": np.abs(_frf().response)})
    _check_fails(path, "variable 'H' (1x41 double)", "real values", "complex", kind="accelerance")


def test_mat_response_wrong_shape(tmp_path):
    import scipy.io

    path = tmp_path / "m.mat"
    scipy.io.savemat(path, {"f": FREQ, "H": np.ones((3, 40), dtype=complex)})
    _check_fails(path, "variable 'H' (3x40 complex)", "does not match 'f' (41 lines)", kind="accelerance")


def test_mat_frequency_not_a_vector(tmp_path):
    import scipy.io

    path = tmp_path / "m.mat"
    scipy.io.savemat(path, {"f": np.ones((3, 41)), "H": _frf().response})
    _check_fails(path, "variable 'f' (3x41 double)", "real vector", kind="accelerance")


def test_mat_truncated(tmp_path):
    path = tmp_path / "m.mat"
    write_frf(_frf(2), path)
    _write(tmp_path, "m.mat", path.read_bytes()[:300])
    _check_fails(path, "not a readable MATLAB")


def test_mat_size_beyond_what_the_file_can_hold(tmp_path):
    # a bit flip in a cell's dimensions (1x1 → 1x268435457) in a 1.8 kB file
    # kept loadmat allocating for 9 s before it failed. The sizes listed by whosmat are checked
    # against the file's size first (zlib compresses at most about 1032:1)
    path = tmp_path / "m.mat"
    write_frf(_frf(), path)
    data = bytearray(path.read_bytes())
    name = data.index(b"response_points")
    dims = name - 8 - 8  # the dimensions subelement: its tag, then two int32, then the name's tag
    assert data[dims - 8] == 5 and int.from_bytes(data[dims:dims + 4], "little") == 1  # miINT32, 1 x …
    data[dims + 4:dims + 8] = (268435457).to_bytes(4, "little")
    path.write_bytes(bytes(data))
    _check_fails(path, "variable 'response_points' claims shape (1, 268435457)", f"{len(data)}-byte file")


def test_mat73_missing_variable(tmp_path):
    path = tmp_path / "m.mat"
    write_frf(_frf(), path, format="mat73")
    _check_fails(path, "no variable 'Hxy'", "response (41x1 complex)", variables={"response": "Hxy"})


# ================================================================ HDF5
def test_hdf5_without_frf_group(tmp_path):
    import h5py

    from modal.io.hdf5 import write_root_attrs

    path = tmp_path / "a.h5"
    with h5py.File(path, "w") as fh:
        write_root_attrs(fh)
        fh.create_group("identification")
    _check_fails(path, "no group /frf", "identification")


def test_hdf5_unknown_schema_major_version(tmp_path):
    import h5py

    path = tmp_path / "a.h5"
    write_frf(_frf(), path)
    with h5py.File(path, "r+") as fh:
        fh.attrs["schema_version"] = "2.0"
    _check_fails(path, "schema_version is '2.0'", "major version 1")


def test_hdf5_of_another_program(tmp_path):
    import h5py

    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as fh:
        fh["x"] = np.arange(3)
    _check_fails(path, "root attribute schema is None", "modalbal-archive")


def test_hdf5_truncated(tmp_path):
    path = tmp_path / "a.h5"
    write_frf(_frf(2), path)
    _write(tmp_path, "a.h5", path.read_bytes()[:1500])
    _check_fails(path, "HDF5")


def test_hdf5_real_response(tmp_path):
    import h5py

    path = tmp_path / "a.h5"
    write_frf(_frf(), path)
    with h5py.File(path, "r+") as fh:
        del fh["frf/0/response"]
        fh["frf/0/response"] = np.ones(FREQ.size)
    _check_fails(path, "group /frf/0/response", "dtype float64", "complex128")


def test_hdf5_missing_dataset(tmp_path):
    import h5py

    path = tmp_path / "a.h5"
    write_frf(_frf(), path)
    with h5py.File(path, "r+") as fh:
        del fh["frf/0/frequency_hz"]
    _check_fails(path, "group /frf/0", "no dataset 'frequency_hz'")


# ================================================================ writers
def test_uff_writer_refuses_point_ids_it_cannot_store(tmp_path):
    frf = FRF(FREQ, _frf().response, kind="mobility", response_points=["left wing"], reference_points=["1+Z"])
    with pytest.raises(FormatError, match=r"h\.uff: field 'response_points' channel 0: point id 'left wing'"):
        write_frf(frf, tmp_path / "h.uff")
    assert list(tmp_path.iterdir()) == []
    write_frf(frf, tmp_path / "h.csv")  # other formats store any id
    assert read_frf(tmp_path / "h.csv").response_points == ("left wing",)


def test_writers_leave_an_existing_target_alone_on_failure(tmp_path, monkeypatch):
    import h5py

    target = tmp_path / "keep.h5"
    write_frf(_frf(), target)
    before = target.read_bytes()

    def broken(group, frf):
        group.create_dataset("frequency_hz", data=frf.frequency_hz)
        raise OSError("device full")

    monkeypatch.setattr("modal.io.hdf5.write_frf_group", broken)
    with pytest.raises(OSError, match="device full"):
        write_frf(_frf(2), target)
    assert target.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["keep.h5"]
    with h5py.File(target, "r") as fh:
        assert fh["frf/0/response"].shape == (FREQ.size,)
