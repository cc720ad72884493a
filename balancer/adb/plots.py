"""Plots of ADB results.  Each function takes a result and an optional Axes and returns the
Figure; without Axes it builds ``matplotlib.figure.Figure()`` itself, so pyplot's global
state is never touched (nothing is shown, no rcParams changes)."""
from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from modal.figures import plain_log_ticks

from .simulate import SimulationResult
from .stability import StabilityMap
from .studies import SettlingStudy

__all__ = [
    "plot_stability_map",
    "plot_orbit",
    "plot_amplitude",
    "plot_ball_angles",
    "plot_run_up",
    "plot_settling_study",
]

_UNITS = {"M": "kg", "m": "kg", "n": "", "R": "m", "e": "m", "k": "N/m", "c": "N s/m", "D": "N m s"}


def _axes(ax: Axes | None) -> tuple[Figure, Axes]:
    if ax is not None:
        return ax.figure, ax
    figure = Figure()
    return figure, figure.add_subplot()


def plot_stability_map(result: StabilityMap, *, ax: Axes | None = None) -> Figure:
    """Stable / marginal / unstable regions of the balanced state over speed and a parameter.

    Parameters
    ----------
    result : StabilityMap
        From :func:`~balancer.adb.stability_map`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in.
    """
    figure, ax = _axes(ax)
    cmap = ListedColormap(["#d9534f", "#f0ad4e", "#5cb85c"])  # unstable, marginal, stable
    ratio = result.speed_ratio.mean(axis=0) if np.allclose(result.speed_ratio, result.speed_ratio[:1]) else None
    x = ratio if ratio is not None else result.speeds_rad_s
    mesh = ax.pcolormesh(x, result.values, result.stability_class, cmap=cmap, vmin=-1.5, vmax=1.5, shading="nearest")
    if result.values.size > 2 and np.all(result.values > 0) and result.values.max() / result.values.min() > 100:
        ax.set_yscale("log")
    ax.set_xlabel("speed ratio Ω/ωn" if ratio is not None else "speed (rad/s)")
    unit = _UNITS.get(result.parameter, "")
    ax.set_ylabel(f"{result.parameter} ({unit})" if unit else result.parameter)
    ax.set_title("balanced state: green stable, orange marginal, red unstable")
    colorbar = figure.colorbar(mesh, ax=ax, ticks=[-1, 0, 1])
    colorbar.ax.set_yticklabels(["unstable", "marginal", "stable"])
    return figure


def plot_orbit(result: SimulationResult, *, ax: Axes | None = None) -> Figure:
    """Rotor orbit in the fixed frame, with and (if computed) without balls (mm).

    Parameters
    ----------
    result : SimulationResult
        From :func:`~balancer.adb.simulate`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in.
    """
    figure, ax = _axes(ax)
    if result.rotor_x_without_balls_m.size:
        ax.plot(1e3 * result.rotor_x_without_balls_m, 1e3 * result.rotor_y_without_balls_m,
                lw=0.6, color="0.6", label="without balls")
    ax.plot(1e3 * result.rotor_x_m, 1e3 * result.rotor_y_m, lw=0.6, label="with balls")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(loc="upper right")
    return figure


def plot_amplitude(result: SimulationResult, *, ax: Axes | None = None, log: bool = True) -> Figure:
    """Vibration amplitude against time with and (if computed) without balls.

    Parameters
    ----------
    result : SimulationResult
        From :func:`~balancer.adb.simulate`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in.
    log : bool
        Logarithmic amplitude axis (shows the decay to the rounding floor).
    """
    figure, ax = _axes(ax)
    if result.amplitude_without_balls_m.size:
        ax.plot(result.time_s, result.amplitude_without_balls_m, color="0.6", label="without balls")
    ax.plot(result.time_s, result.amplitude_m, label="with balls")
    if np.isfinite(result.settling_time_s):
        ax.axvline(result.settling_time_s, ls="--", color="k", lw=0.8, label="balls settled")
    if log:
        ax.set_yscale("log")
        plain_log_ticks(ax.yaxis)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("amplitude (m)")
    # y given: nothing sits above this axes, so matplotlib's search for a free place (which lays out
    # the y tick labels once more) would leave the title where it is
    ax.set_title(f"final state: {result.final_state}", y=1.0)
    ax.legend(loc="best")
    return figure


def _break_at_wraps(time_s: np.ndarray, angle_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The curve with a gap (NaN) where the wrapped angle jumps by more than 180°, so that a ball passing
    ±180° is not drawn as a vertical line across the panel."""
    jumps = np.flatnonzero(np.abs(np.diff(angle_deg)) > 180.0) + 1
    return (np.insert(np.asarray(time_s, float), jumps, np.nan),
            np.insert(np.asarray(angle_deg, float), jumps, np.nan))


def plot_ball_angles(result: SimulationResult, *, ax: Axes | None = None) -> Figure:
    """Ball angles relative to the unbalance (degrees) against time, with the balanced angles.

    Parameters
    ----------
    result : SimulationResult
        From :func:`~balancer.adb.simulate`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in.
    """
    figure, ax = _axes(ax)
    wrapped = np.degrees(np.angle(np.exp(1j * result.ball_angles_rad)))
    for index in range(wrapped.shape[1]):
        time_s, angle = _break_at_wraps(result.time_s, wrapped[:, index])
        ax.plot(time_s, angle, lw=0.8, label=f"ball {index + 1}")
    for angle in np.degrees(result.balanced_ball_angles_rad):
        ax.axhline(angle, ls=":", color="k", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ball angle from unbalance (deg)")
    ax.set_ylim(-180, 180)
    ax.legend(loc="best")
    return figure


def plot_run_up(result: SimulationResult, natural_frequency_rad_s: float | None = None, *,
                ax: Axes | None = None) -> Figure:
    """Amplitude against shaft speed during a run-up, with and without balls.

    Parameters
    ----------
    result : SimulationResult
        A run with a speed profile.
    natural_frequency_rad_s : float, optional
        If given, the speed axis is ``omega / omega_n``.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in.
    """
    figure, ax = _axes(ax)
    x = result.speed_rad_s / natural_frequency_rad_s if natural_frequency_rad_s else result.speed_rad_s
    if result.amplitude_without_balls_m.size:
        ax.plot(x, result.amplitude_without_balls_m, color="0.6", lw=0.8, label="without balls")
    ax.plot(x, result.amplitude_m, lw=0.8, label="with balls")
    ax.set_xlabel("speed ratio Ω/ωn" if natural_frequency_rad_s else "speed (rad/s)")
    ax.set_ylabel("amplitude (m)")
    ax.legend(loc="best")
    return figure


def plot_settling_study(study: SettlingStudy, *, ax: Axes | None = None) -> Figure:
    """Settling time against the varied parameter.

    Parameters
    ----------
    study : SettlingStudy
        From :func:`~balancer.adb.settling_study`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw in.
    """
    figure, ax = _axes(ax)
    finite = np.isfinite(study.settling_time_s)
    ax.plot(study.values[finite], study.settling_time_s[finite], "o-")
    if np.any(~finite):
        ax.plot(study.values[~finite], np.full(np.sum(~finite), study.t_end_s), "x", color="r",
                label="not settled")
        ax.legend(loc="best")
    unit = _UNITS.get(study.parameter, "")
    ax.set_xlabel(f"{study.parameter} ({unit})" if unit else study.parameter)
    ax.set_ylabel("settling time (s)")
    ax.set_title(f"Ω/ωn = {study.speed_ratio:g}")
    return figure
