"""The readable summary of a scene run, and a JSON-ready digest of its results."""
from __future__ import annotations

import math

import numpy as np

from modal.report import format_table

from .schema import STAGES

__all__ = ["format_summary", "digest"]


def _fmt(value, unit="", digits=5):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}g}{(' ' + unit) if unit else ''}"


def digest(stage: str, result) -> dict:
    """A few headline numbers of a stage result (SI units, JSON-ready)."""
    if stage == "frf":
        return {"n_channels": result.n_channels, "n_lines": result.n_freq, "kind": result.kind}
    if stage == "identify":
        return {"modes": result.rows()}
    if stage == "rotor":
        p = result.params
        return {"M_kg": p.M, "m_kg": p.m, "n": p.n, "R_m": p.R, "e_m": p.e, "k_n_per_m": p.k, "c_n_s_per_m": p.c,
                "D_n_m_s": p.D, "natural_frequency_rad_s": p.natural_frequency_rad_s,
                "std": {"M_kg": result.std.M, "k_n_per_m": result.std.k, "c_n_s_per_m": result.std.c}}
    if stage == "adb_stability":
        return {"stable_intervals_rad_s": [list(map(float, row)) for row in result.intervals.intervals_rad_s],
                "stable_intervals_ratio": [list(map(float, row)) for row in result.intervals.intervals_ratio],
                "natural_frequency_rad_s": float(result.intervals.natural_frequency_rad_s)}
    if stage == "adb_response":
        return {"final_state": result.final_state, "settling_time_s": float(result.settling_time_s),
                "residual_amplitude_m": float(result.residual_amplitude_m),
                "residual_amplitude_without_balls_m": float(result.residual_amplitude_without_balls_m),
                "peak_amplitude_m": float(np.max(result.amplitude_m))}
    if stage == "compressor":
        o = result.optimum
        return {"balance_fraction": float(o.balance_fraction), "max_force_n": float(o.max_force_n),
                "unbalanced_max_force_n": float(o.unbalanced_max_force_n),
                "counterweight_mass_kg": result.counterweight_mass_kg,
                "counterweight_radius_m": result.counterweight_radius_m, "speed_rpm": result.speed_rpm}
    if stage == "mounts":
        before = result.comparison.base_force_amplitude_before_n
        after = result.comparison.base_force_amplitude_after_n
        return {"natural_frequencies_hz": [float(f) for f in result.natural_frequencies_hz],
                "base_force_1x_before_n": [float(v) for v in before[0]],
                "base_force_1x_after_n": [float(v) for v in after[0]]}
    if stage == "drive":
        d = {"driven_speed_rpm": float(result.drive.stages[-1].driven_speed_rpm)}
        if result.handover is not None:
            h = result.handover
            d.update(speed_rad_s=float(h.speed_rad_s), stiffness_n_per_m=float(h.stiffness_n_per_m),
                     speed_ratio_to_critical=float(h.speed_ratio))
        return d
    return {}


def _table(stage: str, result) -> list[str]:
    d = digest(stage, result)
    if stage == "identify":
        return [format_table(result)]
    if stage == "rotor":
        return [f"  M = {_fmt(d['M_kg'], 'kg')} (± {_fmt(d['std']['M_kg'], digits=2)}), k = {_fmt(d['k_n_per_m'], 'N/m')} "
                f"(± {_fmt(d['std']['k_n_per_m'], digits=2)}), c = {_fmt(d['c_n_s_per_m'], 'N s/m')} "
                f"(± {_fmt(d['std']['c_n_s_per_m'], digits=2)}), e = {_fmt(d['e_m'], 'm')}",
                f"  balls: n = {d['n']}, m = {_fmt(d['m_kg'], 'kg')}, R = {_fmt(d['R_m'], 'm')}, D = {_fmt(d['D_n_m_s'], 'N m s')};"
                f" ωn = {_fmt(d['natural_frequency_rad_s'], 'rad/s')}"]
    if stage == "adb_stability":
        rows = [f"  stable from {lo:.5g} to {hi:.5g} rad/s  (Ω/ωn {rlo:.4f} – {rhi:.4f})"
                for (lo, hi), (rlo, rhi) in zip(d["stable_intervals_rad_s"], d["stable_intervals_ratio"])]
        return rows or ["  the balanced state is not stable at any speed scanned"]
    if stage == "adb_response":
        return [f"  final state: {d['final_state']}; settling time {_fmt(d['settling_time_s'], 's')}; residual amplitude "
                f"{_fmt(d['residual_amplitude_m'], 'm', 3)} with balls, {_fmt(d['residual_amplitude_without_balls_m'], 'm', 3)} "
                f"without; peak {_fmt(d['peak_amplitude_m'], 'm', 3)}"]
    if stage == "compressor":
        return [f"  optimum balance fraction α* = {d['balance_fraction']:.7g}: max shaking force {d['max_force_n']:.6g} N "
                f"(without counterweight {d['unbalanced_max_force_n']:.6g} N) at {d['speed_rpm']:g} rpm",
                f"  counterweight {d['counterweight_mass_kg'] * 1e3:.5g} g at r_c = {d['counterweight_radius_m'] * 1e3:.5g} mm"]
    if stage == "mounts":
        freqs = ", ".join(f"{f:.4g}" for f in d["natural_frequencies_hz"])
        b, a = np.linalg.norm(d["base_force_1x_before_n"]), np.linalg.norm(d["base_force_1x_after_n"])
        return [f"  body modes: {freqs} Hz", f"  1x force into the base: {b:.4g} N before, {a:.4g} N after balancing"]
    if stage == "drive":
        line = f"  driven speed {d['driven_speed_rpm']:.5g} rpm"
        if "stiffness_n_per_m" in d:
            line += (f"; hand-over: Ω = {d['speed_rad_s']:.5g} rad/s, k = {d['stiffness_n_per_m']:.5g} N/m, "
                     f"Ω/ω_crit = {d['speed_ratio_to_critical']:.3g}")
        return [line]
    if stage == "frf":
        return [f"  {d['n_channels']} channel(s), {d['n_lines']} lines, {d['kind']}"]
    return []


def format_summary(name, status, results, tables, timings, archive_path, plot_paths) -> str:
    """Stage statuses, the requested tables, and where the outputs are."""
    lines = [f"scene: {name}", "", "stages:"]
    for stage in STAGES:
        extra = f" ({timings[stage]:.2f} s)" if stage in timings else ""
        lines.append(f"  {stage:<14} {status[stage]}{extra}")
    for stage in tables:
        if stage in results:
            lines += ["", f"[{stage}]"] + _table(stage, results[stage])
    if archive_path:
        lines += ["", f"archive: {archive_path}"]
    if plot_paths:
        lines += [f"plots: {', '.join(map(str, plot_paths))}"]
    return "\n".join(lines)
