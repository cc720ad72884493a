"""The `fit` command on broken files: exit 1 and one line on stderr naming the file.

`modal.cli.main` is called in-process (the console script and `python -m modal` call
the same function); `test_cli.py` covers the real subprocess.
"""
import json

import h5py
import numpy as np
import pytest
import scipy.io

from modal import FRF
from modal.cli import main
from modal.io import write_frf
from modal.synthetic import modal_frf

# A well-posed one-mode receptance (m = 1 kg, fn = 20 Hz, zeta = 2 %: 8 lines per half-power
# band at 0.1 Hz) that the command fits (exit 0, `test_good_files_fit`); every broken case below
# changes one thing in it, so the failure can only come from that change.
_F = np.round(np.arange(100, 301) * 0.1, 1)
_H = modal_frf(_F, [20.0], [0.02], [1.0]).response
ROWS = [(f"{f:.1f}", f"{h.real:.12e}", f"{h.imag:.12e}") for f, h in zip(_F, _H)]


def _csv(rows=ROWS, head=("# format: modalbal-frf-csv 1", "# kind: receptance", "frequency_hz,re_0,im_0")):
    return "\n".join(list(head) + [",".join(r) for r in rows]) + "\n"


def _row(i, *cells):
    """ROWS with row i replaced by ``cells``."""
    return ROWS[:i] + [tuple(cells)] + ROWS[i + 1:]


GOOD = _csv()


def _uff(tmp_path):
    path = tmp_path / "good.uff"
    write_frf(modal_frf(np.arange(1, 51) * 2.0, [40.0], [0.02], [1.0], kind="accelerance",
                        response_points=["1+Z"], reference_points=["1+Z"]), path)
    return path.read_text().splitlines()


def _func_type(lines, code):
    out = list(lines)
    i = next(k for k, line in enumerate(out) if line.strip() == "58") + 6
    parts = out[i].split()
    out[i] = f"{code:5d}" + out[i][5:] if parts else out[i]
    return out


# name -> (content, the reason the one-line message must give). The reason is the part of the
# message that only this breakage produces, so a reader that stops checking it fails here.
CASES = {
    "empty.csv": (lambda tmp: "", "empty file (0 bytes)"),
    "header_only.csv": (lambda tmp: "frequency_hz,re_0,im_0\n", "only a header or comments, no data lines"),
    "text_in_number.csv": (lambda tmp: _csv(_row(5, "10.5", "five", ROWS[5][2])),
                           "line 9, column 're_0': 'five' is not a number"),
    "nan.csv": (lambda tmp: _csv(_row(5, ROWS[5][0], ROWS[5][1], "nan")),
                "line 9, column 'im_0': value nan is not finite"),
    "inf.csv": (lambda tmp: _csv(_row(5, ROWS[5][0], "-inf", ROWS[5][2])),
                "line 9, column 're_0': value -inf is not finite"),
    "duplicate.csv": (lambda tmp: _csv(_row(5, ROWS[4][0], ROWS[5][1], ROWS[5][2])),
                      "duplicate lines (10.4 Hz)"),
    "negative.csv": (lambda tmp: _csv(_row(0, "-10.0", ROWS[0][1], ROWS[0][2])), "negative value (-10.0)"),
    "columns.csv": (lambda tmp: _csv(_row(5, *ROWS[5], "7")), "line 9: 4 columns; expected 3"),
    "unknown_kind.csv": (lambda tmp: GOOD.replace("# kind: receptance", "# kind: transmissibility"),
                         "unknown FRF kind 'transmissibility'"),
    "no_kind.csv": (lambda tmp: GOOD.replace("# kind: receptance\n", ""), "the FRF kind cannot be determined"),
    "newer_version.csv": (lambda tmp: GOOD.replace("modalbal-frf-csv 1", "modalbal-frf-csv 9"),
                          "version 9 is not supported"),
    "decimal_comma.csv": (lambda tmp: "f;re;im\n" + "".join(f"{f},5;{f},25;0,1\n" for f in range(1, 30)),
                          "'1,5' is not a number (decimal comma? pass decimal=',')"),
    "garbage.bin": (lambda tmp: bytes(range(256)) * 8, "binary content of no known kind"),
    "time.uff": (lambda tmp: "\n".join(_func_type(_uff(tmp), 1)) + "\n", "expected real time samples"),
    "spectrum.uff": (lambda tmp: "\n".join(_func_type(_uff(tmp), 2)) + "\n",
                     "function type 2 (auto spectrum) is not an FRF"),
    "truncated.uff": (lambda tmp: "\n".join(_uff(tmp)[:14]) + "\n", "no complete dataset"),
    "text_field.uff": (lambda tmp: "\n".join(_uff(tmp)[:12] + ["  abc  def  ghi"] + _uff(tmp)[13:]) + "\n",
                       "line 13, record 11, field z_axis_spec_data_type): 'abc  def' is not an integer"),
    "no_end.uff": (lambda tmp: "\n".join(_uff(tmp)[:-1]) + "\n", "no complete dataset"),
}


def test_good_files_fit(tmp_path, capsys):
    """The files every broken case starts from fit: a broken case's exit 1 comes from its breakage."""
    (tmp_path / "good.csv").write_text(GOOD)
    (tmp_path / "good.uff").write_text("\n".join(_uff(tmp_path)) + "\n")
    for name in ("good.csv", "good.uff"):
        assert main(["fit", str(tmp_path / name), "--json"]) == 0, capsys.readouterr().err
        out = capsys.readouterr()
        assert out.err == ""
        doc = json.loads(out.out)
        assert len(doc["modes"]) == 1
        # exact data written with >= 11 significant digits: the fit recovers 20 Hz (CSV) / 40 Hz (UFF)
        # far inside 1e-6 (observed ~1e-15); a reader that garbled the lines would not
        fn = doc["modes"][0]["natural_frequency_hz"]
        assert fn == pytest.approx(20.0 if name.endswith("csv") else 40.0, rel=1e-6)


@pytest.mark.parametrize("name", sorted(CASES))
def test_broken_file_gives_one_line_and_exit_1(tmp_path, capsys, name):
    path = tmp_path / name
    make, reason = CASES[name]
    content = make(tmp_path)
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    code = main(["fit", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1, err
    assert len(err) == 1 and err[0].startswith("error: ") and name in err[0], err
    assert reason in err[0], err


def test_mat_without_the_variables(tmp_path, capsys):
    path = tmp_path / "other.mat"
    scipy.io.savemat(path, {"x": np.arange(3.0)})
    assert main(["fit", str(path)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "other.mat" in err


@pytest.mark.parametrize("schema", ["somebody-else", None])
def test_hdf5_not_ours_or_empty(tmp_path, capsys, schema):
    path = tmp_path / "x.h5"
    with h5py.File(path, "w") as f:
        if schema:
            f.attrs["schema"] = schema
    assert main(["fit", str(path)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "x.h5" in err


def test_directory_and_missing_path(tmp_path, capsys):
    assert main(["fit", str(tmp_path)]) == 1
    assert main(["fit", str(tmp_path / "none.csv")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("error: ") for line in err)


def test_flat_frf_has_no_mode(tmp_path, capsys):
    path = tmp_path / "flat.csv"
    write_frf(FRF(np.linspace(1, 10, 50), np.ones(50)), path)
    assert main(["fit", str(path)]) == 1
    assert "no resonance" in capsys.readouterr().err
