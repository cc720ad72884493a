"""The HDF5 archive layer: results written and read back equal, bit for bit; schema checks."""
import h5py
import numpy as np
import pytest

from modal import identify
from modal.archive import SCHEMA, read_archive, units_of, write_archive
from modal.errors import ArchiveError
from modal.synthetic import add_noise, modal_frf


def _equal(a, b):
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True) and np.asarray(a).dtype == np.asarray(b).dtype
    if hasattr(a, "__dataclass_fields__"):
        return type(a) is type(b) and all(_equal(getattr(a, k), getattr(b, k)) for k in a.__dataclass_fields__)
    if isinstance(a, (tuple, list)):
        return type(a) is type(b) and len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, dict):
        return type(b) is dict and a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, float) and np.isnan(a):
        return isinstance(b, float) and np.isnan(b)
    return type(a) is type(b) and a == b


@pytest.fixture(scope="module")
def result():
    frf = add_noise(modal_frf(np.linspace(10, 400, 2001), [50.0, 120.0], [0.01, 0.02],
                              np.array([[1.0, 0.5], [0.2, -0.3]]), response_points=["1", "2"],
                              reference_points="1"), 0.001, seed=3)
    return identify(frf)


def test_identification_round_trip_bit_exact(tmp_path, result):
    path = tmp_path / "a.h5"
    extra = {"none": None, "flag": True, "text": "ü-ok", "pair": (1.5, 2), "table": {"a/b": np.arange(3)}}
    write_archive(path, {"identify": result, **extra}, scene_text="[frf]\nfile = 'x'\n", inputs_hash={"identify": "abc"})
    back = read_archive(path)
    assert _equal(back["identify"], result)
    for key, value in extra.items():
        assert _equal(back[key], value), key
    assert back.scene_text == "[frf]\nfile = 'x'\n"
    assert back.inputs_hash == {"identify": "abc"}
    assert back.attrs["schema"] == SCHEMA and back.attrs["created"].endswith("Z")


def test_creation_time_written_once(tmp_path, result):
    # an overwritten variable-length string keeps its old bytes in the global heap: the
    # archive once held two timestamps, and two runs a second apart differed in the stale one
    import re

    path = tmp_path / "a.h5"
    write_archive(path, {"identify": result})
    stamps = re.findall(rb"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d", path.read_bytes())
    assert len(stamps) == 1


def test_units_attributes(tmp_path, result):
    path = tmp_path / "a.h5"
    write_archive(path, {"identify": result})
    with h5py.File(path) as f:
        mode = f["identify/modes/0"]
        assert mode["natural_frequency_hz"].attrs["units"] == "Hz"
        assert mode["stiffness_n_per_m"].attrs["units"] == "N/m"
        assert mode["damping_n_s_per_m"].attrs["units"] == "N s/m"
        assert mode["mass_kg"].attrs["units"] == "kg"
    assert units_of("rotor_x_m") == "m" and units_of("time_s") == "s" and units_of("damping_ratio") == "1"  # dimensionless (issue 20)


def test_unknown_major_version_is_refused(tmp_path, result):
    path = tmp_path / "a.h5"
    write_archive(path, {"identify": result})
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = "2.0"
    with pytest.raises(ArchiveError, match="schema_version.*'2.0'"):
        read_archive(path)


def test_foreign_and_missing_files(tmp_path):
    with pytest.raises(ArchiveError, match="no such archive"):
        read_archive(tmp_path / "none.h5")
    (tmp_path / "text.h5").write_text("hello")
    with pytest.raises(ArchiveError, match="not a readable HDF5"):
        read_archive(tmp_path / "text.h5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f.attrs["schema"] = "something-else"
    with pytest.raises(ArchiveError, match="not an archive of this toolkit"):
        read_archive(tmp_path / "other.h5")


def test_failed_write_leaves_previous_archive(tmp_path, result):
    path = tmp_path / "a.h5"
    write_archive(path, {"identify": result})
    before = path.read_bytes()
    with pytest.raises(ArchiveError, match="cannot store"):
        write_archive(path, {"identify": result, "bad": object()})
    assert path.read_bytes() == before
    assert list(tmp_path.glob("*.tmp")) == []
