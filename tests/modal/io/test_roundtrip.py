"""Write-then-read round trips of every FRF file format."""
from __future__ import annotations

import os

import numpy as np
import pytest

from modal.errors import FormatError
from modal.frf import FRF
from modal.io import read_frf, sniff_format, write_frf
from modal.synthetic import add_noise, modal_frf


def _frf(n_channels: int, kind: str = "accelerance", points: bool = True, n_lines: int = 401) -> FRF:
    freq = np.linspace(2.0, 400.0, n_lines)
    rng = np.random.default_rng(n_channels)
    const = rng.standard_normal((n_channels, 3)) + 0.1j * rng.standard_normal((n_channels, 3))
    frf = modal_frf(freq, [40.0, 130.0, 310.0], [0.01, 0.02, 0.015], const if n_channels > 1 else const[0],
                    kind=kind,
                    response_points=[f"{101 + i}+Z" for i in range(n_channels)] if points else None,
                    reference_points=["1-Y"] * n_channels if points else None)
    return add_noise(frf, 0.02, seed=n_channels)


def _awkward_frf() -> FRF:
    """Values whose decimal text is long or extreme: exact round trips must keep every bit."""
    rng = np.random.default_rng(7)
    freq = np.sort(rng.uniform(0.0, 1e4, 300))
    mant = rng.standard_normal((2, 300)) + 1j * rng.standard_normal((2, 300))
    scale = 10.0 ** rng.integers(-300, 300, (2, 300))
    resp = mant * scale
    resp[0, :3] = [0.0, -0.0 + 1j * 5e-324, 1.7976931348623157e308 - 2.2250738585072014e-308j]
    return FRF(freq, resp, kind="mobility", response_points=["a", "b"], reference_points=["c", "d"])


def _assert_same(got: FRF, want: FRF, rtol: float | None = None) -> None:
    assert got.kind == want.kind
    assert got.units == want.units
    assert got.response_points == want.response_points
    assert got.reference_points == want.reference_points
    assert got.response.shape == want.response.shape
    if rtol is None:  # bit-exact
        assert got.frequency_hz.tobytes() == want.frequency_hz.tobytes()
        assert got.response.tobytes() == want.response.tobytes()
    else:
        np.testing.assert_allclose(got.frequency_hz, want.frequency_hz, rtol=rtol, atol=0)
        scale = np.abs(want.channels).max(axis=1, keepdims=True)
        err = np.abs(got.channels - want.channels) / scale
        assert err.max() <= rtol, err.max()


# ----------------------------------------------------------------- CSV
@pytest.mark.parametrize("n_channels", [1, 3])
def test_canonical_csv_round_trip_is_bit_exact(tmp_path, n_channels):
    frf = _frf(n_channels)
    path = tmp_path / "h.csv"
    write_frf(frf, path)
    got = read_frf(path)
    _assert_same(got, frf)
    assert got == frf
    assert got.source == str(path)


def test_canonical_csv_keeps_extreme_values_bit_exact(tmp_path):
    frf = _awkward_frf()
    write_frf(frf, tmp_path / "x.csv")
    _assert_same(read_frf(tmp_path / "x.csv"), frf)


def test_canonical_csv_without_points(tmp_path):
    frf = _frf(2, kind="receptance", points=False)
    write_frf(frf, tmp_path / "np.csv")
    got = read_frf(tmp_path / "np.csv")
    assert got.response_points is None and got.reference_points is None
    _assert_same(got, frf)


def test_canonical_csv_layout(tmp_path):
    frf = _frf(2)
    write_frf(frf, tmp_path / "h.csv")
    lines = (tmp_path / "h.csv").read_text().splitlines()
    assert lines[0] == "# format: modalbal-frf-csv 1"
    assert "# kind: accelerance" in lines
    assert "# units: m/s^2/N" in lines
    assert "# frequency_unit: Hz" in lines
    assert '# response_points: ["101+Z", "102+Z"]' in lines
    assert "frequency_hz,re_0,im_0,re_1,im_1" in lines
    assert sniff_format(tmp_path / "h.csv") == "text"


def test_failed_write_leaves_target_untouched_and_no_temporary_files(tmp_path, monkeypatch):
    frf = _frf(1)
    target = tmp_path / "h.csv"
    target.write_text("old content\n")
    import modal.io.csv as csv_mod

    def exploding_repr(x):  # fails after the writer has written part of the file
        raise OSError("disk full")

    monkeypatch.setattr(csv_mod, "repr", exploding_repr, raising=False)
    with pytest.raises(OSError, match="disk full"):
        write_frf(frf, target)
    monkeypatch.undo()
    assert target.read_text() == "old content\n"
    assert os.listdir(tmp_path) == ["h.csv"]
    write_frf(frf, target)
    assert os.listdir(tmp_path) == ["h.csv"]
    assert read_frf(target) == frf


def test_atomic_path_renames_only_on_success(tmp_path):
    from modal.io._atomic import atomic_path

    target = tmp_path / "t.bin"
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("crash")
    assert not target.exists() and os.listdir(tmp_path) == []
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path
        tmp.write_bytes(b"whole")
    assert target.read_bytes() == b"whole" and os.listdir(tmp_path) == ["t.bin"]


def test_several_files_combine_into_channels(tmp_path):
    frf = _frf(3)
    paths = []
    for i in range(3):
        paths.append(tmp_path / f"c{i}.csv")
        write_frf(frf.channel(i), paths[-1])
    got = read_frf(paths)
    assert got.n_channels == 3
    _assert_same(got, frf)
    # a file given twice, or copied under another name: its channels would come twice (two identical rows in
    # every shape); refused naming both
    (tmp_path / "copy.csv").write_bytes(paths[1].read_bytes())
    for again in (paths[1], tmp_path / "copy.csv"):
        with pytest.raises(FormatError, match=rf"{again.name}: holds the same bytes as .*c1\.csv; expected each of "
                                              r"the files combined on one axis once"):
            read_frf([*paths, again])


# ----------------------------------------------------------------- HDF5
@pytest.mark.parametrize("n_channels", [1, 3])
def test_hdf5_round_trip_is_bit_exact(tmp_path, n_channels):
    frf = _frf(n_channels)
    write_frf(frf, tmp_path / "h.h5")
    assert sniff_format(tmp_path / "h.h5") == "hdf5"
    _assert_same(read_frf(tmp_path / "h.h5"), frf)
    awkward = _awkward_frf()
    write_frf(awkward, tmp_path / "x.hdf5")
    _assert_same(read_frf(tmp_path / "x.hdf5"), awkward)
    assert set(os.listdir(tmp_path)) == {"h.h5", "x.hdf5"}  # no temporary files left


def test_hdf5_layout_is_nexus_style_with_units(tmp_path):
    import h5py

    import modal
    from modal.io.hdf5 import SCHEMA_VERSION

    frf = _frf(2)
    write_frf(frf, tmp_path / "h.h5")
    with h5py.File(tmp_path / "h.h5", "r") as fh:
        assert fh.attrs["schema"] == "modalbal-archive"
        assert fh.attrs["schema_version"] == SCHEMA_VERSION == "1.0"
        assert fh.attrs["software_version"] == modal.__version__
        assert fh.attrs["created"].endswith("Z")
        g = fh["frf/0"]
        assert g.attrs["NX_class"] == "NXdata" and g.attrs["signal"] == "response"
        assert list(g.attrs["axes"]) == [".", "frequency_hz"]
        assert g["frequency_hz"].dtype == np.float64 and g["frequency_hz"].attrs["units"] == "Hz"
        assert g["response"].dtype == np.complex128 and g["response"].attrs["units"] == "m/s^2/N"
        assert g.attrs["kind"] == "accelerance"
        assert list(g.attrs["response_points"]) == ["101+Z", "102+Z"]


def test_hdf5_group_functions_are_reusable_inside_other_files(tmp_path):
    import h5py

    from modal.io.hdf5 import read_frf_group, write_frf_group

    a, b = _frf(1), _frf(2, kind="mobility", points=False)
    with h5py.File(tmp_path / "arch.h5", "w") as fh:
        write_frf_group(fh.create_group("frf/a"), a)
        write_frf_group(fh.create_group("frf/b"), b)
        fh.create_group("identification")
    with h5py.File(tmp_path / "arch.h5", "r") as fh:
        _assert_same(read_frf_group(fh["frf/a"], "arch.h5"), a)
        _assert_same(read_frf_group(fh["frf/b"], "arch.h5"), b)


def test_hdf5_keeps_a_one_row_two_dimensional_response(tmp_path):
    frf = _frf(1)
    two_d = FRF(frf.frequency_hz, frf.response[np.newaxis, :], kind=frf.kind)
    write_frf(two_d, tmp_path / "h.h5")
    got = read_frf(tmp_path / "h.h5")
    assert got.response.shape == (1, frf.n_freq) and got == two_d


def test_hdf5_dataset_hint_picks_one_of_several_groups(tmp_path):
    import h5py

    from modal.io.hdf5 import write_frf_group, write_root_attrs

    a, b = _frf(1), _frf(2)
    with h5py.File(tmp_path / "two.h5", "w") as fh:
        write_root_attrs(fh)
        write_frf_group(fh.create_group("frf/a"), a)
        write_frf_group(fh.create_group("frf/b"), b)
    _assert_same(read_frf(tmp_path / "two.h5", dataset="b"), b)


# ----------------------------------------------------------------- UFF 58 / 58b
def _even_frf(n_channels: int, kind: str = "accelerance") -> FRF:
    """An FRF on 2 + 0.25 k Hz: an axis UFF's 6-digit minimum and increment rebuild exactly."""
    frf = _frf(n_channels, kind=kind)
    freq = 2.0 + 0.25 * np.arange(frf.n_freq)
    return FRF(freq, frf.response, kind=kind, response_points=frf.response_points,
               reference_points=frf.reference_points)


@pytest.mark.parametrize("n_channels", [1, 3])
@pytest.mark.parametrize("kind", ["receptance", "mobility", "accelerance"])
def test_uff58_ascii_round_trip(tmp_path, n_channels, kind):
    frf = _even_frf(n_channels, kind)
    write_frf(frf, tmp_path / "h.uff")
    assert sniff_format(tmp_path / "h.uff") == "uff"
    got = read_frf(tmp_path / "h.uff")
    # The ASCII dataset 58 stores double ordinates as Fortran E20.12 fields (pyuff: '%20.11e'),
    # i.e. 12 significant digits: each real and imaginary part is rounded by at most 5e-12 of
    # itself. That is the format's limit, not 1e-12; the axis is rebuilt exactly from min + k*inc.
    _assert_same(got, frf, rtol=5.000001e-12)
    assert np.array_equal(got.frequency_hz, frf.frequency_hz)
    rel = np.abs(got.channels.real - frf.channels.real) / np.abs(frf.channels.real)
    assert rel.max() <= 5.000001e-12


@pytest.mark.parametrize("n_channels", [1, 3])
@pytest.mark.parametrize("axis", ["even", "uneven"])
def test_uff58b_binary_round_trip_is_bit_exact(tmp_path, n_channels, axis):
    frf = _even_frf(n_channels) if axis == "even" else _frf(n_channels)  # linspace: not 6-digit even
    write_frf(frf, tmp_path / "h.uff", format="uff58b")
    assert b"    58b" in (tmp_path / "h.uff").read_bytes()[:20]
    got = read_frf(tmp_path / "h.uff")
    _assert_same(got, frf)  # doubles in the binary records (uneven axis: each x stored as a double)


def test_uff58b_keeps_extreme_values_bit_exact(tmp_path):
    frf = _awkward_frf()
    frf = FRF(frf.frequency_hz, frf.response, kind=frf.kind, response_points=["1+X", "2-RZ"],
              reference_points=["3+Y", "3+Y"])
    write_frf(frf, tmp_path / "x.unv", format="uff58b")
    _assert_same(read_frf(tmp_path / "x.unv"), frf)


def test_uff58_ascii_warns_when_the_axis_cannot_be_kept(tmp_path):
    from modal.errors import ModalWarning

    frf = _frf(1)  # linspace(2, 400, 401): step 0.995, fine; make it uneven with long decimals
    freq = np.sort(np.random.default_rng(3).uniform(1.0, 400.0, frf.n_freq))
    frf = FRF(freq, frf.response, kind="accelerance")
    with pytest.warns(ModalWarning, match="6 significant digits"):
        write_frf(frf, tmp_path / "h.uff")
    got = read_frf(tmp_path / "h.uff")
    np.testing.assert_allclose(got.frequency_hz, freq, rtol=5.000001e-6, atol=0)


def test_uff_without_points_reads_back_without_points(tmp_path):
    frf = _even_frf(2)
    frf = FRF(frf.frequency_hz, frf.response, kind="mobility")
    write_frf(frf, tmp_path / "h.uff", format="uff58b")
    got = read_frf(tmp_path / "h.uff")
    assert got.response_points is None and got.reference_points is None
    assert got.units == "m/s/N"


@pytest.mark.parametrize("node,direction,text", [
    (101, 3, "101+Z"), (7, -5, "7-RY"), (1, 1, "1+X"), (2, -2, "2-Y"), (12, 6, "12+RZ"), (5, 0, "5"),
])
def test_point_id_helpers_are_inverse(node, direction, text):
    from modal.io.uff import format_point, parse_point

    assert format_point(node, direction) == text
    assert parse_point(text) == (node, direction)
    assert parse_point(text.lower()) == (node, direction)


def test_parse_point_refuses_other_ids():
    from modal.io.uff import parse_point

    for bad in ("a", "101+W", "+Z", "101 Z", ""):
        with pytest.raises(ValueError):
            parse_point(bad)


# ----------------------------------------------------------------- MATLAB
@pytest.mark.parametrize("n_channels", [1, 3])
@pytest.mark.parametrize("fmt,signature", [("mat", "mat5"), ("mat73", "mat73")])
def test_mat_round_trip_is_bit_exact(tmp_path, n_channels, fmt, signature):
    frf = _frf(n_channels, kind="mobility")
    write_frf(frf, tmp_path / "h.mat", format=fmt)
    assert sniff_format(tmp_path / "h.mat") == signature
    _assert_same(read_frf(tmp_path / "h.mat"), frf)


@pytest.mark.parametrize("fmt", ["mat", "mat73"])
def test_mat_keeps_extreme_values_and_no_points(tmp_path, fmt):
    frf = _awkward_frf()
    write_frf(frf, tmp_path / "x.mat", format=fmt)
    _assert_same(read_frf(tmp_path / "x.mat"), frf)
    bare = _frf(2, points=False)
    write_frf(bare, tmp_path / "y.mat", format=fmt)
    _assert_same(read_frf(tmp_path / "y.mat"), bare)


def test_mat73_header_is_what_matlab_and_scipy_expect(tmp_path):
    from scipy.io.matlab import matfile_version

    write_frf(_frf(1), tmp_path / "h.mat", format="mat73")
    head = (tmp_path / "h.mat").read_bytes()[:128]
    assert head.startswith(b"MATLAB 7.3 MAT-file") and head[124:128] == b"\x00\x02IM"
    assert matfile_version(str(tmp_path / "h.mat")) == (2, 0)


def test_mat_v5_with_other_names_and_channels_in_rows(tmp_path):
    import scipy.io

    frf = _frf(3)
    scipy.io.savemat(tmp_path / "user.mat", {"w": frf.omega_rad_s[np.newaxis, :], "Hxy": frf.channels,
                                             "note": "from a user"})
    got = read_frf(tmp_path / "user.mat", variables={"frequency": "w", "response": "Hxy"},
                   frequency_axis="rad/s", kind="accelerance")
    np.testing.assert_allclose(got.frequency_hz, frf.frequency_hz, rtol=1e-15)
    assert np.array_equal(got.response, frf.response)
    assert got.kind == "accelerance" and got.response_points is None


def test_mat_v73_written_like_matlab_with_default_names(tmp_path):
    """A v7.3 file made directly with h5py as MATLAB lays it out: f (1 x n), H (n x 2), transposed."""
    import h5py

    frf = _frf(2)
    with h5py.File(tmp_path / "m.mat", "w", userblock_size=512) as fh:
        ds = fh.create_dataset("f", data=frf.frequency_hz[:, np.newaxis])  # MATLAB 1 x n
        ds.attrs["MATLAB_class"] = np.bytes_("double")
        comp = np.empty((2, frf.n_freq), dtype=[("real", "<f8"), ("imag", "<f8")])  # MATLAB n x 2
        comp["real"], comp["imag"] = frf.channels.real, frf.channels.imag
        fh.create_dataset("H", data=comp).attrs["MATLAB_class"] = np.bytes_("double")
    with open(tmp_path / "m.mat", "r+b") as fh:
        fh.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64".ljust(116) + b"\0" * 8 + b"\0\x02IM")
    got = read_frf(tmp_path / "m.mat", kind="accelerance")
    assert np.array_equal(got.frequency_hz, frf.frequency_hz) and np.array_equal(got.response, frf.response)


def test_hdf5_keeps_a_plain_frfs_noise_and_window(tmp_path):
    want = _frf(2)
    want = FRF(want.frequency_hz, want.response, kind=want.kind, response_points=want.response_points,
               reference_points=want.reference_points, noise_std=np.abs(want.response) * 1e-3 + 1e-9,
               exponential_decay_s=0.25)
    write_frf(want, tmp_path / "a.h5")
    got = read_frf(tmp_path / "a.h5")
    assert type(got) is FRF
    assert np.array_equal(got.noise_std, want.noise_std) and got.exponential_decay_s == 0.25


def test_combined_files_keep_their_exponential_window_and_noise(tmp_path):
    # FRFs estimated with an exponential window carry its decay: combining files (a roving hammer's FRFs on one
    # axis) must keep it, or every pole keeps the window's damping (zeta 14.9 % for 9.8 % on a hammer record)
    want = _frf(2)
    noise = np.abs(want.response) * 1e-3 + 1e-9
    for i in range(2):
        part = want.channel(i)
        write_frf(FRF(part.frequency_hz, part.response, kind=part.kind, response_points=part.response_points,
                      reference_points=part.reference_points, noise_std=noise[i], exponential_decay_s=0.25),
                  tmp_path / f"c{i}.h5")
    got = read_frf([tmp_path / "c0.h5", tmp_path / "c1.h5"])
    assert got.exponential_decay_s == 0.25 and np.array_equal(got.noise_std, noise)
    write_frf(want.channel(1), tmp_path / "plain.h5")  # no window: refused, not fitted with one decay for both
    with pytest.raises(FormatError, match=r"plain.h5: estimated with no exponential window where .*c0.h5 has an "
                                          r"exponential window of 0.25 s"):
        read_frf([tmp_path / "c0.h5", tmp_path / "plain.h5"])
