"""Polar plot of a balancing job: readings before, with trials and predicted after;
correction masses (and their split onto holes) on the rotor outline.

Angles are drawn as measured: phase lag and mass angle both increase clockwise from
the top (the keyphasor mark), i.e. against a counter-clockwise rotation.
"""
from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .job import BalanceReport
from .readings import reading_unit

__all__ = ["plot_balance"]


def _polar(ax):
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)


def plot_balance(report: BalanceReport, fig: Figure | None = None) -> Figure:
    """Two polar panels: vibration vectors (user units) and correction masses per plane.

    Parameters
    ----------
    report : BalanceReport
    fig : Figure, optional
        Figure to draw on (default: a new 11 x 5 in figure).

    Returns
    -------
    Figure
    """
    fig = fig or Figure(figsize=(11, 5), layout="constrained")
    ax_v = fig.add_subplot(1, 2, 1, projection="polar")
    ax_m = fig.add_subplot(1, 2, 2, projection="polar")
    for ax in (ax_v, ax_m):
        _polar(ax)
    colours = [f"C{i % 10}" for i in range(len(report.sensors))]

    def arrows(values, style, label):
        amplitude, phase = report.in_user_units(values)
        for i, (a, p) in enumerate(zip(amplitude, phase)):
            ax_v.plot([0, np.deg2rad(p)], [0, a], style, color=colours[i], lw=1.5)
        ax_v.plot([], [], style, color="0.3", lw=1.5, label=label)  # the style's entry, in grey

    arrows(report.initial, "-", "initial")
    for j, run in enumerate(report.trial_runs):
        amplitude, phase = report.in_user_units(run)
        ax_v.plot(np.deg2rad(phase), amplitude, ["o", "s", "^", "D", "v"][j % 5], mfc="none", color="0.3",
                  label=f"trial plane {j + 1}")
    arrows(report.residual, "--", f"predicted after ({report.method})")
    if report.after.size:
        arrows(report.after, ":", "measured after")
    for i, sensor in enumerate(report.sensors):  # every reading's colour
        ax_v.plot([], [], "-", color=colours[i], lw=4, label=sensor)
    ax_v.set_title(f"1x vibration [{reading_unit(report.reading_units).label}], phase lag")
    ax_v.legend(loc="lower left", bbox_to_anchor=(-0.15, -0.18), fontsize="small", ncol=2)

    mass_scale = 1e3 if report.mass_units == "g" else 1.0
    n_planes = report.correction_kg_m.size
    outline = np.linspace(0, 2 * np.pi, 361)
    top = float(np.max(report.correction_mass_kg)) * mass_scale if n_planes else 1.0
    top = top if top > 0 else 1.0
    ax_m.plot(outline, np.full_like(outline, 1.1 * top), color="0.6", lw=1)
    if report.positions_deg.size:
        ax_m.plot(np.deg2rad(report.positions_deg), np.full(report.positions_deg.size, 1.1 * top), "o", color="0.6",
                  mfc="white", label="holes")
    for j in range(n_planes):
        theta = np.deg2rad(report.correction_angle_deg[j])
        ax_m.annotate("", xy=(theta, report.correction_mass_kg[j] * mass_scale), xytext=(0, 0),
                      arrowprops={"arrowstyle": "->", "color": f"C{j}", "lw": 2})
        ax_m.plot([], [], color=f"C{j}", lw=2, label=f"plane {j + 1}: {report.correction_mass_kg[j] * mass_scale:.3g} "
                  f"{report.mass_units} at {report.correction_angle_deg[j]:.1f}°")
        if report.positions_deg.size:
            on = report.split_mass_kg[j] > 0
            ax_m.plot(np.deg2rad(report.positions_deg[on]), report.split_mass_kg[j][on] * mass_scale, "x", color=f"C{j}",
                      ms=9, mew=2, label=f"plane {j + 1} on holes: " + ", ".join(
                          f"{m * mass_scale:.3g} {report.mass_units} at {p:g}°"
                          for p, m in zip(report.positions_deg[on], report.split_mass_kg[j][on])))
    ax_m.set_ylim(0, 1.2 * top)
    ax_m.set_title(f"correction masses [{report.mass_units}] at their radius")
    ax_m.legend(loc="lower left", bbox_to_anchor=(-0.1, -0.18), fontsize="small")
    return fig
