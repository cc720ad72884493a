"""Make the report screenshots in docs/ from the real browser (headless Chromium driven by Playwright).

Run ``python docs/make_screenshots.py`` from the project folder (needs Debian's ``chromium`` and the
``test`` extra). It fits the real beam (data/real) and the synthetic plate with its UFF 15/82 geometry
(data/synthetic) as ``python -m modal fit --archive`` does, writes their reports with
``python -m modal report`` and saves:

* ``docs/report_beam.png``: the top of the real beam's report (the test at a glance, the modes and their
  flags, the FRFs with the fitted model);
* ``docs/report_plate.png``: the plate's mode shapes section, mode 4 on the geometry.
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _run(*args) -> None:
    # paths relative to the project folder, as the README's commands give them (the report shows them)
    subprocess.run([sys.executable, "-m", "modal", *map(str, args)], check=True, cwd=ROOT, capture_output=True)


def main() -> list[Path]:
    from playwright.sync_api import sync_playwright

    from modal.report.browser import launch, open_report

    with tempfile.TemporaryDirectory(prefix="modalbal-shots-") as tmp:
        folder = Path(tmp)
        beams = sorted(p.relative_to(ROOT) for p in (ROOT / "data" / "real").glob("pyuff_meas_point_*.txt"))
        _run("fit", *beams, "--frequency-step", "1", "--kind", "accelerance", "--archive", folder / "beam.h5")
        _run("report", folder / "beam.h5", "--out", folder / "beam.html")
        _run("fit", "data/synthetic/plate_frf.uff", "--archive", folder / "plate.h5",
             "--geometry", "data/synthetic/plate_geometry.uff")
        _run("report", folder / "plate.h5", "--out", folder / "plate.html")
        written = []
        with sync_playwright() as play:
            browser = launch(play)
            page, _ = open_report(browser, folder / "beam.html", width=1100, height=1400)
            target = DOCS / "report_beam.png"
            page.screenshot(path=str(target))
            written.append(target)
            page.close()
            page, _ = open_report(browser, folder / "plate.html", width=1100, height=900)
            page.click("#shape-play")  # pause at the start of the cycle: largest deflection of a real mode
            page.select_option("#shape-mode", "3")
            target = DOCS / "report_plate.png"
            page.locator("section#shapes").screenshot(path=str(target))
            written.append(target)
            page.close()
            browser.close()
    return written


if __name__ == "__main__":
    for path in main():
        print(path)
