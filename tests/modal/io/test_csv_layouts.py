"""The common CSV/text layouts users bring (not our canonical CSV)."""
from __future__ import annotations

import numpy as np
import pytest

from modal.errors import FormatError
from modal.io import read_frf
from modal.units import TWO_PI

F = np.array([10.0, 20.0, 30.0, 40.0])
H = np.array([[1 + 2j, -0.5 + 0.25j, 3 - 1j, -2 - 2j], [0.1 - 0.2j, 0.3 + 0j, -0.25 + 1j, 2 + 0.5j]])


def _table(columns, delimiter=",", header=None, decimal="."):
    rows = []
    if header:
        rows.append(delimiter.join(header))
    for row in np.column_stack(columns):
        text = delimiter.join(repr(float(v)) for v in row)
        rows.append(text.replace(".", ",") if decimal == "," else text)
    return "\n".join(rows) + "\n"


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_re_im_with_header_two_channels(tmp_path):
    text = _table([F, H[0].real, H[0].imag, H[1].real, H[1].imag],
                  header=["Frequency (Hz)", "Re H1", "Im H1", "Re H2", "Im H2"])
    frf = read_frf(_write(tmp_path, "a.csv", text), kind="mobility")
    assert frf.n_channels == 2 and np.array_equal(frf.response, H) and np.array_equal(frf.frequency_hz, F)


def test_mag_phase_degrees(tmp_path):
    text = _table([F, np.abs(H[0]), np.degrees(np.angle(H[0]))], header=["freq", "magnitude", "phase [deg]"])
    frf = read_frf(_write(tmp_path, "m.csv", text), kind="receptance")
    np.testing.assert_allclose(frf.response, H[0], rtol=1e-14, atol=1e-15)


def test_mag_phase_radians_from_header(tmp_path):
    text = _table([F, np.abs(H[0]), np.angle(H[0])], header=["f", "|H|", "phase (rad)"])
    frf = read_frf(_write(tmp_path, "r.csv", text), kind="receptance")
    np.testing.assert_allclose(frf.response, H[0], rtol=1e-14, atol=1e-15)


def test_db_phase_semicolon_two_channels(tmp_path):
    db = 20 * np.log10(np.abs(H))
    deg = np.degrees(np.angle(H))
    text = _table([F, db[0], deg[0], db[1], deg[1]], delimiter=";",
                  header=["f", "H1 dB", "H1 phase", "H2 dB", "H2 phase"])
    frf = read_frf(_write(tmp_path, "d.csv", text), kind="accelerance")
    np.testing.assert_allclose(frf.response, H, rtol=1e-13, atol=1e-15)


def test_tab_delimited_decimal_comma_with_layout_hint(tmp_path):
    text = _table([F, H[0].real, H[0].imag], delimiter="\t", decimal=",")
    frf = read_frf(_write(tmp_path, "t.txt", text), kind="mobility", layout="re_im", decimal=",")
    assert np.array_equal(frf.response, H[0])


def test_whitespace_with_comments_and_layout_hint(tmp_path):
    text = "# exported by some analyser\n" + _table([F, H[0].real, H[0].imag], delimiter="   ")
    frf = read_frf(_write(tmp_path, "w.txt", text), kind="mobility", layout="re_im")
    assert np.array_equal(frf.response, H[0])


@pytest.mark.parametrize("unit,factor", [("rad/s", TWO_PI), ("cpm", 60.0), ("rpm", 60.0), ("kHz", 1e-3)])
def test_frequency_column_units(tmp_path, unit, factor):
    text = _table([F * factor, H[0].real, H[0].imag], header=[f"frequency [{unit}]", "real", "imag"])
    frf = read_frf(_write(tmp_path, "u.csv", text), kind="mobility")
    np.testing.assert_allclose(frf.frequency_hz, F, rtol=1e-15)
    plain = _table([F * factor, H[0].real, H[0].imag], header=["x", "re", "im"])
    frf = read_frf(_write(tmp_path, "p.csv", plain), kind="mobility", frequency_axis=unit)
    np.testing.assert_allclose(frf.frequency_hz, F, rtol=1e-15)


def test_complex_text_with_frequency_column(tmp_path):
    lines = [f"{float(f)!r} {complex(h)!r} {complex(g)!r}" for f, h, g in zip(F, H[0], H[1])]
    frf = read_frf(_write(tmp_path, "c.txt", "\n".join(lines)), kind="receptance")
    assert frf.n_channels == 2 and np.array_equal(frf.response, H)


def test_complex_text_with_frequency_hints(tmp_path):
    text = "\n".join(repr(complex(h)) for h in H[0])
    path = _write(tmp_path, "c1.txt", text)
    frf = read_frf(path, kind="receptance", frequency_start=10.0, frequency_step=10.0)
    assert np.array_equal(frf.frequency_hz, F)
    frf = read_frf(path, kind="receptance", frequency_hz=F * TWO_PI)
    assert np.array_equal(frf.frequency_hz, F * TWO_PI)
    frf = read_frf(path, kind="receptance", frequency_start=10.0 * TWO_PI, frequency_step=10.0 * TWO_PI,
                   frequency_axis="rad/s")
    np.testing.assert_allclose(frf.frequency_hz, F, rtol=1e-15)


def test_kind_aliases_and_units_hint(tmp_path):
    text = "# kind: inertance\n" + _table([F, H[0].real, H[0].imag], header=["f", "re", "im"])
    frf = read_frf(_write(tmp_path, "k.csv", text), units="g/N")
    # g/N is converted to the kind's SI unit (1 g = 9.80665 m/s^2, exactly by definition)
    assert frf.kind == "accelerance" and frf.units == "m/s^2/N"
    np.testing.assert_allclose(frf.response, 9.80665 * H[0], rtol=1e-15)


def test_a_file_cut_short_in_its_last_line_says_so(tmp_path):
    text = _table([F, H[0].real, H[0].imag], header=["f", "re", "im"])
    cut = text.rstrip("\n").rpartition(",")[0] + "\n"  # the last row loses its last column
    with pytest.raises(FormatError, match=r"2 columns \(the last line: is the file cut short\?\); expected 3"):
        read_frf(_write(tmp_path, "cut.csv", cut), kind="mobility")


def test_trailing_delimiter_and_utf16(tmp_path):
    text = _table([F, H[0].real, H[0].imag], delimiter=";", header=["f", "re", "im"])
    text = "\n".join(ln + ";" for ln in text.splitlines()) + "\n"
    frf = read_frf(_write(tmp_path, "x.csv", text), kind="mobility")
    assert np.array_equal(frf.response, H[0])
    path = tmp_path / "u16.csv"
    path.write_bytes(text.encode("utf-16"))
    assert np.array_equal(read_frf(path, kind="mobility").response, H[0])


def test_a_layout_that_contradicts_the_header_is_refused(tmp_path):
    # the header states the phase in degrees and the magnitude in dB: a layout saying otherwise is a mistake
    # (read as given it would turn every phase by 57x or take dB for magnitudes: a plausible, wrong fit)
    mag, deg = np.abs(H[0]), np.rad2deg(np.angle(H[0]))
    path = _write(tmp_path, "m.csv", _table([F, mag, deg], header=["f [Hz]", "Magnitude", "Phase (deg)"]))
    for layout in ("mag_rad", "re_im", "db_deg"):
        if layout == "db_deg":  # a magnitude column not marked dB may hold dB: not a contradiction
            assert np.allclose(np.abs(read_frf(path, layout=layout, kind="receptance").response), 10 ** (mag / 20))
            continue
        with pytest.raises(FormatError, match=rf"layout='{layout}' but the header names the columns 'Magnitude', "
                                              r"'Phase \(deg\)' \(mag_deg\)"):
            read_frf(path, layout=layout, kind="receptance")
    db = _write(tmp_path, "d.csv", _table([F, 20 * np.log10(mag), deg], header=["f", "Magnitude (dB)", "Phase (deg)"]))
    with pytest.raises(FormatError, match=r"header names the columns 'Magnitude \(dB\)'"):
        read_frf(db, layout="mag_deg", kind="receptance")


def test_negative_magnitudes_are_refused_as_probably_db(tmp_path):
    path = _write(tmp_path, "d.csv", _table([F, 20 * np.log10(np.abs(H[0]) / 10), np.rad2deg(np.angle(H[0]))]))
    with pytest.raises(FormatError, match=r"d.csv: column 2: negative magnitude .* in data row 1 \(layout mag_deg\); "
                                          r"expected magnitudes >= 0 \(in dB\?"):
        read_frf(path, layout="mag_deg", kind="receptance")


def test_a_degree_phase_within_pi_warns_of_radians(tmp_path):
    # an FRF's phase turns by 180 degrees at every mode: a column "in degrees" that stays within ±3.14 over 20 lines
    # or more holds radians
    from modal.errors import QualityWarning
    from modal.synthetic import modal_frf

    f = np.linspace(1.0, 200.0, 40)
    h = modal_frf(f, [80.0], [0.02], [1.0], kind="accelerance").response
    path = _write(tmp_path, "r.csv", _table([f, np.abs(h), np.angle(h)]))
    with pytest.warns(QualityWarning, match=r"r.csv: the phase column in degrees span only .* radians\?"):
        read_frf(path, layout="mag_deg", kind="accelerance")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", QualityWarning)  # the same phase in degrees: no warning
        read_frf(_write(tmp_path, "d.csv", _table([f, np.abs(h), np.rad2deg(np.angle(h))])), layout="mag_deg",
                 kind="accelerance")
