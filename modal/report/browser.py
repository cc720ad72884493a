"""Opening a report in headless Chromium: Debian's browser driven by Playwright for Python.

Used by the browser tests (``tests/browser``), ``docs/make_screenshots.py`` and
``benchmarks/bench_report.py``; the report itself needs no browser to be written. Playwright's own
browser download is not used: :func:`chromium_path` finds Debian's ``chromium``.
"""
from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

__all__ = ["CHROMIUM_ARGS", "chromium_path", "launch", "open_report"]

#: flags for a headless Chromium run as root on a machine without network: no sandbox, and none of the
#: browser's own background requests (a report makes no request, and the tests check that none is made)
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-default-apps", "--mute-audio"]


def chromium_path() -> str | None:
    """The Chromium to drive: ``$CHROMIUM`` when set (and only it), else Debian's; None when there is none."""
    if os.environ.get("CHROMIUM"):
        return os.environ["CHROMIUM"] if Path(os.environ["CHROMIUM"]).is_file() else None
    for name in ("/usr/bin/chromium", shutil.which("chromium"), shutil.which("chromium-browser")):
        if name and Path(name).is_file():
            return name
    return None


def launch(playwright, executable: str | None = None):
    """A headless Chromium browser from a started ``sync_playwright()``."""
    executable = executable or chromium_path()
    if executable is None:
        raise FileNotFoundError("no Chromium: install Debian's chromium (apt-get install chromium)")
    return playwright.chromium.launch(executable_path=executable, headless=True, args=CHROMIUM_ARGS)


def open_report(browser, path: str | os.PathLike, width: int = 1280, height: int = 900, timeout_s: float = 10.0):
    """Open a report in a new page and wait until its script has drawn everything.

    Returns
    -------
    (page, seconds)
        The page and the time from navigation to the report's ``ready`` flag, s.
    """
    page = browser.new_page(viewport={"width": width, "height": height})
    start = time.perf_counter()
    page.goto(Path(path).resolve().as_uri())
    wait_until(page, "window.modalReport && window.modalReport.ready", timeout_s)
    return page, time.perf_counter() - start


def wait_until(page, expression: str, timeout_s: float = 5.0) -> None:
    """Poll a JavaScript expression until it is true (the report's policy forbids the eval behind
    Playwright's ``wait_for_function``)."""
    end = time.monotonic() + timeout_s
    while not page.evaluate(expression):
        if time.monotonic() > end:
            raise TimeoutError(f"{expression} still false after {timeout_s} s")
        page.wait_for_timeout(10)
