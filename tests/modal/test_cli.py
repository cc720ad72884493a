"""The `python -m modal fit` command line, run as users run it (a subprocess)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from modal.io import write_frf
from modal.synthetic import add_noise, modal_frf


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "modal", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=120)


@pytest.fixture(scope="module")
def three_mode_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "three.csv"
    frf = modal_frf(np.linspace(10, 400, 2001), [50.0, 120.0, 300.0], [0.01, 0.02, 0.03], [1.0, 0.5, 2.0],
                    kind="mobility", response_points=["7+Z"], reference_points=["7+Z"])
    write_frf(add_noise(frf, 0.001, seed=1), path)
    return path


def test_table_on_stdout(three_mode_file):
    out = run("fit", three_mode_file)
    assert out.returncode == 0, out.stderr
    assert "f_n [Hz]" in out.stdout and "k [N/m]" in out.stdout
    assert out.stdout.count("\n   ") >= 3  # three mode rows


def test_json_document_keys_and_values(three_mode_file):
    out = run("fit", three_mode_file, "--json", "--method", "all")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    rows = doc["modes"]
    assert {row["method"] for row in rows} == {"nls", "circle", "halfpower"}
    nls = [row for row in rows if row["method"] == "nls"]
    for key in ("natural_frequency_hz", "damping_ratio", "stiffness_n_per_m", "damping_n_s_per_m", "mass_kg",
                "std", "flags", "channel", "method"):
        assert key in nls[0]
    assert set(nls[0]["std"]) >= {"natural_frequency_hz", "damping_ratio", "stiffness_n_per_m", "mass_kg"}
    fns = sorted(row["natural_frequency_hz"] for row in nls)
    # 0.1 % noise: the frequencies are good to ~1e-5; 1e-3 leaves a wide margin
    np.testing.assert_allclose(fns, [50.0, 120.0, 300.0], rtol=1e-3)


def test_bands_and_plot(three_mode_file, tmp_path):
    png = tmp_path / "fit.png"
    out = run("fit", three_mode_file, "--band", "45", "55", "--band", "110", "130", "--json", "--plot", png)
    assert out.returncode == 0, out.stderr
    assert len(json.loads(out.stdout)["modes"]) == 2
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_usage_error_exits_2(three_mode_file):
    assert run("fit", three_mode_file, "--method", "lscf").returncode == 2
    assert run("fit").returncode == 2


@pytest.mark.parametrize(
    "content, expect",
    [
        ("", "empty file (0 bytes)"),
        ("frequency_hz,re,im\n1,2,x\n", "line 2, column 'im': 'x' is not a number"),
        # two lines of words: both read as header text, so no data line is left
        ("not,a\nfrf,file\n", "line 2: only a header or comments, no data lines"),
    ],
)
def test_bad_file_is_one_line_and_exit_1(tmp_path, content, expect):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    out = run("fit", path)
    assert out.returncode == 1
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "bad.csv" in lines[0]
    assert expect in lines[0]
    assert "Traceback" not in out.stderr


def test_missing_file_exit_1(tmp_path):
    out = run("fit", tmp_path / "nope.uff")
    assert out.returncode == 1 and "nope.uff" in out.stderr and "Traceback" not in out.stderr


def test_no_half_written_plot_on_failure(tmp_path):
    path = tmp_path / "flat.csv"
    from modal import FRF

    write_frf(FRF(np.linspace(1, 10, 50), np.ones(50), kind="receptance"), path)
    png = tmp_path / "out.png"
    out = run("fit", path, "--plot", png)
    assert out.returncode == 1 and "no resonance" in out.stderr
    assert not png.exists() and list(tmp_path.glob("*.tmp")) == []


def test_real_beam_files_and_time_data_refused():
    from support.paths import REAL

    real = REAL
    beams = sorted(real.glob("pyuff_meas_point_*.txt"))
    assert len(beams) == 3, "data/real must ship the three beam files"
    out = run("fit", *beams, "--frequency-step", "1", "--kind", "accelerance", "--band", "40", "60", "--json")
    assert out.returncode == 0, out.stderr
    rows = json.loads(out.stdout)["modes"]
    assert {row["channel"] for row in rows} == {1, 2, 3}  # counted from 1
    assert abs(rows[0]["natural_frequency_hz"] / 51.5 - 1) < 1e-3  # LSCF value, 0.1 %
    time_file = real / "pyuff_MPSTD_Set001_2024_10_08_10_27_07.uff"
    refused = run("fit", time_file)
    # time data without a force channel: refused with what it holds and how to name the force
    assert refused.returncode == 1 and "no channel marked as force" in refused.stderr and "--excitation" in refused.stderr


def test_a_budget_of_evaluations_on_the_command_line(three_mode_file):
    # one evaluation cannot take the nls fit to convergence: its modes are flagged work_capped, with the warning
    # naming the budget and the option that lifts it
    capped = run("fit", three_mode_file, "--method", "nls", "--max-evaluations", 1, "--json")
    assert capped.returncode == 0, capped.stderr
    assert all("work_capped" in row["flags"] for row in json.loads(capped.stdout)["modes"])
    assert "stopped at its budget of 1 model evaluations" in capped.stderr and "--max-evaluations N" in capped.stderr
    # the circle fit takes the budget for the refinement that checks it
    circle = run("fit", three_mode_file, "--method", "circle", "--max-evaluations", 1, "--json")
    assert circle.returncode == 0, circle.stderr
    assert all("work_capped" in row["flags"] for row in json.loads(circle.stdout)["modes"])
    assert "circle: the least-squares refinement that checks it stopped at its budget of 1" in circle.stderr
    bad = run("fit", three_mode_file, "--max-evaluations", 0)
    assert bad.returncode == 1 and bad.stderr.startswith("error: ")
    assert "--max-evaluations 0: expected a whole number" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
