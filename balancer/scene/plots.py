"""The stages' figures, saved as PNG (crash-safely) for the scene runner.

Each stage names its figures function, the results they read and the modules drawing them
imports in :data:`.registry.REGISTRY`.
"""
from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from modal.figures import fixed_figure, png_bytes
from modal.io._atomic import atomic_path

from .registry import REGISTRY, load

__all__ = ["stage_figures", "save_stage_plot", "preload", "frf_figures", "identify_figures", "stability_figures", "response_figures",
           "compressor_figures", "mounts_figures", "drive_figures", "balance_figures"]


def frf_figures(results):
    """An FRF estimated from a time record: its magnitude with the coherence; nothing for an FRF file."""
    from modal.estimate import EstimatedFRF
    from modal.estimate.plots import plot_estimate

    frf = results["frf"]
    return [("estimate", plot_estimate(frf))] if isinstance(frf, EstimatedFRF) else []


def identify_figures(results):
    from modal.plots import plot_fit

    if "frf" not in results:
        return []
    return [("fit", plot_fit(results["frf"], results["identify"]))]


def stability_figures(results):
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


def response_figures(results):
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


def compressor_figures(results):
    from ..compressor.crank_plots import plot_force_locus, plot_objective

    c = results["compressor"]
    return [("force_locus", plot_force_locus(c.mechanism, c.speed_rpm, c.counterweight_mass_kg, c.counterweight_radius_m)),
            ("objective", plot_objective(c.mechanism, c.speed_rpm, c.optimum))]


def mounts_figures(results):
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


def drive_figures(results):
    d = results["drive"]
    fig = Figure(figsize=(7, 3), layout="constrained")
    ax = fig.add_subplot()
    speeds = [d.drive.stages[0].driver_speed_rpm] + [s.driven_speed_rpm for s in d.drive.stages]
    ax.plot(range(len(speeds)), speeds, "o-")
    ax.set_xticks(range(len(speeds)), ["motor"] + [f"stage {i + 1}" for i in range(len(speeds) - 1)])
    ax.set_ylabel("speed [rpm]")
    return [("speeds", fig)]


def balance_figures(results):
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


def preload(stages, modules=()) -> None:
    """Import what drawing the figures of ``stages`` needs (their ``plot_modules``), and their figures functions;
    and ``modules`` (the modules of this run's result classes that its figures are handed: :func:`.registry.result_modules`).

    The plotting process does this once, before it forks its helper, instead of each drawing process
    importing them for itself.
    """
    for name in modules:
        importlib.import_module(name)
    for stage in stages:
        for name in REGISTRY[stage].plot_modules:
            importlib.import_module(name)
        if REGISTRY[stage].figures:
            load(REGISTRY[stage].figures)


def stage_figures(stage: str, results) -> list[tuple[str, Figure]]:
    """(name, Figure) pairs for a stage; empty for stages without a plot."""
    figures = REGISTRY[stage].figures
    if stage not in results or figures is None:
        return []
    return load(figures)(results)


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
