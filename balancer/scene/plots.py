"""One figure per stage, saved as PNG (crash-safely) for the scene runner."""
from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from modal.figures import fixed_figure, png_bytes
from modal.io._atomic import atomic_path

__all__ = ["stage_figures", "save_stage_plot", "PLOT_MODULES", "preload"]


def _identify(results):
    from modal.plots import plot_fit

    if "frf" not in results:
        return []
    return [("fit", plot_fit(results["frf"], results["identify"]))]


def _stability(results):
    stage = results["adb_stability"]
    wn = stage.intervals.natural_frequency_rad_s
    fig = fixed_figure(7, 4, left=0.75, right=0.2, bottom=0.55, top=0.35)
    ax = fig.add_subplot()
    ax.plot(stage.speeds_rad_s / wn, stage.max_real_part_per_s, lw=1.2)
    ax.axhline(0, color="0.5", lw=0.8)
    for lo, hi in stage.intervals.intervals_ratio:
        ax.axvspan(lo, hi, color="tab:green", alpha=0.15, lw=0)
    ax.set_xlabel("speed Ω/ωn")
    ax.set_ylabel("max Re λ of the balanced state [1/s]")
    ax.set_title("balanced state: stable where shaded", y=1.0)  # fixed: nothing above the axes to avoid
    return [("stability", fig)]


def _response(results):
    from ..adb.plots import plot_amplitude, plot_ball_angles, plot_orbit, plot_run_up

    r = results["adb_response"]
    # the left column's log labels (10⁻¹²) and the right column's y label set the gaps
    fig = fixed_figure(10, 7, left=0.85, right=0.15, bottom=0.5, top=0.35, wgap=0.95, hgap=0.6, ncols=2, nrows=2)
    ax_amp, ax_orbit, ax_balls, ax_runup = fig.subplots(2, 2).ravel()
    plot_amplitude(r, ax=ax_amp)
    plot_orbit(r, ax=ax_orbit)
    plot_ball_angles(r, ax=ax_balls)
    wn = results["rotor"].params.natural_frequency_rad_s if "rotor" in results else None
    plot_run_up(r, wn, ax=ax_runup)
    return [("response", fig)]


def _compressor(results):
    from ..compressor.crank_plots import plot_force_locus, plot_objective

    c = results["compressor"]
    return [("force_locus", plot_force_locus(c.mechanism, c.speed_rpm, c.counterweight_mass_kg, c.counterweight_radius_m)),
            ("objective", plot_objective(c.mechanism, c.speed_rpm, c.optimum))]


def _mounts(results):
    m = results["mounts"]
    fig = fixed_figure(7, 4, left=0.7, right=0.15, bottom=0.5, top=0.15)  # bottom: the rotated tick labels
    ax = fig.add_subplot()
    before = m.comparison.base_force_amplitude_before_n
    after = m.comparison.base_force_amplitude_after_n
    labels = [f"{order}x {axis}" for order in range(1, before.shape[0] + 1) for axis in "xyz"]
    x = np.arange(len(labels))
    ax.bar(x - 0.2, before.ravel(), 0.4, label="before balancing")
    ax.bar(x + 0.2, after.ravel(), 0.4, label="after balancing")
    ax.set_xticks(x, labels, rotation=90, fontsize="small")
    ax.set_ylabel("force into the base [N]")
    ax.legend(fontsize="small")
    return [("base_force", fig)]


def _drive(results):
    d = results["drive"]
    fig = Figure(figsize=(7, 3), layout="constrained")
    ax = fig.add_subplot()
    speeds = [d.drive.stages[0].driver_speed_rpm] + [s.driven_speed_rpm for s in d.drive.stages]
    ax.plot(range(len(speeds)), speeds, "o-")
    ax.set_xticks(range(len(speeds)), ["motor"] + [f"stage {i + 1}" for i in range(len(speeds) - 1)])
    ax.set_ylabel("speed [rpm]")
    return [("speeds", fig)]


def _balance(results):
    from ..influence.plots import plot_balance

    b = results["balance"]
    figures = [("polar", plot_balance(b.report))]
    if b.study is not None:
        st = b.study
        fig = Figure(figsize=(7, 4), layout="constrained")
        ax = fig.add_subplot()
        w = st.speeds_rad_s
        ax.semilogy(w, st.amplitude_before_m * 1e6, "o-", label="before")
        ax.semilogy(w, st.amplitude_least_squares_m * 1e6, "s--", label="least squares")
        ax.semilogy(w, st.amplitude_minmax_m * 1e6, "^--", label="min-max")
        ax.semilogy(w, st.amplitude_model_only_m * 1e6, "x:", label="model alpha only (no trial)")
        if np.isfinite(st.adb_residual_amplitude_m):
            ax.semilogy([st.adb_speed_rad_s], [st.adb_residual_amplitude_m * 1e6], "*", ms=12, label="ball balancer")
        ax.set_xlabel("speed [rad/s]")
        ax.set_ylabel("1x amplitude [µm]")
        ax.legend(fontsize="small")
        figures.append(("comparison", fig))
    return figures


_FIGURES = {"identify": _identify, "adb_stability": _stability, "adb_response": _response,
            "compressor": _compressor, "mounts": _mounts, "drive": _drive, "balance": _balance}


#: the modules a stage's figures import when drawn from its plot inputs (runner._PLOT_INPUTS) in a plotting
#: process, which holds only what drawing needs (balancer._plotter): the plotting functions and the classes of
#: the results unpickled for them (tests/balancer/scene/test_plot_jobs.py checks it). The plotting process imports them
#: once, before it forks its helper, instead of each drawing process importing them for itself.
PLOT_MODULES = {
    "identify": ("modal.plots", "modal.flags"),
    "adb_stability": ("balancer.scene.stages",),  # the stage results' classes (StabilityStage, ...)
    "adb_response": ("balancer.adb.plots", "balancer.scene.stages"),
    "compressor": ("balancer.compressor.crank_plots", "balancer.scene.stages"),
    "mounts": ("balancer.compressor.mounts", "balancer.scene.stages"),
    "drive": ("balancer.drive", "balancer.drive.shaft", "balancer.scene.stages"),
    "balance": ("balancer.influence.plots", "balancer.influence.study", "balancer.scene.stages"),
}


def preload(stages) -> None:
    """Import what drawing the figures of ``stages`` needs (:data:`PLOT_MODULES`)."""
    for stage in stages:
        for name in PLOT_MODULES.get(stage, ()):
            importlib.import_module(name)


def stage_figures(stage: str, results) -> list[tuple[str, Figure]]:
    """(name, Figure) pairs for a stage; empty for stages without a plot."""
    if stage not in results or stage not in _FIGURES:
        return []
    return _FIGURES[stage](results)


def save_stage_plot(stage: str, results, folder: Path) -> list[Path]:
    """Save a stage's figures as PNG files in ``folder``; returns their paths."""
    paths = []
    for name, fig in stage_figures(stage, results):
        path = Path(folder) / f"{stage}_{name}.png"
        data = png_bytes(fig, dpi=100)  # savefig's pixels, encoded in 40 % of its time
        with atomic_path(path) as tmp:
            Path(tmp).write_bytes(data)
        paths.append(path)
    return paths
