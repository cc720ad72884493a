"""Figure helpers that keep drawing cheap: margins fixed in inches (no layout engine) and
logarithmic tick labels as plain text (no mathtext).

A layout engine (``layout="constrained"``) measures every tick label of every axes twice
before the figure is drawn, and mathtext runs a parser for each ``10^{-3}`` label: both
cost more than drawing the figure itself.  The figures of this package have known
contents (tick labels of a few characters, one-line axis labels and titles), so margins
set once in inches leave room for them at any figure size.
"""
from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatterSciNotation

__all__ = ["fixed_figure", "margins", "PlainLogFormatter", "plain_log_ticks"]

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
    axes_w = (inner_w - (ncols - 1) * wgap) / ncols
    axes_h = (inner_h - (nrows - 1) * hgap) / nrows
    if axes_w <= 0 or axes_h <= 0:
        raise ValueError(f"margins leave no room for the axes in a {width_in} x {height_in} in figure")
    return {"left": left / width_in, "right": 1.0 - right / width_in, "bottom": bottom / height_in,
            "top": 1.0 - top / height_in, "wspace": wgap / axes_w, "hspace": hgap / axes_h}


def fixed_figure(width_in: float, height_in: float, **kwargs) -> Figure:
    """A :class:`~matplotlib.figure.Figure` without layout engine, its subplots placed by :func:`margins`
    (same keywords)."""
    fig = Figure(figsize=(width_in, height_in))
    fig.subplots_adjust(**margins(width_in, height_in, **kwargs))
    return fig
