"""The drive's plain-text report and shaft diagrams (balancer.drive.report), and the docs' worked example.

Reference numbers are the machine-drive report (seed 002) as decoded in ``shared/reference/crank_drive.md``
section 4.
"""
from __future__ import annotations

import math

import pytest
from matplotlib.figure import Figure

from support.paths import ROOT

from balancer.drive import report as drive_report

from balancer.drive.shaft import PointLoad, ShaftGeometry, analyse_shaft
from modal.errors import ParameterError


# --------------------------------------------------------------------------- report and plots
def test_text_report_holds_the_chain(stage_a, stage_b):
    text = drive_report.drive_report(stages=[stage_a, stage_b], title="Seed 002")
    assert text.startswith("Seed 002\n========\n")
    assert "quantity" in text and "formula" in text and "unit" in text
    for value in ("775.00", "945.73", "975.00", "176.18", "4.8695", "154.02", "236.05", "2075.97", "877.58"):
        assert value in text, value
    lines = text.splitlines()
    assert len(lines) == 4 + len(drive_report.belt_stage_rows(stage_a)) + len(drive_report.belt_stage_rows(stage_b))
    with pytest.raises(ParameterError, match="nothing to report"):
        drive_report.drive_report()


def _shaft_1():
    geometry = ShaftGeometry(length_m=1.30, bearing_a_m=0.0, bearing_b_m=1.15)
    return analyse_shaft(geometry, [PointLoad.from_direction(1.30, 235.88, 5.0, "pulley")], 9.24)


def test_plot_builds_its_own_figure_without_pyplot():
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    figure = drive_report.plot_shaft_diagrams(_shaft_1())
    assert isinstance(figure, Figure)
    assert plt.get_fignums() == before  # pyplot state untouched
    shear_ax, moment_ax = figure.axes
    assert shear_ax.get_ylabel() == "shear force (N)"
    assert moment_ax.get_ylabel() == "bending moment (N m)"
    # the resultant's peak is marked at B (1150 mm) with M = 235.88 * 0.15 N m
    marker = [line for line in moment_ax.lines if line.get_marker() == "o"][0]
    assert marker.get_xdata()[0] == pytest.approx(1150.0)
    assert marker.get_ydata()[0] == pytest.approx(235.88 * 0.15, rel=1e-12)


def test_plot_on_given_axes():
    figure = Figure()
    ax = figure.add_subplot()
    assert drive_report.plot_moment(_shaft_1(), ax) is figure
    assert len(ax.lines) >= 3
    pair_figure = Figure()
    axes = pair_figure.subplots(1, 2)
    assert drive_report.plot_shaft_diagrams(_shaft_1(), axes) is pair_figure
    with pytest.raises(ParameterError, match="expected a matplotlib Axes"):
        drive_report.plot_shear(_shaft_1(), ax="not an axes")
    with pytest.raises(ParameterError, match=r"axes has 1 entries"):
        drive_report.plot_shaft_diagrams(_shaft_1(), [ax])


def test_docs_worked_example_runs(capsys):
    # The code block in docs/drive.md must run as printed and give the numbers the doc quotes.
    from pathlib import Path

    text = (ROOT / "docs" / "drive.md").read_text(encoding="utf-8")
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    namespace: dict = {}
    exec(compile(block, "docs/drive.md", "exec"), namespace)  # noqa: S102 - our own documentation
    handover = namespace["handover"]
    # derived independently of the code, then the doc's printed digits checked against them:
    # 775 rpm; overhung stiffness 3EI/(c^2 (L + c)), c = 0.15 m, L = 1.15 m, d = 25 mm,
    # E = 205 GPa; Dunkerley with the rotor alone (sqrt(k/M), M = 2 kg) and the bare span
    # (pi/L)^2 sqrt(EI/(rho A)), rho = 7850 kg/m^3. Rounding only between code and formulas.
    speed = 775.0 * 2 * math.pi / 60
    ei = 205e9 * math.pi * 0.025**4 / 64
    k = 3 * ei / (0.15**2 * (1.15 + 0.15))
    span_mode = (math.pi / 1.15) ** 2 * math.sqrt(ei / (7850.0 * math.pi * 0.025**2 / 4))
    critical = 1 / math.sqrt(1 / span_mode**2 + 2.0 / k)
    critical_rpm = critical * 60 / (2 * math.pi)
    assert handover.speed_rad_s == pytest.approx(speed, rel=1e-12)
    assert handover.stiffness_n_per_m == pytest.approx(k, rel=1e-12)
    assert handover.critical.critical_speed_rpm == pytest.approx(critical_rpm, rel=1e-9)
    # the numbers docs/drive.md prints, to the digits it prints
    assert (f"{speed:.3f}", f"{k / 1e3:.1f}", f"{critical:.2f}", f"{critical_rpm:.1f}") == (
        "81.158", "403.2", "210.53", "2010.4")
    for printed in ("**81.158 rad/s**", "**k = 403.2 kN/m**", "**210.53 rad/s = 2010.4 rpm**"):
        assert printed in text, printed
    assert isinstance(namespace["figure"], Figure)
    assert "first critical speed" in capsys.readouterr().out
