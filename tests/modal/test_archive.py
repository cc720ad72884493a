"""The HDF5 archive layer: results written and read back equal, bit for bit; schema checks."""
import h5py
import numpy as np
import pytest

from modal import identify
from modal.archive import SCHEMA, read_archive, units_of, write_archive
from modal.errors import ArchiveError
from modal.synthetic import add_noise, modal_frf


#: two runs of the same arithmetic on another CPU or BLAS build differ in their last digits: the recomputed circle
#: fit's ζ by 1 ulp, the half-power ζ by 7.5e-13 (the crossings' difference loses digits). The errors are central
#: differences over relative steps of 1e-6, which scale that by 1e6: measured 5e-10 (circle) and 1.6e-7
#: (half-power ζ's error) between two machines. A changed algorithm moves the numbers by far more than this
#: relative difference
ROUNDING = 1e-6


def _equal(a, b, rtol=0.0):
    """``a`` and ``b`` of the same types and structure, their numbers equal (within ``rtol`` relative to each
    array's largest |value|, or each number's own)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.dtype != b.dtype or a.shape != b.shape:
            return False
        if rtol == 0 or not np.issubdtype(a.dtype, np.number):
            return np.array_equal(a, b, equal_nan=True)
        scale = np.nanmax(np.abs(a)) if np.any(np.isfinite(a)) else 0.0
        return bool(np.all((np.isnan(a) & np.isnan(b)) | (np.abs(a - b) <= rtol * scale)))
    if hasattr(a, "__dataclass_fields__"):
        return type(a) is type(b) and all(_equal(getattr(a, k), getattr(b, k), rtol) for k in a.__dataclass_fields__)
    if isinstance(a, (tuple, list)):
        return type(a) is type(b) and len(a) == len(b) and all(_equal(x, y, rtol) for x, y in zip(a, b))
    if isinstance(a, dict):
        return type(b) is dict and a.keys() == b.keys() and all(_equal(a[k], b[k], rtol) for k in a)
    if isinstance(a, float) and np.isnan(a):
        return isinstance(b, float) and np.isnan(b)
    if rtol and isinstance(a, (float, complex)) and type(a) is type(b):
        return abs(a - b) <= rtol * abs(a)
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
    assert units_of("rotor_x_m") == "m" and units_of("time_s") == "s" and units_of("damping_ratio") == "1"  # dimensionless


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


def test_an_archive_written_before_classes_moved_still_loads():
    # written by the toolkit before the band-wise algorithms moved into modal/sdof (main at 473933f:
    # circle_fit_curve, half_power_curve and identify(..., "circle") of one mode at 50 Hz, zeta 0.02, mobility,
    # 81 lines 40-60 Hz, add_noise(1e-3, seed=1); a MissingMode(51.5, 0.01, 0, 40.0, 25.0, (0,))): its
    # @__class__ attributes name modal.circlefit, modal.halfpower and modal.checks
    import warnings
    from pathlib import Path

    from modal.archive import RENAMED_CLASSES
    from modal.sdof.checks import MissingMode
    from modal.sdof.circlefit import CircleEstimate, circle_fit_curve
    from modal.sdof.halfpower import HalfPowerEstimate, half_power_curve

    path = Path(__file__).parent / "data" / "archive_before_sdof.h5"
    with h5py.File(path, "r") as f:
        assert {f[name].attrs["__class__"] for name in ("circle", "halfpower", "missing")} <= set(RENAMED_CLASSES)
    back = read_archive(path)
    frf = add_noise(modal_frf(np.linspace(40.0, 60.0, 81), [50.0], [0.02], [1.0], kind="mobility"), 1e-3, seed=1)
    omega, h = frf.omega_rad_s, frf.response
    # the classes load from their new homes, and today's code computes the same numbers, to rounding
    assert type(back["circle"]) is CircleEstimate and _equal(back["circle"], circle_fit_curve(omega, h, 1e-3), ROUNDING)
    assert (type(back["halfpower"]) is HalfPowerEstimate
            and _equal(back["halfpower"], half_power_curve(omega, h, 1, 1e-3), ROUNDING))
    assert back["missing"] == MissingMode(51.5, 0.01, 0, 40.0, 25.0, (0,))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # whatever the flags say, they are the same flags
        again = identify(frf, "circle", driving_point=True)
    # the archived single channel was then assumed to be a driving point (flag driving_point_assumed); a
    # driving point is now known or declared: declared, the numbers are the same, to rounding
    old = back["identify"]
    assert [set(m.flags) - {"driving_point_assumed"} for m in old.modes] == [set(m.flags) for m in again.modes]
    assert all("driving_point_assumed" in m.flags for m in old.modes)
    # that flag described the setting then, as it would now: the modes keep the verdict they were archived with
    assert [m.ok for m in old.modes] == [m.ok for m in again.modes]
    from dataclasses import replace

    def numbers(result):
        # (today's settings also record the budget of the refinement that checks the circle fit, and the
        # evaluations it used: no number of the result)
        settings = {k: v for k, v in result.settings.items() if k not in ("max_evaluations", "evaluations")}
        return replace(result, modes=tuple(replace(m, flags=()) for m in result.modes), settings=settings)

    assert _equal(numbers(old), numbers(again), ROUNDING)


@pytest.mark.parametrize("old", sorted(__import__("modal.archive", fromlist=["RENAMED_CLASSES"]).RENAMED_CLASSES))
def test_every_renamed_class_has_a_home(old):
    from modal.archive import RENAMED_CLASSES, _class_from

    cls = _class_from(old)
    assert f"{cls.__module__}:{cls.__qualname__}" == RENAMED_CLASSES[old]


def test_attributes_stored_as_other_strings_read_alike(tmp_path, result):
    # the reader takes its text attributes (types, units, classes) by h5py's low-level calls where they are one
    # UTF-8 variable-length string, as the toolkit writes them; an archive whose tool stored them otherwise
    # (fixed-length ASCII, variable-length ASCII) must read the same
    path = tmp_path / "a.h5"
    write_archive(path, {"identify": result})
    with h5py.File(path, "r+") as f:
        mode = f["identify/modes/0"]
        mode.attrs["__type__"] = np.bytes_("dataclass")  # fixed-length
        mode.attrs.create("__class__", str(mode.attrs["__class__"]).encode(), dtype=h5py.string_dtype("ascii"))
        f["identify/modes/0/mass_kg"].attrs["units"] = np.bytes_("kg")
    assert _equal(read_archive(path)["identify"], result)
