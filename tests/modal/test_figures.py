"""Figures drawn cheaply: fixed margins instead of a layout engine, log labels without
mathtext; nothing may overlap or fall off the figure because of it."""
from __future__ import annotations

from pathlib import Path

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.ticker import LogFormatterSciNotation

from modal.figures import PlainLogFormatter, margins

from support.paths import ROOT  # noqa: E402
DEMO = ROOT / "data" / "synthetic" / "demo_scene.toml"


@pytest.mark.parametrize("low, high, value, text", [(1e-4, 1e13, 1e-3, "10⁻³"), (1e-4, 1e13, 1.0, "10⁰"),
                                                     (1e-4, 1e13, 1e12, "10¹²"), (1e-3, 1e-2, 2e-3, "2×10⁻³"),
                                                     (1e4, 3e4, 2e4, "2×10⁴")])
def test_plain_log_labels_say_what_mathtext_said(low, high, value, text):
    from matplotlib.figure import Figure

    ax = Figure().add_subplot()
    ax.set_yscale("log")
    ax.set_ylim(low, high)
    labels = []
    for formatter in (PlainLogFormatter(labelOnlyBase=False), LogFormatterSciNotation(labelOnlyBase=False)):
        formatter.set_axis(ax.yaxis)
        formatter.set_locs([value])
        labels.append(formatter(value))
    plain, math = labels
    assert plain == text and "$" not in plain
    # mathtext said the same: e.g. $\mathdefault{2\times10^{-3}}$
    mantissa, _, exponent = text.translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")).partition("10")
    assert math == r"$\mathdefault{" + mantissa.replace("×", r"\times") + "10^{" + exponent + "}}$"


def test_margins_in_inches():
    frame = margins(10.0, 5.0, left=1.0, right=0.5, bottom=0.5, top=0.25, wgap=1.0, hgap=0.5, ncols=2, nrows=2)
    assert frame["left"] == pytest.approx(0.1) and frame["right"] == pytest.approx(0.95)
    assert frame["bottom"] == pytest.approx(0.1) and frame["top"] == pytest.approx(0.95)
    # axes (10 - 1.5 - 1) / 2 = 3.75 in wide, (5 - 0.75 - 0.5) / 2 = 1.875 in high
    assert frame["wspace"] == pytest.approx(1.0 / 3.75) and frame["hspace"] == pytest.approx(0.5 / 1.875)
    with pytest.raises(ValueError, match="no room"):
        margins(2.0, 2.0, left=1.0, right=1.0, bottom=0.1, top=0.1)


@pytest.fixture(scope="module")
def demo_results(tmp_path_factory):
    from balancer.scene import run_scene

    folder = tmp_path_factory.mktemp("demo")
    scene = dict(__import__("tomllib").loads(DEMO.read_text()))
    scene["outputs"] = {**scene["outputs"], "plots": [], "archive": False}
    scene["frf"] = {**scene["frf"], "file": str(DEMO.parent / scene["frf"]["file"])}
    return run_scene(scene, plots_dir=folder).results


@pytest.mark.parametrize("stage", ["identify", "adb_stability", "adb_response", "mounts"])
def test_scene_figures_fit_without_a_layout_engine(demo_results, stage):
    from balancer.scene.plots import stage_figures

    for name, fig in stage_figures(stage, demo_results):
        assert fig.get_layout_engine() is None, name
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        renderer = canvas.get_renderer()
        width, height = canvas.get_width_height()
        # each axes with all it draws (tick labels, axis labels, title, legend, offset text)
        boxes = [ax.get_tightbbox(renderer) for ax in fig.axes]
        for ax, box in zip(fig.axes, boxes):  # on the figure (1 px of antialiasing)
            assert box.x0 >= -1 and box.y0 >= -1 and box.x1 <= width + 1 and box.y1 <= height + 1, (name, ax.get_title())
            for label in ax.get_xticklabels() + ax.get_yticklabels():
                assert "$" not in label.get_text(), label.get_text()  # no mathtext
        for i, a in enumerate(boxes):  # no axes' labels run into another axes
            for b in boxes[i + 1:]:
                overlap = (min(a.x1, b.x1) - max(a.x0, b.x0), min(a.y1, b.y1) - max(a.y0, b.y0))
                assert min(overlap) <= 1.0, (stage, name, a, b)


@pytest.mark.parametrize("stage", ["identify", "adb_response", "mounts"])
def test_png_bytes_holds_the_pixels_savefig_writes(demo_results, stage):
    # the scene's own PNG writer (no filter, zlib) against matplotlib's savefig (Pillow): decoded,
    # the same RGBA pixels, resolution and software note
    import io

    import numpy as np
    from PIL import Image

    from balancer.scene.plots import stage_figures
    from modal.figures import png_bytes

    for name, fig in stage_figures(stage, demo_results):
        ours = Image.open(io.BytesIO(png_bytes(fig, dpi=100)))
        theirs_file = io.BytesIO()
        fig.savefig(theirs_file, format="png", dpi=100)
        theirs = Image.open(io.BytesIO(theirs_file.getvalue()))
        assert ours.mode == theirs.mode == "RGBA", name
        assert np.array_equal(np.asarray(ours), np.asarray(theirs)), name
        assert ours.info["dpi"] == theirs.info["dpi"] and ours.info["Software"] == theirs.info["Software"]


def _log_figure(axis: str, low: float, high: float, marks: bool):
    import numpy as np
    from matplotlib.figure import Figure

    from modal.figures import minor_tick_marks, plain_log_ticks

    fig = Figure(figsize=(4, 3))
    ax = fig.add_subplot()
    x = np.linspace(1.0, 100.0, 500)
    y = np.geomspace(low, high, 500)
    (ax.semilogy if axis == "y" else ax.semilogx)(*((x, y) if axis == "y" else (y, x)), ".", ms=2)
    target = ax.yaxis if axis == "y" else ax.xaxis
    plain_log_ticks(target)
    if marks:
        minor_tick_marks(target)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy(), target


@pytest.mark.parametrize("axis, low, high", [("y", 2e-4, 30.0), ("x", 1e-3, 10.0), ("y", 1.5, 8.0), ("y", 0.3, 3.0)])
def test_minor_tick_marks_draw_what_the_minor_ticks_drew(axis, low, high):
    # the same pixels as the axis' own minor ticks: over several decades (unlabelled: one artist, no
    # Tick per location) and within about one decade (labelled: the axis' own ticks come back)
    import numpy as np

    plain, _ = _log_figure(axis, low, high, marks=False)
    light, target = _log_figure(axis, low, high, marks=True)
    assert np.array_equal(plain, light)
    if high / low > 100:
        assert len(target.minorTicks) <= 1  # the template tick only
    else:  # labelled: the axis drew its own minor ticks, labels included
        assert any(label.get_text() for label in target.get_minorticklabels())
