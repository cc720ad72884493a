"""Figure helpers that keep drawing cheap: margins fixed in inches (no layout engine) and
logarithmic tick labels as plain text (no mathtext).

A layout engine (``layout="constrained"``) measures every tick label of every axes twice
before the figure is drawn, and mathtext runs a parser for each ``10^{-3}`` label: both
cost more than drawing the figure itself.  The figures of this package have known
contents (tick labels of a few characters, one-line axis labels and titles), so margins
set once in inches leave room for them at any figure size.  :func:`png_bytes` encodes the
drawn figure itself (Pillow's adaptive PNG filtering costs more than it saves on plots), and
:func:`minor_tick_marks` draws a log axis' unlabelled minor ticks as one artist instead of a
tick object each; both give the same pixels.
"""
from __future__ import annotations

import struct
import zlib

import numpy as np
from matplotlib.artist import Artist
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import LogFormatterSciNotation, NullLocator

__all__ = ["fixed_figure", "margins", "gap_fraction", "PlainLogFormatter", "plain_log_ticks", "png_bytes",
           "minor_tick_marks"]

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
_MATH_OPEN, _MATH_CLOSE = r"$\mathdefault{", "}$"


class PlainLogFormatter(LogFormatterSciNotation):
    """:class:`~matplotlib.ticker.LogFormatterSciNotation` written with Unicode superscripts.

    The same labels (``10⁻³``, ``2×10⁻³``) as the default log-axis formatter, drawn as
    plain text instead of mathtext.
    """

    def __call__(self, x, pos=None) -> str:
        text = super().__call__(x, pos)
        if not (text.startswith(_MATH_OPEN) and text.endswith(_MATH_CLOSE)):
            return text
        body = text[len(_MATH_OPEN):-len(_MATH_CLOSE)].replace(r"\times", "×")
        if "^{" in body:
            mantissa, exponent = body.split("^{", 1)
            body = mantissa + exponent.rstrip("}").translate(_SUPERSCRIPT)
        return body.replace("-", "\N{MINUS SIGN}")


def plain_log_ticks(axis) -> None:
    """Label a logarithmic :class:`~matplotlib.axis.Axis` with :class:`PlainLogFormatter` (call after
    setting the log scale, which installs the mathtext formatters)."""
    base = getattr(axis.get_major_formatter(), "_base", 10.0)
    axis.set_major_formatter(PlainLogFormatter(base))
    axis.set_minor_formatter(PlainLogFormatter(base, labelOnlyBase=False))


def margins(width_in: float, height_in: float, *, left: float, right: float, bottom: float, top: float,
            wgap: float = 0.0, hgap: float = 0.0, ncols: int = 1, nrows: int = 1) -> dict[str, float]:
    """Subplot parameters (figure fractions) for margins and gaps given in inches.

    Parameters
    ----------
    width_in, height_in : float
        Figure size, in.
    left, right, bottom, top : float
        Space between the figure's edges and the axes grid, in.
    wgap, hgap : float
        Space between neighbouring columns and rows of the grid, in.
    ncols, nrows : int
        Columns and rows of the grid (to turn the gaps into matplotlib's fractions of an axes).

    Returns
    -------
    dict
        ``left``, ``right``, ``bottom``, ``top``, ``wspace``, ``hspace`` for
        :meth:`~matplotlib.figure.Figure.subplots_adjust` or a gridspec.
    """
    inner_w = width_in - left - right
    inner_h = height_in - bottom - top
    if inner_w - (ncols - 1) * wgap <= 0 or inner_h - (nrows - 1) * hgap <= 0:
        raise ValueError(f"margins leave no room for the axes in a {width_in} x {height_in} in figure")
    return {"left": left / width_in, "right": 1.0 - right / width_in, "bottom": bottom / height_in,
            "top": 1.0 - top / height_in, "wspace": gap_fraction(wgap, inner_w, ncols),
            "hspace": gap_fraction(hgap, inner_h, nrows)}


def gap_fraction(gap_in: float, extent_in: float, n: int) -> float:
    """matplotlib's ``wspace``/``hspace`` (a fraction of the mean axes size) for a gap of ``gap_in`` inches
    between ``n`` axes sharing ``extent_in`` inches (0 for one axes: there is no gap)."""
    return gap_in / ((extent_in - (n - 1) * gap_in) / n) if n > 1 else 0.0


def fixed_figure(width_in: float, height_in: float, **kwargs) -> Figure:
    """A :class:`~matplotlib.figure.Figure` without layout engine, its subplots placed by :func:`margins`
    (same keywords)."""
    fig = Figure(figsize=(width_in, height_in))
    fig.subplots_adjust(**margins(width_in, height_in, **kwargs))
    return fig


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_bytes(figure: Figure, dpi: float = 100.0, compress_level: int = 3) -> bytes:
    """The figure drawn by Agg at ``dpi`` and encoded as a PNG file (8-bit RGBA).

    The pixels of ``figure.savefig(format="png", dpi=dpi)`` (tested), written without a PNG
    filter and deflated at ``compress_level``: on the flat colours of plots that is smaller
    than Pillow's adaptive filtering (which ``savefig`` uses) and takes about 40 % of its time.
    Like ``savefig`` it records the software (tEXt) and the resolution (pHYs).

    Parameters
    ----------
    figure : Figure
    dpi : float
        Resolution, dots per inch.
    compress_level : int
        zlib level, 0-9.

    Returns
    -------
    bytes
        The PNG file's content.
    """
    import matplotlib
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    before = figure.dpi
    figure.set_dpi(dpi)
    try:
        canvas = FigureCanvasAgg(figure)
        canvas.draw()
        rgba = np.asarray(canvas.buffer_rgba())
    finally:
        figure.set_dpi(before)
    height, width = rgba.shape[:2]
    rows = np.zeros((height, 1 + 4 * width), dtype=np.uint8)  # each scanline: filter type 0, then RGBA
    rows[:, 1:] = rgba.reshape(height, -1)
    per_metre = int(dpi / 0.0254 + 0.5)
    software = f"Matplotlib version{matplotlib.__version__}, https://matplotlib.org/"
    return b"".join([
        b"\x89PNG\r\n\x1a\n",
        _png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)),
        _png_chunk(b"tEXt", b"Software\x00" + software.encode("latin-1")),
        _png_chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1)),
        _png_chunk(b"IDAT", zlib.compress(rows, compress_level)),
        _png_chunk(b"IEND", b""),
    ])


class _MinorTickMarks(Artist):
    """An axis' unlabelled minor ticks drawn as one set of markers.

    Matplotlib makes a :class:`~matplotlib.axis.Tick` (two marks, a grid line and two labels) for
    every minor location and draws each on its own: 48 of them on a log axis over six decades
    cost a sixth of a two-panel FRF figure.  Here the axis keeps a ``NullLocator``; a companion
    (:class:`_MinorTickCheck`, drawn just before the axis) asks the real locator for the
    locations at draw time, leaves out those on major ticks and outside the view as the axis
    does, and this artist draws them just after the axis (where the axis would have drawn its
    minor ticks, after the major ones), styled as the axis' own minor ticks.  If the formatter
    would label any of them (a view of about one decade or less), the axis gets its locator
    back before it draws and nothing is drawn here: then the axis' own ticks are drawn.
    """

    def __init__(self, axis, locator):
        super().__init__()
        self._axis = axis
        self._locator = locator
        self._locs = np.zeros(0)
        template = axis.get_minor_ticks(1)[0]  # the axis' minor tick style, tick_params included
        self._marks = []
        for line in (template.tick1line, template.tick2line):
            mark = Line2D([], [])
            mark.update_from(line)
            mark.set_transform(line.get_transform())
            mark.set_visible(line.get_visible())
            mark.set_clip_on(line.get_clip_on())
            self._marks.append(mark)
        self.set_zorder(np.nextafter(axis.get_zorder(), np.inf))  # after the axis, before anything above it
        self.set_in_layout(False)

    def set_figure(self, figure) -> None:
        super().set_figure(figure)
        for mark in self._marks:
            mark.set_figure(figure)

    def prepare(self) -> None:
        """Before the axis draws: this draw's locations, or the axis' own ticks back if any is labelled."""
        axis = self._axis
        self._locs = np.zeros(0)
        axis.minor.locator = self._locator  # the axis' own rule for dropping locations on major ticks
        try:
            locs = np.asarray(axis.get_minorticklocs(), dtype=float)
            labels = axis.minor.formatter.format_ticks(locs) if locs.size else []
        finally:
            axis.minor.locator = NullLocator()
        if any(labels):  # labelled minor ticks: the axis draws its own from now on
            axis.set_minor_locator(self._locator)
            self.set_visible(False)
            return
        low, high = sorted(axis.get_view_interval())
        transform = axis.get_transform()
        with np.errstate(divide="ignore", invalid="ignore"):
            ends = transform.transform(np.array([low, high]))
            where = transform.transform(locs) if locs.size else locs
        slack = 1e-10 * (ends[1] - ends[0])  # as matplotlib's own test of a tick being in view
        self._locs = locs[np.isfinite(where) & (where >= ends[0] - slack) & (where <= ends[1] + slack)]

    def draw(self, renderer) -> None:
        if not (self.get_visible() and self._axis.get_visible()) or not self._locs.size:
            return
        across = np.zeros_like(self._locs)
        for mark in self._marks:
            if mark.get_visible():
                mark.set_data((across, self._locs) if self._axis.axis_name == "y" else (self._locs, across))
                mark.draw(renderer)


class _MinorTickCheck(Artist):
    """Drawn just before the axis (same z-order, added earlier): runs :meth:`_MinorTickMarks.prepare`."""

    def __init__(self, marks: _MinorTickMarks):
        super().__init__()
        self._marks = marks
        self.set_zorder(marks._axis.get_zorder())
        self.set_in_layout(False)

    def draw(self, renderer) -> None:
        if self._marks.get_visible():
            self._marks.prepare()


def minor_tick_marks(axis) -> None:
    """Draw ``axis``' unlabelled minor ticks as one artist instead of one Tick object each.

    The figure looks the same (tested pixel for pixel); see :class:`_MinorTickMarks`.  Call
    once the axis' scale and locators are set, before adding other artists of the axis' z-order.
    """
    locator = axis.get_minor_locator()
    if isinstance(locator, NullLocator):
        return
    marks = _MinorTickMarks(axis, locator)
    axis.set_minor_locator(NullLocator())
    axis.axes.add_artist(_MinorTickCheck(marks))
    axis.axes.add_artist(marks)
