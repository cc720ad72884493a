"""Size, write time and render time of the HTML report (``python -m modal report``).

Run ``python -m benchmarks.bench_report [--runs N]``. Cases: the real beam (data/real, 3 channels, the
issue's limits: under 5 MB, written in under 2 s, rendered in under 3 s), the synthetic plate with its
geometry (12 channels), and a synthetic 1000-channel FRF (what is drawn is decimated, the tables are not).

Columns: file size; the report written in this process (``write_report``: archive read, shapes, HTML),
and by the command line as a user runs it (a subprocess: Python start and imports included); the render
time in headless Chromium from navigation until the report's script has drawn everything. Medians of
``--runs`` interleaved runs (each case's three timings in turn), min-max in brackets, with the load.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import modal
from modal.archive import write_archive
from modal.report import write_report

ROOT = Path(__file__).resolve().parents[1]


def _archives(folder: Path) -> dict[str, Path]:
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        beam = modal.read_frf(sorted((ROOT / "data" / "real").glob("pyuff_meas_point_*.txt")), frequency_step=1.0,
                              kind="accelerance")
        result = modal.identify(beam)
        out["real beam (3 ch)"] = write_archive(folder / "beam.h5", {"frf": beam, f"identify_{result.method}": result})
        plate = modal.read_frf(ROOT / "data" / "synthetic" / "plate_frf.uff")
        result = modal.identify(plate)
        out["plate + geometry (12 ch)"] = write_archive(folder / "plate.h5", {
            "frf": plate, f"identify_{result.method}": result,
            "geometry": modal.read_geometry(ROOT / "data" / "synthetic" / "plate_geometry.uff")})
        rng = np.random.default_rng(0)
        f = 0.5 * np.arange(1, 4001)
        many = modal.add_noise(modal.modal_frf(f, [120.0, 410.0, 800.0, 1300.0, 1750.0], [0.01, 0.015, 0.01, 0.02, 0.01],
                                               rng.normal(size=(1000, 5)), kind="accelerance",
                                               response_points=[f"{k}+Z" for k in range(1, 1001)],
                                               reference_points=["1+Z"] * 1000), 0.002, seed=1)
        result = modal.identify(many, "global")
        out["synthetic (1000 ch x 4000 lines)"] = write_archive(folder / "many.h5",
                                                                {"frf": many, "identify_global": result})
    return out


def _spread(values) -> str:
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args(argv)
    from playwright.sync_api import sync_playwright

    from modal.report.browser import launch, open_report

    with tempfile.TemporaryDirectory(prefix="bench-report-") as tmp:
        folder = Path(tmp)
        cases = _archives(folder)
        times = {name: {"write": [], "cli": [], "render": []} for name in cases}
        sizes = {}
        with sync_playwright() as play:
            browser = launch(play)
            for _ in range(args.runs):
                for name, archive in cases.items():
                    out = archive.with_suffix(".html")
                    start = time.perf_counter()
                    write_report(archive, out)
                    times[name]["write"].append(time.perf_counter() - start)
                    start = time.perf_counter()
                    subprocess.run([sys.executable, "-m", "modal", "report", str(archive), "--out", str(out)],
                                   check=True, capture_output=True)
                    times[name]["cli"].append(time.perf_counter() - start)
                    sizes[name] = out.stat().st_size
                    page, seconds = open_report(browser, out)
                    times[name]["render"].append(seconds)
                    page.close()
            browser.close()
    load = os.getloadavg()
    print(f"HTML report: medians of {args.runs} interleaved runs (min-max), s; load {load[0]:.1f} {load[1]:.1f} "
          f"{load[2]:.1f} on {os.cpu_count()} CPUs")
    print(f"{'case':<34} {'size MB':>8} {'write_report':>18} {'python -m modal report':>24} {'render (Chromium)':>20}")
    for name in cases:
        t = times[name]
        print(f"{name:<34} {sizes[name] / 1e6:>8.3f} {_spread(t['write']):>18} {_spread(t['cli']):>24} "
              f"{_spread(t['render']):>20}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
