"""The `fit` command on broken files: exit 1 and one line on stderr naming the file (issue 3).

`modal.cli.main` is called in-process (the console script and `python -m modal` call
the same function); `test_cli.py` covers the real subprocess.
"""
import h5py
import numpy as np
import pytest
import scipy.io

from modal import FRF
from modal.cli import main
from modal.io import write_frf
from modal.synthetic import modal_frf

GOOD = "\n".join(["# format: modalbal-frf-csv 1", "# kind: receptance", "frequency_hz,re_0,im_0"]
                 + [f"{f},{1.0 / (1 + f)},0.1" for f in range(1, 40)]) + "\n"


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


CASES = {
    "empty.csv": lambda tmp: "",
    "header_only.csv": lambda tmp: "frequency_hz,re_0,im_0\n",
    "text_in_number.csv": lambda tmp: GOOD.replace("5,", "five,", 1),
    "nan.csv": lambda tmp: GOOD.replace("0.1\n", "nan\n", 1),
    "inf.csv": lambda tmp: GOOD.replace("0.1\n", "inf\n", 1),
    "duplicate.csv": lambda tmp: GOOD.replace("3,", "2,", 1),
    "negative.csv": lambda tmp: GOOD.replace("\n1,", "\n-1,", 1),
    "columns.csv": lambda tmp: GOOD.replace("0.1\n", "0.1,7\n", 1),
    "unknown_kind.csv": lambda tmp: GOOD.replace("receptance", "compliance"),
    "no_kind.csv": lambda tmp: GOOD.replace("# kind: receptance\n", ""),
    "newer_version.csv": lambda tmp: GOOD.replace("modalbal-frf-csv 1", "modalbal-frf-csv 9"),
    "decimal_comma.csv": lambda tmp: "f;re;im\n" + "".join(f"{f},5;{f},25;0,1\n" for f in range(1, 30)),
    "garbage.bin": lambda tmp: bytes(range(256)) * 8,
    "time.uff": lambda tmp: "\n".join(_func_type(_uff(tmp), 1)) + "\n",
    "spectrum.uff": lambda tmp: "\n".join(_func_type(_uff(tmp), 2)) + "\n",
    "truncated.uff": lambda tmp: "\n".join(_uff(tmp)[:14]) + "\n",
    "text_field.uff": lambda tmp: "\n".join(_uff(tmp)[:12] + ["  abc  def  ghi"] + _uff(tmp)[13:]) + "\n",
    "no_end.uff": lambda tmp: "\n".join(_uff(tmp)[:-1]) + "\n",
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_broken_file_gives_one_line_and_exit_1(tmp_path, capsys, name):
    path = tmp_path / name
    content = CASES[name](tmp_path)
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    code = main(["fit", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1, err
    assert len(err) == 1 and err[0].startswith("error: ") and name in err[0], err


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
