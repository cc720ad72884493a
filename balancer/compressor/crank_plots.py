"""Plots for the crank counterweight study.

Every function draws on the given Axes, or on a new
``matplotlib.figure.Figure`` when ``ax`` is None, and returns the Figure.
pyplot state is never touched; angles are shown in degrees, forces in N,
radii in mm (display only).
"""
from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .crank import (
    PAPER_RULES,
    OptimalCounterweight,
    SliderCrank,
    optimal_counterweight,
    shaking_force,
    shaking_objective,
)

__all__ = ["plot_force_vs_angle", "plot_force_locus", "plot_objective", "plot_optimal_curve"]

_N_ANGLES = 721


def _figure_and_axes(ax: Axes | None) -> tuple[Figure, Axes]:
    if ax is None:
        figure = Figure()
        return figure, figure.add_subplot()
    return ax.figure, ax


def plot_force_vs_angle(mech: SliderCrank, speed_rpm: float, counterweight_mass_kg: float = 0.0,
                        counterweight_radius_m: float = 0.0, *, ax: Axes | None = None) -> Figure:
    """Force components and resultant against crank angle over one revolution.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min].
    counterweight_mass_kg, counterweight_radius_m : float
        Counterweight [kg], [m].
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes = _figure_and_axes(ax)
    theta = np.linspace(0.0, 2.0 * np.pi, _N_ANGLES)
    force = shaking_force(mech, speed_rpm, theta, counterweight_mass_kg, counterweight_radius_m)
    degrees = np.rad2deg(theta)
    axes.plot(degrees, force.force_x_n, label="F_x (across stroke)")
    axes.plot(degrees, force.force_y_n, label="F_y (along stroke)")
    axes.plot(degrees, force.resultant_n, label="|F|", color="black")
    axes.set_xlabel("crank angle from TDC [deg]")
    axes.set_ylabel("shaking force [N]")
    axes.set_xlim(0.0, 360.0)
    axes.axhline(0.0, color="grey", linewidth=0.5)
    axes.legend()
    return figure


def plot_force_locus(mech: SliderCrank, speed_rpm: float, counterweight_mass_kg: float,
                     counterweight_radius_m: float, *, ax: Axes | None = None) -> Figure:
    """Polar locus of the shaking force (F_x against F_y) before and after balancing.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min].
    counterweight_mass_kg, counterweight_radius_m : float
        The balancing counterweight [kg], [m].
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes = _figure_and_axes(ax)
    theta = np.linspace(0.0, 2.0 * np.pi, _N_ANGLES)
    before = shaking_force(mech, speed_rpm, theta)
    after = shaking_force(mech, speed_rpm, theta, counterweight_mass_kg, counterweight_radius_m)
    axes.plot(before.force_x_n, before.force_y_n, label="no counterweight")
    axes.plot(after.force_x_n, after.force_y_n,
              label=f"m_c = {counterweight_mass_kg * 1e3:.1f} g at r_c = "
                    f"{counterweight_radius_m * 1e3:.2f} mm")
    axes.plot([0.0], [0.0], marker="+", color="black")
    axes.set_xlabel("F_x across stroke [N]")
    axes.set_ylabel("F_y along stroke [N]")
    axes.set_aspect("equal", adjustable="datalim")
    axes.legend()
    return figure


def plot_objective(mech: SliderCrank, speed_rpm: float, optimum: OptimalCounterweight | None = None,
                   balance_fractions=None, *, ax: Axes | None = None) -> Figure:
    """Peak resultant force against balance fraction, with the optimum and the papers' rules.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min].
    optimum : OptimalCounterweight, optional
        Computed if not given.
    balance_fractions : array_like, optional
        ``alpha`` values to draw; default 121 values over the feasible box.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes = _figure_and_axes(ax)
    if optimum is None:
        optimum = optimal_counterweight(mech, speed_rpm, n_curve_points=2)
    if balance_fractions is None:
        lower = -mech.rotating_mass_kg / mech.reciprocating_mass_kg
        balance_fractions = np.linspace(max(lower, -0.5), 1.0, 121)
    alphas = np.asarray(balance_fractions, dtype=float)
    axes.plot(alphas, shaking_objective(mech, speed_rpm, alphas), label="peak |F|")
    axes.plot([optimum.balance_fraction], [optimum.max_force_n], marker="o", linestyle="none",
              color="black",
              label=f"optimum alpha = {optimum.balance_fraction:.4f}, {optimum.max_force_n:.2f} N")
    for name, alpha in PAPER_RULES.items():
        axes.axvline(alpha, color="grey", linestyle=":", linewidth=1.0)
        axes.annotate(name, (alpha, axes.get_ylim()[1]), rotation=90, va="top", ha="right",
                      fontsize="small")
    axes.set_xlabel("balance fraction alpha = (m_c r_c / r - m_rot) / m_rec")
    axes.set_ylabel("peak resultant shaking force [N]")
    axes.legend()
    return figure


def plot_optimal_curve(optimum: OptimalCounterweight, *, ax: Axes | None = None) -> Figure:
    """The family of optimal counterweights: radius against k, mass on a second axis.

    Parameters
    ----------
    optimum : OptimalCounterweight
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes = _figure_and_axes(ax)
    curve = optimum.curve
    axes.plot(curve.k, curve.counterweight_radius_m * 1e3, label="r_c")
    axes.plot(curve.k[:1], curve.counterweight_radius_m[:1] * 1e3, marker="o", linestyle="none",
              color="black", label="lightest (r_c = r)")
    axes.set_xlabel("k  (m_c = m_rot + k m_rec)")
    axes.set_ylabel("counterweight radius r_c [mm]")
    mass_axes = axes.twinx()
    mass_axes.plot(curve.k, curve.counterweight_mass_kg * 1e3, color="tab:orange", label="m_c")
    mass_axes.set_ylabel("counterweight mass m_c [g]")
    axes.set_title(f"optimal counterweights: m_c r_c = {optimum.counterweight_moment_kg_m * 1e6:.1f} "
                   "g mm")
    axes.legend(loc="upper center")
    return figure
