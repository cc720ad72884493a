"""One headless Chromium (Debian's, driven by Playwright) for the whole browser suite.

Without Chromium or Playwright the tests skip with one line saying which; in CI (``CI=true``) they fail
instead, so a CI that lost its browser cannot pass by skipping them.
"""
from __future__ import annotations

import os
import warnings

import pytest

from modal.report.browser import chromium_path, launch


def _unavailable(reason: str):
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"{reason}; CI=true, where the browser tests must run (.ci/run installs chromium)")
    pytest.skip(reason)


@pytest.fixture(scope="session")
def browser():
    executable = chromium_path()
    if executable is None:
        _unavailable("no Chromium: install Debian's chromium (apt-get install chromium) to run the browser tests")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _unavailable("no Playwright for Python: pip install -e '.[test]'")
    with sync_playwright() as play:
        chromium = launch(play, executable)
        yield chromium
        chromium.close()


@pytest.fixture(scope="session")
def reports(tmp_path_factory):
    """The real beam's and the synthetic plate's reports (archives written as modal fit writes them)."""
    import modal
    from modal.archive import write_archive
    from modal.report import write_report
    from support.paths import REAL, SYNTHETIC

    folder = tmp_path_factory.mktemp("reports")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)  # real data: flags expected
        beam = modal.read_frf(sorted(REAL.glob("pyuff_meas_point_*.txt")), frequency_step=1.0, kind="accelerance")
        beam_result = modal.identify(beam)
        plate = modal.read_frf(SYNTHETIC / "plate_frf.uff")
        plate_result = modal.identify(plate)
    write_archive(folder / "beam.h5", {"frf": beam, f"identify_{beam_result.method}": beam_result})
    write_archive(folder / "plate.h5", {"frf": plate, f"identify_{plate_result.method}": plate_result,
                                        "geometry": modal.read_geometry(SYNTHETIC / "plate_geometry.uff")})
    return {"beam": write_report(folder / "beam.h5", folder / "beam.html"),
            "plate": write_report(folder / "plate.h5", folder / "plate.html")}
