"""The HTML reports opened in headless Chromium, as a person opens them: no error, no request, every section,
a mode selector that changes the shape, an animation that moves, and something drawn."""
from __future__ import annotations

import io

import numpy as np
import pytest

from modal.report.html import SECTIONS

pytestmark = pytest.mark.browser


class Opened:
    """A report open in a page, with what the page logged and asked for."""

    def __init__(self, browser, path):
        self.url = path.resolve().as_uri()
        self.page = browser.new_page(viewport={"width": 1280, "height": 900})
        self.errors, self.requests = [], []
        self.page.on("console", lambda m: self.errors.append(f"console {m.type}: {m.text}")
                     if m.type in ("error", "warning") else None)
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))
        self.page.on("request", lambda r: self.requests.append(r.url) if r.url != self.url else None)
        self.page.goto(self.url)
        self.wait_until("window.modalReport && window.modalReport.ready", timeout_s=10)

    def wait_until(self, expression: str, timeout_s: float = 5) -> None:
        from modal.report.browser import wait_until

        wait_until(self.page, expression, timeout_s)

    def canvas(self, element_id: str) -> str:
        return self.page.evaluate(f"document.getElementById('{element_id}').toDataURL()")

    def close(self):
        self.page.close()


@pytest.fixture(params=["beam", "plate"])
def opened(request, browser, reports):
    page = Opened(browser, reports[request.param])
    yield page
    page.close()


def test_opens_without_errors_or_requests_and_shows_every_section(opened):
    page = opened.page
    for key, title in SECTIONS:
        if key == "scene":
            assert page.locator("section#scene").count() == 0  # not a scene archive
            continue
        assert page.locator(f"section#{key} h2").inner_text() == title
    assert page.locator("#modes table tbody tr").count() >= 5  # five modes at least, on both structures
    assert page.locator("#frf-channel option").count() >= 2
    assert opened.errors == [] and opened.requests == []


def test_the_mode_selector_changes_the_shape_shown(opened):
    page = opened.page
    page.click("#shape-play")  # pause: the picture changes only with the mode
    opened.wait_until("!window.modalReport.playing")
    page.select_option("#shape-mode", "0")
    first, info = opened.canvas("shape-canvas"), page.inner_text("#shape-info")
    page.select_option("#shape-mode", "1")
    assert page.evaluate("window.modalReport.mode") == 1
    assert opened.canvas("shape-canvas") != first and page.inner_text("#shape-info") != info
    assert opened.errors == []


def test_a_mode_chosen_while_paused_is_shown_at_its_largest_deflection(opened):
    page = opened.page
    page.click("#shape-play")
    opened.wait_until("!window.modalReport.playing")
    page.select_option("#shape-mode", "1")
    # phase 0 draws the normalised shape's real part, its largest deflection: a paused picture
    # taken for a slide never shows the structure caught at rest mid-cycle
    opened.wait_until("window.modalReport.phase === 0")
    assert opened.errors == []


def test_the_animation_advances(opened):
    page = opened.page
    frames, picture = page.evaluate("window.modalReport.frames"), opened.canvas("shape-canvas")
    # the phase follows the clock (a cycle in 1.5 s): two pictures a half cycle apart, each caught as a real
    # shape passes through rest, are the same, so a loaded machine's slow frames can land on that; three
    # pictures later in the animation cannot all do so
    later = []
    for step in (5, 10, 15):
        opened.wait_until(f"window.modalReport.frames > {frames} + {step}")
        later.append(opened.canvas("shape-canvas"))
    assert any(p != picture for p in later)


def test_zoom_on_the_frf_narrows_the_axis(opened):
    page = opened.page
    page.locator("#frf-mag").scroll_into_view_if_needed()
    box = page.locator("#frf-mag").bounding_box()
    before = opened.canvas("frf-mag")
    y = box["y"] + box["height"] / 2
    page.mouse.move(box["x"] + box["width"] * 0.3, y)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.5, y, steps=4)
    page.mouse.up()
    zoomed = opened.canvas("frf-mag")
    assert zoomed != before
    page.dblclick("#frf-mag")
    assert opened.canvas("frf-mag") == before  # double-click: back to the whole band


def test_a_screenshot_is_not_blank(opened):
    from PIL import Image

    picture = np.asarray(Image.open(io.BytesIO(opened.page.screenshot(full_page=True))).convert("L"), float)
    # a blank page is one colour; the report's plots, tables and text give many grey levels and contrast
    assert picture.std() > 20 and np.unique(picture.astype(int)).size > 50
    shape = opened.page.locator("#shape-canvas").screenshot()
    drawn = np.asarray(Image.open(io.BytesIO(shape)).convert("L"), float)
    assert (drawn < 200).mean() > 0.002  # the structure's lines on the white canvas
