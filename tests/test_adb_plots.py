"""Plots: return Figures, draw the expected artists, never touch pyplot state."""
from __future__ import annotations

import io
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


def test_time_plots(run):
    for plot, lines in ((plot_orbit, 2), (plot_amplitude, 3), (plot_ball_angles, 4)):
        figure = plot(run)
        assert isinstance(figure, Figure)
        assert len(figure.axes[0].get_lines()) == lines
        assert _render(figure)[:4] == b"\x89PNG"


def test_plot_into_given_axes(run):
    figure = Figure()
    ax = figure.add_subplot()
    assert plot_amplitude(run, ax=ax) is figure


def test_stability_map_and_run_up_plots():
    result = stability_map(S1, np.linspace(0.3, 4, 30) * WN, "D", np.geomspace(1e-6, 0.1, 20))
    figure = plot_stability_map(result)
    assert figure.axes[0].get_yscale() == "log"
    assert _render(figure)
    up = simulate(S1, LinearRunUp(0.0, 2 * WN, 0.6), 0.6, n_samples=601)
    figure = plot_run_up(up, WN)
    x = figure.axes[0].get_lines()[-1].get_xdata()
    assert x[-1] == pytest.approx(2.0)


def test_settling_study_plot():
    study = settling_study(S1, "m", [0.01, 0.02], speed_ratio=4.0, t_end_s=1.5)
    assert np.all(np.isfinite(study.settling_time_s))
    figure = plot_settling_study(study)
    assert len(figure.axes[0].get_lines()[0].get_xdata()) == 2


def test_pyplot_state_untouched(run):
    pyplot = sys.modules.get("matplotlib.pyplot")
    before = pyplot.get_fignums() if pyplot else []
    plot_orbit(run)
    after = pyplot.get_fignums() if pyplot else []
    assert before == after
