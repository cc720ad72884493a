"""Real measured data from data/real (pyuff's measured beam FRFs and a 58b time file)."""
from __future__ import annotations

import numpy as np
import pytest

from modal.errors import FormatError
from modal.io import read_frf, sniff_format, write_frf

BEAM = [f"pyuff_meas_point_{i}.txt" for i in (1, 2, 3)]
TIME = "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff"


@pytest.fixture
def real(real_dir):
    return real_dir


def _beam(real):
    # One complex value per line, no frequency column: the README gives 0..1000 Hz in 1 Hz steps;
    # pyuff's showcase: fixed response at node 1, roving hammer at nodes 1..3.
    return read_frf([real / name for name in BEAM], kind="accelerance", frequency_step=1.0,
                    response_points=["1"] * 3, reference_points=["1", "2", "3"])


def test_beam_files_are_complex_text(real):
    for name in BEAM:
        assert sniff_format(real / name) == "text"
    one = read_frf(real / BEAM[0], kind="accelerance", frequency_step=1.0)
    assert one.n_channels == 1 and one.n_freq == 1001
    want = np.genfromtxt(real / BEAM[0], dtype=complex)
    assert np.array_equal(one.response, want)


def test_three_beam_points_combine_into_three_channels(real):
    frf = _beam(real)
    assert frf.n_channels == 3 and frf.n_freq == 1001 and frf.kind == "accelerance"
    assert np.array_equal(frf.frequency_hz, np.arange(1001.0))
    assert frf.reference_points == ("1", "2", "3") and frf.is_driving_point().tolist() == [True, False, False]
    for ch, name in enumerate(BEAM):
        assert np.array_equal(frf.channels[ch], np.genfromtxt(real / name, dtype=complex))
    total = np.abs(frf.channels).sum(axis=0)
    peaks = [int(np.argmax(np.where(np.abs(frf.frequency_hz - f) < 8, total, 0))) for f in (52, 142, 279, 460, 687)]
    assert peaks == [52, 142, 279, 460, 687]  # the README's peaks of the summed |H| (free-free beam)


def test_beam_needs_kind_and_frequency_lines(real):
    with pytest.raises(FormatError, match=r"pyuff_meas_point_1\.txt.*kind= \(--kind\)"):
        read_frf(real / BEAM[0], frequency_step=1.0)
    with pytest.raises(FormatError,
                       match=r"pyuff_meas_point_1\.txt: the file has no frequency column.*frequency_step="):
        read_frf(real / BEAM[0], kind="accelerance")


@pytest.mark.parametrize("fmt,exact", [("uff58b", True), ("csv", True), ("mat", True), ("mat73", True),
                                       ("hdf5", True), ("uff58", False)])
def test_beam_round_trips_through_every_format(real, tmp_path, fmt, exact):
    frf = _beam(real)
    path = tmp_path / "beam.dat"
    write_frf(frf, path, format=fmt)
    got = read_frf(path)
    assert got.kind == "accelerance" and got.reference_points == frf.reference_points
    assert np.array_equal(got.frequency_hz, frf.frequency_hz)
    if exact:
        assert got.response.tobytes() == frf.response.tobytes()
    else:  # ASCII 58: 12 significant digits per part (E20.12 fields)
        np.testing.assert_allclose(got.response.real, frf.response.real, rtol=5.000001e-12, atol=0)
        np.testing.assert_allclose(got.response.imag, frf.response.imag, rtol=5.000001e-12, atol=0)


def test_binary_58b_time_data_is_refused_as_an_frf(real):
    path = real / TIME
    assert sniff_format(path) == "uff"
    with pytest.raises(FormatError) as info:
        read_frf(path)
    msg = str(info.value)
    assert "\n" not in msg
    assert TIME in msg
    assert "dataset 1 (line 8, record 6, field func_type)" in msg
    assert "function type 1 (time response) is not an FRF" in msg
    assert "expected 4 (frequency response function)" in msg
    with pytest.raises(FormatError, match=r"dataset 3 .*function type 1 \(time response\)"):
        read_frf(path, dataset=3)
    with pytest.raises(FormatError, match="time response"):
        read_frf(path, kind="accelerance")  # a kind hint does not make time data an FRF
