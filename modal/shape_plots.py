"""Figures of mode shapes: the shape on the test geometry (3D), its animation (GIF), the complexity
(Argand) diagram per mode and a MAC matrix. Each returns a matplotlib Figure (or an Animation),
built without pyplot; nothing is shown.

The numbers come from :mod:`modal.shapes`; these functions only draw them.
"""
from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from .geometry import Geometry
from .shapes import ModeShapes, animation_frames, mean_phase_deviation_deg, mpc, normalise

__all__ = ["plot_mode_shape", "plot_complexity", "plot_mac_matrix", "animate_mode_shape", "write_gif"]


def _mode_title(shapes: ModeShapes, mode: int) -> str:
    return (f"mode {mode + 1}: {shapes.natural_frequency_hz[mode]:.5g} Hz, "
            f"ζ = {100 * shapes.damping_ratio[mode]:.3g} %")


def _check_mode(shapes: ModeShapes, mode: int) -> None:
    from .errors import ParameterError

    if not 0 <= int(mode) < shapes.n_modes:
        raise ParameterError(f"mode must be 1..{shapes.n_modes} (as numbered in the report), got {int(mode) + 1}")


def _draw_structure(ax, geometry: Geometry, positions: np.ndarray, color: str, lw: float):
    """Trace lines (one collection) and nodes at ``positions`` (n_nodes, 3); returns (lines or None, nodes)."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    lines = None
    if geometry.lines.size:
        rows = geometry.node_index(geometry.lines.ravel()).reshape(-1, 2)
        lines = Line3DCollection(positions[rows], colors=color, linewidths=lw)
        ax.add_collection3d(lines)
    (points,) = ax.plot(*positions.T, "o", ms=3, color=color)
    return lines, points


def _equal_box(ax, frames: np.ndarray) -> None:
    """Equal scales on the three axes, the box holding every frame."""
    lo, hi = frames.reshape(-1, 3).min(axis=0), frames.reshape(-1, 3).max(axis=0)
    centre, half = (lo + hi) / 2, max(float(np.max(hi - lo)) / 2, 1e-12)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")


def plot_mode_shape(shapes: ModeShapes, mode: int = 0, geometry: Geometry | None = None, amplitude: float = 0.1,
                    phase_deg: float = 0.0, figure: Figure | None = None) -> Figure:
    """A mode's shape on the test geometry in 3D: undeformed in grey, deflected in colour.

    Parameters
    ----------
    shapes : ModeShapes
        From :func:`modal.shapes.mode_shapes`.
    mode : int
        Index of the mode (0-based).
    geometry : Geometry, optional
        The test geometry; without one the entries stand on a line in order.
    amplitude : float
        Largest displacement as a fraction of the geometry's extent.
    phase_deg : float
        Instant of the cycle drawn, degrees (0: the real part of the normalised shape).
    figure : Figure, optional
    """
    _check_mode(shapes, mode)
    placed = shapes.placed_on(geometry)
    shape = normalise(shapes.shapes[mode]) * np.exp(1j * np.radians(phase_deg))
    deformed = animation_frames(placed, shape, n_frames=1, amplitude=amplitude)[0]
    fig = figure if figure is not None else Figure(figsize=(6, 5), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    _draw_structure(ax, placed, placed.coordinates_m, color="0.7", lw=0.8)
    _draw_structure(ax, placed, deformed, color="tab:blue", lw=1.6)
    _equal_box(ax, np.stack([placed.coordinates_m, deformed]))
    ax.set_title(_mode_title(shapes, mode), fontsize="medium")
    return fig


def animate_mode_shape(shapes: ModeShapes, mode: int = 0, geometry: Geometry | None = None, n_frames: int = 24,
                       amplitude: float = 0.1, figure: Figure | None = None):
    """One cycle of a mode's shape on the geometry as a matplotlib animation.

    Returns
    -------
    matplotlib.animation.FuncAnimation
        Its figure is ``animation._fig``; save it with :func:`write_gif` (or ``animation.save``).
    """
    from matplotlib.animation import FuncAnimation

    _check_mode(shapes, mode)
    placed = shapes.placed_on(geometry)
    frames = animation_frames(placed, normalise(shapes.shapes[mode]), n_frames=n_frames, amplitude=amplitude)
    fig = figure if figure is not None else Figure(figsize=(5, 4), dpi=80, layout="constrained")
    ax = fig.add_subplot(projection="3d")
    _draw_structure(ax, placed, placed.coordinates_m, color="0.75", lw=0.8)
    lines, points = _draw_structure(ax, placed, frames[0], color="tab:blue", lw=1.6)
    _equal_box(ax, frames)
    ax.set_axis_off()  # a slide shows the structure; the axes' panes and ticks would cost most of each frame
    ax.set_title(_mode_title(shapes, mode), fontsize="medium")
    rows = placed.node_index(placed.lines.ravel()).reshape(-1, 2) if placed.lines.size else np.zeros((0, 2), int)

    def update(k):
        pos = frames[k]
        if lines is not None:
            lines.set_segments(pos[rows])
        points.set_data_3d(*pos.T)
        return [a for a in (lines, points) if a is not None]

    return FuncAnimation(fig, update, frames=len(frames), interval=1000 / 12, blit=False)


def write_gif(path: str | os.PathLike, shapes: ModeShapes, mode: int = 0, geometry: Geometry | None = None,
              n_frames: int = 24, fps: int = 12, amplitude: float = 0.1) -> None:
    """Write one cycle of a mode's animation as a looping GIF (Pillow writer), crash-safely.

    Parameters
    ----------
    path : path-like
        Target ``.gif`` file.
    fps : int
        Frames per second.
    """
    import tempfile
    from pathlib import Path

    from matplotlib.animation import PillowWriter

    from .io._atomic import atomic_path

    anim = animate_mode_shape(shapes, mode, geometry, n_frames=n_frames, amplitude=amplitude)
    with atomic_path(path) as tmp, tempfile.TemporaryDirectory(prefix="modalbal-gif-") as scratch:
        drawn = Path(scratch) / "mode.gif"  # the writer takes the format from the extension
        anim.save(os.fspath(drawn), writer=PillowWriter(fps=fps), dpi=80)
        Path(tmp).write_bytes(drawn.read_bytes())


def plot_complexity(shapes: ModeShapes, modes: Sequence[int] | None = None, ncols: int = 4,
                    figure: Figure | None = None) -> Figure:
    """Argand diagram of each mode: its normalised entries in the complex plane, with MPC and MPD.

    A real (normal) mode lies on one line through the origin; scatter about that line is complexity
    (close modes, non-proportional damping, noise).
    """
    chosen = list(range(shapes.n_modes)) if modes is None else [int(m) for m in modes]
    for m in chosen:
        _check_mode(shapes, m)
    ncols = max(1, min(ncols, len(chosen)))
    nrows = -(-len(chosen) // ncols)
    fig = figure if figure is not None else Figure(figsize=(2.6 * ncols, 2.6 * nrows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False).ravel())
    values = normalise(shapes.shapes[chosen])
    mpcs, mpds = mpc(values), mean_phase_deviation_deg(values)
    for ax, m, row, p, d in zip(axes, chosen, values, mpcs, mpds):
        for z in row:
            ax.plot([0, z.real], [0, z.imag], color="tab:blue", lw=0.8)
        ax.plot(row.real, row.imag, "o", ms=3, color="tab:blue")
        ax.axhline(0, color="0.7", lw=0.5)
        ax.axvline(0, color="0.7", lw=0.5)
        ax.set_xlim(-1.1, 1.1)
        ax.set_ylim(-1.1, 1.1)
        ax.set_aspect("equal")
        ax.set_title(f"{shapes.natural_frequency_hz[m]:.4g} Hz\nMPC {p:.3f}, MPD {d:.1f}°", fontsize="small")
        ax.tick_params(labelsize="x-small")
    for ax in axes[len(chosen):]:
        ax.set_visible(False)
    return fig


def plot_mac_matrix(matrix, labels_rows: Sequence[str], labels_columns: Sequence[str] | None = None,
                    title: str = "MAC", figure: Figure | None = None) -> Figure:
    """A MAC matrix (auto or cross) as an image with its values written in the cells."""
    matrix = np.asarray(matrix, float)
    fig = figure if figure is not None else Figure(figsize=(1.2 + 0.45 * matrix.shape[1],
                                                            1.0 + 0.45 * matrix.shape[0]), layout="constrained")
    ax = fig.add_subplot()
    image = ax.imshow(matrix, vmin=0, vmax=1, cmap="Blues")
    if matrix.size <= 400:
        for (i, j), value in np.ndenumerate(matrix):
            ax.text(j, i, f"{value:.2f}", ha="center", va="center", fontsize="x-small",
                    color="white" if value > 0.6 else "black")
    ax.set_yticks(range(matrix.shape[0]), list(labels_rows), fontsize="x-small")
    ax.set_xticks(range(matrix.shape[1]), list(labels_columns or labels_rows), fontsize="x-small", rotation=90)
    ax.set_title(title, fontsize="medium")
    fig.colorbar(image, ax=ax, shrink=0.8)
    return fig
