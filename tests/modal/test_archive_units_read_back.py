"""Archives read back: a result's numbers are read only in the units the toolkit wrote them in, and a result missing
a field is named.

An archive written by another tool under the same group names, or edited by hand (masses in g, frequencies in
rad/s, no units at all), used to be read as if in SI and reported with exit 0.
"""
import re
import subprocess
import sys

import h5py
import numpy as np
import pytest

from modal import identify
from modal.archive import read_archive, write_archive
from modal.errors import ArchiveError
from modal.synthetic import add_noise, modal_frf

from support.cli import run_module


@pytest.fixture(scope="module")
def archive(tmp_path_factory):
    frf = add_noise(modal_frf(np.linspace(10, 400, 801), [50.0, 120.0], [0.01, 0.02], np.array([[1.0, 0.5]]),
                              response_points=["1"], reference_points="1"), 0.001, seed=3)
    path = tmp_path_factory.mktemp("archive") / "fit.h5"
    write_archive(path, {"frf": frf, "identify_nls": identify(frf)})
    return path


def _edited(archive, tmp_path, field, unit):
    path = tmp_path / "edited.h5"
    path.write_bytes(archive.read_bytes())
    with h5py.File(path, "r+") as f:
        node = f[f"identify_nls/modes/0/{field}"]
        if unit is None:
            del node.attrs["units"]
        else:
            node.attrs["units"] = unit
    return path


def test_the_toolkits_own_archive_reads_back(archive):
    assert read_archive(archive)["identify_nls"].modes[0].natural_frequency_hz == pytest.approx(50.0, abs=0.1)


@pytest.mark.parametrize("field, unit, said", [
    ("mass_kg", "g", "has units 'g'; expected 'kg'"),
    ("natural_frequency_hz", "rad/s", "has units 'rad/s'; expected 'Hz'"),
    ("std/stiffness_n_per_m", None, "has no units attribute; expected 'N/m'"),
])
def test_a_number_in_another_unit_or_none_is_refused_naming_the_field(archive, tmp_path, field, unit, said):
    path = _edited(archive, tmp_path, field, unit)
    with pytest.raises(ArchiveError) as err:
        read_archive(path)
    assert f"/identify_nls/modes/0/{field} {said}" in str(err.value) and str(path) in str(err.value)


def test_modal_report_on_an_archive_in_grams_is_one_line_and_exit_1(archive, tmp_path):
    path = _edited(archive, tmp_path, "mass_kg", "g")
    out = subprocess.run([sys.executable, "-m", "modal", "report", str(path), "--out", str(tmp_path / "r.html")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 1 and out.stderr.count("\n") == 1 and out.stderr.startswith("error: "), out.stderr
    assert "mass_kg has units 'g'; expected 'kg'" in out.stderr
    assert not (tmp_path / "r.html").exists()


def test_a_result_missing_a_field_is_one_line_naming_it(archive, tmp_path):
    # a group of another tool's (or an edited archive) without mass_kg: modal report ended in a TypeError traceback
    path = tmp_path / "lacking.h5"
    path.write_bytes(archive.read_bytes())
    with h5py.File(path, "r+") as f:
        del f["identify_nls/modes/0/mass_kg"]
    out = run_module("modal", "report", path, "--out", tmp_path / "r.html")  # the grams test runs the process
    assert out.returncode == 1 and out.stderr.count("\n") == 1, out.stderr
    assert "/identify_nls/modes/0 (ModeResult) has no field mass_kg" in out.stderr


@pytest.mark.parametrize("data, said", [
    (np.array([b"1.0", b"2.0"]), "/identify_nls/modes/0/mass_kg holds data of type |S3; expected numbers"),
    (np.arange(3.0), None),
])
def test_a_field_holding_text_or_the_wrong_shape_is_refused(archive, tmp_path, data, said):
    # masses stored as text were reported as if numbers (exit 0); a frequency stored as an array ended in a
    # TypeError traceback
    path = tmp_path / "odd.h5"
    path.write_bytes(archive.read_bytes())
    field = "mass_kg" if said else "natural_frequency_hz"
    with h5py.File(path, "r+") as f:
        group = f["identify_nls/modes/0"]
        attrs = dict(group[field].attrs)
        del group[field]
        group.create_dataset(field, data=data).attrs.update(attrs)
    said = said or "/identify_nls/modes/0/natural_frequency_hz holds an array of shape (3,); expected one number"
    with pytest.raises(ArchiveError, match=re.escape(said)):
        read_archive(path)


def test_a_mass_per_length_is_labelled_kg_per_m():
    from modal.archive import units_of

    # the belt's centrifugal factor (kg/m) was archived as '1/m' (the '_per_m' suffix alone)
    assert units_of("centrifugal_factor_kg_per_m") == "kg/m" and units_of("stiffness_n_per_m") == "N/m"
