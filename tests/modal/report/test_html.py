"""The HTML report as a file: sections, self-contained, the size the issue allows (the browser opens it in
tests/browser)."""
import re
import warnings

import numpy as np
import pytest

import modal
from modal.archive import write_archive
from modal.report import write_report
from modal.report.html import SECTIONS


@pytest.fixture(scope="module")
def beam_archive(tmp_path_factory):
    from support.paths import REAL

    paths = sorted(REAL.glob("pyuff_meas_point_*.txt"))
    frf = modal.read_frf(paths, frequency_step=1.0, kind="accelerance")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)  # real data: flags expected
        result = modal.identify(frf, "global")
    path = tmp_path_factory.mktemp("beam") / "beam.h5"
    write_archive(path, {"frf": frf, "identify_global": result})
    return path, result


def test_real_beam_report_is_self_contained_small_and_complete(beam_archive, tmp_path):
    path, result = beam_archive
    out = write_report(path, tmp_path / "beam.html")
    text = out.read_text(encoding="utf-8")
    assert out.stat().st_size < 5e6  # the limit for the real beam
    for key, _ in SECTIONS[:-1]:  # every section but the scene's
        assert f'<section id="{key}">' in text
    assert "scene" not in re.findall(r'<section id="(\w+)"', text)
    # nothing outside the file: no src/href to another place, and a policy that forbids any request
    assert not re.search(r'(src|href)="(?!#|data:)', text)
    assert "default-src 'none'" in text
    for mode in result:  # every mode's frequency in the table, as the table formats it
        assert f"{mode.natural_frequency_hz:.6g} ± {mode.std.natural_frequency_hz:.2g}" in text


def test_many_channels_decimate_the_drawing_not_the_table(tmp_path):
    f = np.arange(1.0, 301.0)
    fn = [50.0, 120.0, 250.0]
    rng = np.random.default_rng(4)
    const = rng.normal(size=(400, 3))
    frf = modal.modal_frf(f, fn, [0.02, 0.02, 0.02], const, response_points=[f"{k}+Z" for k in range(1, 401)],
                          reference_points=["1+Z"] * 400)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        result = modal.identify(frf, "global")
    write_archive(tmp_path / "many.h5", {"frf": frf, "identify_global": result})
    text = write_report(tmp_path / "many.h5", tmp_path / "many.html").read_text(encoding="utf-8")
    assert "32 of 400 channels offered" in text
    for mode in result:
        assert f"{mode.natural_frequency_hz:.6g} ± " in text
    # the shape still has all 400 entries: drawn on their nodes, never dropped
    assert text.count('"channel ') < 50 and '"400+Z"' in text
