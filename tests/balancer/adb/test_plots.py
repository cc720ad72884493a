"""Plots: return Figures, draw the expected artists, never touch pyplot state."""
from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np
import pytest
from matplotlib.figure import Figure

from balancer.adb import ADBParameters, LinearRunUp, simulate, stability_map
from balancer.adb.plots import (
    plot_amplitude,
    plot_ball_angles,
    plot_orbit,
    plot_run_up,
    plot_settling_study,
    plot_stability_map,
)
from balancer.adb.studies import settling_study

S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
WN = S1.natural_frequency_rad_s


@pytest.fixture(scope="module")
def run():
    return simulate(S1, 2 * WN, 1.0, n_samples=1001)  # settles at 0.76 s


def _render(figure):
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    return buffer.getvalue()


def _line(ax, label):
    (line,) = [line for line in ax.get_lines() if line.get_label() == label]
    return line


def test_time_plots(run):
    # what is drawn: the run's own samples, in the units the labels say
    orbit = plot_orbit(run).axes[0]
    np.testing.assert_array_equal(_line(orbit, "with balls").get_xdata(), 1e3 * run.rotor_x_m)
    np.testing.assert_array_equal(_line(orbit, "with balls").get_ydata(), 1e3 * run.rotor_y_m)
    np.testing.assert_array_equal(_line(orbit, "without balls").get_xdata(), 1e3 * run.rotor_x_without_balls_m)
    assert (orbit.get_xlabel(), orbit.get_ylabel()) == ("x (mm)", "y (mm)")
    amplitude = plot_amplitude(run).axes[0]
    np.testing.assert_array_equal(_line(amplitude, "with balls").get_xdata(), run.time_s)
    np.testing.assert_array_equal(_line(amplitude, "with balls").get_ydata(), run.amplitude_m)
    np.testing.assert_array_equal(_line(amplitude, "without balls").get_ydata(), run.amplitude_without_balls_m)
    assert _line(amplitude, "balls settled").get_xdata()[0] == run.settling_time_s
    assert amplitude.get_yscale() == "log" and amplitude.get_title() == f"final state: {run.final_state}"
    assert (amplitude.get_xlabel(), amplitude.get_ylabel()) == ("time (s)", "amplitude (m)")
    angles = plot_ball_angles(run).axes[0]
    ends = []
    for index in range(2):
        line = _line(angles, f"ball {index + 1}")
        x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
        # the samples, wrapped to (-180, 180] degrees, with a gap (NaN) where the wrap jumps
        drawn = ~np.isnan(y)
        np.testing.assert_array_equal(x[drawn], run.time_s)
        np.testing.assert_allclose(y[drawn], np.degrees(np.angle(np.exp(1j * run.ball_angles_rad[:, index]))))
        assert not np.any(np.abs(np.diff(y)) > 180.0)  # no vertical line across the panel (NaN gaps)
        ends.append(y[drawn][-1])
    # the run settled (0.76 s): each ball within settle_tolerance (1 %) of its balanced angle
    balanced = np.sort(np.degrees(run.balanced_ball_angles_rad))
    assert run.settled and np.all(np.abs(np.sort(ends) - balanced) <= run.settle_tolerance * np.abs(balanced))
    levels = sorted(line.get_ydata()[0] for line in angles.get_lines() if line.get_label().startswith("_"))
    np.testing.assert_allclose(levels, np.sort(np.degrees(run.balanced_ball_angles_rad)))
    assert angles.get_ylim() == (-180, 180)
    assert _render(plot_orbit(run))[:4] == b"\x89PNG"


def test_plot_into_given_axes(run):
    figure = Figure()
    ax = figure.add_subplot()
    assert plot_amplitude(run, ax=ax) is figure
    assert len(figure.axes) == 1 and _line(ax, "with balls").get_ydata() is not None


def test_stability_map_and_run_up_plots():
    speeds = np.linspace(0.3, 4, 30) * WN
    result = stability_map(S1, speeds, "D", np.geomspace(1e-6, 0.1, 20))
    figure = plot_stability_map(result)
    ax = figure.axes[0]
    assert ax.get_yscale() == "log"
    # the mesh holds the stability classes, cell by cell, over the speed ratio and the drag
    (mesh,) = ax.collections
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(result.stability_class.shape),
                                  result.stability_class)
    assert ax.get_xlim()[0] <= 0.3 and ax.get_xlim()[1] >= 4.0
    assert ax.get_ylim()[0] <= 1e-6 and ax.get_ylim()[1] >= 0.1
    assert ax.get_xlabel() == "speed ratio Ω/ωn" and ax.get_ylabel() == "D (N m s)"
    assert _render(figure)
    up = simulate(S1, LinearRunUp(0.0, 2 * WN, 0.6), 0.6, n_samples=601)
    figure = plot_run_up(up, WN)
    line = _line(figure.axes[0], "with balls")
    np.testing.assert_allclose(line.get_xdata(), up.speed_rad_s / WN)
    np.testing.assert_array_equal(line.get_ydata(), up.amplitude_m)
    assert line.get_xdata()[-1] == pytest.approx(2.0)
    assert figure.axes[0].get_xlabel() == "speed ratio Ω/ωn"


def test_settling_study_plot():
    study = settling_study(S1, "m", [0.01, 0.02], speed_ratio=4.0, t_end_s=1.5)
    assert np.all(np.isfinite(study.settling_time_s))
    ax = plot_settling_study(study).axes[0]
    line = ax.get_lines()[0]
    np.testing.assert_array_equal(line.get_xdata(), [0.01, 0.02])
    np.testing.assert_array_equal(line.get_ydata(), study.settling_time_s)
    assert ax.get_ylabel() == "settling time (s)" and ax.get_title() == "Ω/ωn = 4"


def test_pyplot_state_untouched(run):
    # pyplot imported and holding a current figure of its own: the plots must neither add a
    # figure to it nor change the current one (run alone, pyplot was not even imported, and
    # the old comparison of two empty lists could not fail)
    import matplotlib.pyplot as plt

    mine = plt.figure()
    try:
        before = plt.get_fignums()
        figures = [plot_orbit(run), plot_amplitude(run), plot_ball_angles(run)]
        assert plt.get_fignums() == before and plt.gcf() is mine
        assert all(figure.canvas.manager is None for figure in figures)  # not registered with pyplot
    finally:
        plt.close(mine)


def test_plot_module_does_not_import_pyplot():
    code = ("import sys, balancer.adb.plots, balancer.adb; "
            "sys.exit('matplotlib.pyplot' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], env={**os.environ, "MPLBACKEND": "Agg"}).returncode == 0
