"""Mode-shape figures: what they draw is the shape's numbers; the GIF holds one cycle."""
import numpy as np
import pytest

from modal.errors import ParameterError
from modal.geometry import Geometry
from modal.shape_plots import plot_complexity, plot_mac_matrix, plot_mode_shape, write_gif
from modal.shapes import ModeShapes, animation_frames, normalise


def _shapes():
    values = np.array([[1.0, 0.5, -0.5], [1.0, -1.0, 0.2j]], complex)
    return ModeShapes(np.array([12.0, 40.0]), np.array([0.01, 0.02]), values, np.arange(3), ("1+Z", "2+Z", "3+Z"),
                      "nls")


def _beam():
    return Geometry([1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[1, 2], [2, 3]])


def test_the_3d_figure_draws_the_deflected_shape_on_the_geometry():
    shapes = _shapes()
    fig = plot_mode_shape(shapes, 1, _beam(), amplitude=0.2)
    ax = fig.axes[0]
    expected = animation_frames(shapes.placed_on(_beam()), normalise(shapes.shapes[1]), n_frames=1, amplitude=0.2)[0]
    drawn = [line for line in ax.lines if line.get_color() == "tab:blue" and line.get_marker() == "o"][0]
    x, y, z = drawn.get_data_3d()
    np.testing.assert_allclose(np.column_stack([x, y, z]), expected)
    assert "40 Hz" in ax.get_title()
    with pytest.raises(ParameterError, match=r"mode must be 1\.\.2"):
        plot_mode_shape(shapes, 2)


def test_complexity_plot_reports_mpc_per_mode():
    fig = plot_complexity(_shapes())
    titles = [ax.get_title() for ax in fig.axes if ax.get_visible()]
    assert titles[0].endswith("MPC 1.000, MPD 0.0°")  # a real shape
    assert "MPC 1.000" not in titles[1]  # the second shape has an entry at 90°


def test_mac_matrix_writes_its_values():
    fig = plot_mac_matrix([[1.0, 0.25], [0.25, 1.0]], ["a", "b"])
    assert sorted(t.get_text() for t in fig.axes[0].texts) == ["0.25", "0.25", "1.00", "1.00"]


def test_gif_holds_one_cycle_of_distinct_frames(tmp_path):
    from PIL import Image

    path = tmp_path / "mode.gif"
    write_gif(path, _shapes(), 0, _beam(), n_frames=6, fps=6)
    with Image.open(path) as gif:
        assert gif.n_frames == 6
        frames = []
        for k in (0, 3):  # half a cycle apart: the beam bends the other way
            gif.seek(k)
            frames.append(np.asarray(gif.convert("L"), float))
    assert np.abs(frames[0] - frames[1]).mean() > 0.1
