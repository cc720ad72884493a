"""What a report shows: archives it accepts and refuses, the table of modes and the flags' legend."""
import warnings

import numpy as np
import pytest

import modal
from modal.archive import write_archive
from modal.errors import ArchiveError, ModalError
from modal.flags import FLAG_ACTION
from modal.report.content import flag_legend, mode_rows, report_content
from modal.shapes import mode_shapes


@pytest.fixture(scope="module")
def fitted():
    frf = modal.modal_frf(np.arange(1.0, 200.0, 0.5), [40.0, 90.0], [0.02, 0.01], [[1.0, 0.5], [0.5, -0.8]],
                          kind="accelerance", response_points=["1+Z", "2+Z"], reference_points=["1+Z", "1+Z"])
    frf = modal.add_noise(frf, 0.002, seed=5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = modal.identify(frf, "nls")
    return frf, result


def test_mode_rows_carry_the_results_numbers(fitted):
    frf, result = fitted
    rows = mode_rows(result, mode_shapes(result, frf.response_points, frf.reference_points))
    mode = result[0]
    assert rows[0]["frequency"] == f"{mode.natural_frequency_hz:.6g} ± {mode.std.natural_frequency_hz:.2g}"
    k = float(np.atleast_1d(mode.stiffness_n_per_m)[0])
    assert rows[0]["k"].startswith(f"{k:.5g} ± ") and rows[0]["kcm_channel"] == "1"  # the first channel (counted from 1) is the driving point
    assert float(rows[0]["mpc"]) == pytest.approx(1.0, abs=1e-3)  # real modal constants (noise 0.2 %)


def test_flag_legend_says_what_each_flag_means_and_what_to_do(fitted):
    _, result = fitted
    legend = dict((f, (text, action)) for f, text, action in flag_legend([result]))
    assert "not_driving_point" in legend  # the second channel is a transfer FRF
    assert legend["not_driving_point"][1] == FLAG_ACTION["not_driving_point"]


def test_the_archive_of_a_fit_is_reported(tmp_path, fitted):
    frf, result = fitted
    path = tmp_path / "fit.h5"
    write_archive(path, {"frf": frf, "identify_nls": result, "source_files": ["a.uff"]})
    content = report_content(path)
    glance = dict(content.glance)
    assert glance["file(s)"] == "a.uff" and glance["channels"].startswith("2 (response/reference point: 1+Z/1+Z")
    assert content.shapes[0].points == ("1+Z", "2+Z")
    assert glance["geometry"] == "none: the channels stand on a line in file order"
    assert not any(label.startswith("warning") for label, _ in content.glance)
    # the warnings a fit was given are shown with the results they were given to, once each
    said = ("hits' FRF changes with force level", "takes disagree")
    write_archive(path, {"frf": frf, "identify_nls": result, "identify_circle": result},
                  warnings={"identify_nls": said, "identify_circle": said[:1]})
    rows = [row for row in report_content(path).glance if row[0].startswith("warning")]
    assert rows == [("warning (identify_nls, identify_circle)", said[0]), ("warning (identify_nls)", said[1])]


def test_a_batch_archive_and_an_archive_without_results_are_refused(tmp_path):
    write_archive(tmp_path / "batch.h5", {"batch": {"n_files": 2}})
    with pytest.raises(ArchiveError, match=r"batch\.h5: is a batch archive \(many files\)"):
        report_content(tmp_path / "batch.h5")
    write_archive(tmp_path / "other.h5", {"numbers": np.arange(3.0)})
    with pytest.raises(ArchiveError, match=r"holds no FRF, identification result or scene \(it holds numbers\)"):
        report_content(tmp_path / "other.h5")
    (tmp_path / "text.h5").write_text("not hdf5")
    with pytest.raises(ModalError, match="not a readable HDF5 file"):
        report_content(tmp_path / "text.h5")


def test_a_geometry_without_the_channels_nodes_is_one_line(tmp_path, fitted):
    frf, result = fitted
    write_archive(tmp_path / "fit.h5", {"frf": frf, "identify_nls": result})
    geometry = modal.Geometry([1, 5], [[0, 0, 0], [1, 0, 0]], source="g.csv")
    with pytest.raises(ModalError, match=r"g\.csv: channel 2 \(point '2\+Z'\) stands on node 2"):
        report_content(tmp_path / "fit.h5", geometry)
