"""The readable summary of a scene run, and a JSON-ready digest of its results."""
from __future__ import annotations

import math

import numpy as np

from modal.report import format_table

from .registry import REGISTRY, STAGES, load

__all__ = ["format_summary", "digest"]


def _fmt(value, unit="", digits=5):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}g}{(' ' + unit) if unit else ''}"


def digest(stage: str, result) -> dict:
    """A few headline numbers of a stage result (SI units, JSON-ready); empty for a stage without them."""
    entry = REGISTRY.get(stage)
    return load(entry.digest)(result) if entry is not None and entry.digest else {}


def _table(stage: str, result) -> list[str]:
    entry = REGISTRY[stage]
    return load(entry.rows)(result, digest(stage, result)) if entry.rows else []


# ------------------------------------------------------------------ each stage's digest and summary rows
# (named by the stage's entry in balancer.scene.registry; a row function gets the result and its digest)
def frf_digest(result) -> dict:
    from modal.estimate import EstimatedFRF

    d = {"n_channels": result.n_channels, "n_lines": result.n_freq, "kind": result.kind}
    if isinstance(result, EstimatedFRF):  # estimated from a time record in the scene
        d["estimate"] = {"source": result.source, "estimator": result.estimator, "window": result.window,
                         "averages": result.averages, "rejected": [dict(r) for r in result.rejected],
                         "overloads": [dict(o) for o in result.overloads],
                         "unrelated": [dict(u) for u in result.unrelated],
                         "excitation_points": list(result.reference_points or ()),
                         "response_points": list(result.response_points or ())}
    return d


def frf_rows(result, d: dict) -> list[str]:
    rows = [f"  {d['n_channels']} channel(s), {d['n_lines']} lines, {d['kind']}"]
    est = d.get("estimate")
    if est is not None:
        rejected = "; ".join(f"hit {r['hit']} at {r['time_s']:.3g} s: {r['reason']}" for r in est["rejected"])
        rows.append(f"  estimated from {est['source']}: {est['estimator']}, {est['averages']} average(s), window "
                    f"{est['window']}; {len(est['rejected'])} hit(s) rejected{': ' + rejected if rejected else ''}")
    return rows


def identify_digest(result) -> dict:
    return {"modes": result.rows()}


def identify_rows(result, d: dict) -> list[str]:
    return [format_table(result)]


def rotor_digest(result) -> dict:
    p = result.params
    return {"M_kg": p.M, "m_kg": p.m, "n": p.n, "R_m": p.R, "e_m": p.e, "k_n_per_m": p.k, "c_n_s_per_m": p.c,
            "D_n_m_s": p.D, "natural_frequency_rad_s": p.natural_frequency_rad_s,
            "std": {"M_kg": result.std.M, "k_n_per_m": result.std.k, "c_n_s_per_m": result.std.c},
            "sources": list(result.sources)}


def rotor_rows(result, d: dict) -> list[str]:
    return [f"  M = {_fmt(d['M_kg'], 'kg')} (± {_fmt(d['std']['M_kg'], digits=2)}), k = {_fmt(d['k_n_per_m'], 'N/m')} "
            f"(± {_fmt(d['std']['k_n_per_m'], digits=2)}), c = {_fmt(d['c_n_s_per_m'], 'N s/m')} "
            f"(± {_fmt(d['std']['c_n_s_per_m'], digits=2)}), e = {_fmt(d['e_m'], 'm')}",
            f"  balls: n = {d['n']}, m = {_fmt(d['m_kg'], 'kg')}, R = {_fmt(d['R_m'], 'm')}, D = {_fmt(d['D_n_m_s'], 'N m s')};"
            f" ωn = {_fmt(d['natural_frequency_rad_s'], 'rad/s')}"] + [f"  {s}" for s in d["sources"]]


def stability_digest(result) -> dict:
    return {"stable_intervals_rad_s": [list(map(float, row)) for row in result.intervals.intervals_rad_s],
            "stable_intervals_ratio": [list(map(float, row)) for row in result.intervals.intervals_ratio],
            "natural_frequency_rad_s": float(result.intervals.natural_frequency_rad_s)}


def stability_rows(result, d: dict) -> list[str]:
    rows = [f"  stable from {lo:.5g} to {hi:.5g} rad/s  (Ω/ωn {rlo:.4f} – {rhi:.4f})"
            for (lo, hi), (rlo, rhi) in zip(d["stable_intervals_rad_s"], d["stable_intervals_ratio"])]
    return rows or ["  the balanced state is not stable at any speed scanned"]


def response_digest(result) -> dict:
    return {"final_state": result.final_state, "settling_time_s": float(result.settling_time_s),
            "residual_amplitude_m": float(result.residual_amplitude_m),
            "residual_amplitude_without_balls_m": float(result.residual_amplitude_without_balls_m),
            "peak_amplitude_m": float(np.max(result.amplitude_m))}


def response_rows(result, d: dict) -> list[str]:
    return [f"  final state: {d['final_state']}; settling time {_fmt(d['settling_time_s'], 's')}; residual amplitude "
            f"{_fmt(d['residual_amplitude_m'], 'm', 3)} with balls, {_fmt(d['residual_amplitude_without_balls_m'], 'm', 3)} "
            f"without; peak {_fmt(d['peak_amplitude_m'], 'm', 3)}"]


def compressor_digest(result) -> dict:
    o = result.optimum
    return {"balance_fraction": float(o.balance_fraction), "max_force_n": float(o.max_force_n),
            "unbalanced_max_force_n": float(o.unbalanced_max_force_n),
            "counterweight_mass_kg": result.counterweight_mass_kg,
            "counterweight_radius_m": result.counterweight_radius_m, "speed_rpm": result.speed_rpm}


def compressor_rows(result, d: dict) -> list[str]:
    return [f"  optimum balance fraction α* = {d['balance_fraction']:.7g}: max shaking force {d['max_force_n']:.6g} N "
            f"(without counterweight {d['unbalanced_max_force_n']:.6g} N) at {d['speed_rpm']:g} rpm",
            f"  counterweight {d['counterweight_mass_kg'] * 1e3:.5g} g at r_c = {d['counterweight_radius_m'] * 1e3:.5g} mm"]


def mounts_digest(result) -> dict:
    before = result.comparison.base_force_amplitude_before_n
    after = result.comparison.base_force_amplitude_after_n
    return {"natural_frequencies_hz": [float(f) for f in result.natural_frequencies_hz],
            "base_force_1x_before_n": [float(v) for v in before[0]],
            "base_force_1x_after_n": [float(v) for v in after[0]]}


def mounts_rows(result, d: dict) -> list[str]:
    freqs = ", ".join(f"{f:.4g}" for f in d["natural_frequencies_hz"])
    b, a = np.linalg.norm(d["base_force_1x_before_n"]), np.linalg.norm(d["base_force_1x_after_n"])
    return [f"  body modes: {freqs} Hz", f"  1x force into the base: {b:.4g} N before, {a:.4g} N after balancing"]


def drive_digest(result) -> dict:
    d = {"driven_speed_rpm": float(result.drive.stages[-1].driven_speed_rpm)}
    if result.handover is not None:
        h = result.handover
        d.update(speed_rad_s=float(h.speed_rad_s), stiffness_n_per_m=float(h.stiffness_n_per_m),
                 speed_ratio_to_critical=float(h.speed_ratio))
    return d


def drive_rows(result, d: dict) -> list[str]:
    line = f"  driven speed {d['driven_speed_rpm']:.5g} rpm"
    if "stiffness_n_per_m" in d:
        line += (f"; hand-over: Ω = {d['speed_rad_s']:.5g} rad/s, k = {d['stiffness_n_per_m']:.5g} N/m, "
                 f"Ω/ω_crit = {d['speed_ratio_to_critical']:.3g}")
    return [line]


def balance_digest(result) -> dict:
    r = result.report
    amplitude, _ = r.in_user_units(r.initial)
    left, _ = r.in_user_units(r.residual)
    from balancer.influence.readings import reading_unit, user_digits

    d = {"method": r.method, "reading_units": reading_unit(r.reading_units).label, "mass_units": r.mass_units,
         "correction_mass": [float(m) * (1e3 if r.mass_units == "g" else 1.0) for m in r.correction_mass_kg],
         "correction_angle_deg": [float(a) for a in r.correction_angle_deg],
         "correction_kg_m": [[float(u.real), float(u.imag)] for u in r.correction_kg_m],
         "worst_initial": float(np.max(amplitude)), "worst_residual": float(np.max(left)),
         "condition_number": r.condition_number, "flags": list(r.flags)}
    if r.positions_deg.size:
        d["split"] = [{f"{p:g}": float(user_digits(m * (1e3 if r.mass_units == "g" else 1.0)))
                       for p, m in zip(r.positions_deg, row) if m > 0} for row in r.split_mass_kg]
        if r.weight_resolution_kg is not None:
            d["weight_resolution"] = float(user_digits(r.weight_resolution_kg * (1e3 if r.mass_units == "g" else 1.0)))
    if r.iso is not None:
        d["iso"] = {"grade_mm_s": r.iso.grade_mm_s, "verdict": r.iso.verdict,
                    "permissible_per_plane_kg_m": [float(v) for v in r.iso.permissible_per_plane_kg_m],
                    "residual_unbalance_kg_m": [float(v) for v in r.iso.residual_unbalance_kg_m]}
    from balancer.influence.job import check_run_summary, spread_summary

    if r.spread is not None:
        d["spread"] = spread_summary(r)
    if r.check is not None:
        d["check_run"] = check_run_summary(r)
    st = result.study
    if st is not None:
        d["study"] = {"speeds_rad_s": [float(w) for w in st.speeds_rad_s],
                      "alpha_model_error": [float(v) for v in st.alpha_model_error],
                      "alpha_measured_error": [float(v) for v in st.alpha_measured_error],
                      "amplitude_before_m": [float(v) for v in st.amplitude_before_m],
                      "amplitude_least_squares_m": [float(v) for v in st.amplitude_least_squares_m],
                      "amplitude_minmax_m": [float(v) for v in st.amplitude_minmax_m],
                      "amplitude_model_only_m": [float(v) for v in st.amplitude_model_only_m],
                      "adb_speed_rad_s": st.adb_speed_rad_s, "adb_residual_amplitude_m": st.adb_residual_amplitude_m,
                      "adb_amplitude_without_balls_m": st.adb_amplitude_without_balls_m}
    return d


def balance_rows(result, d: dict) -> list[str]:
    unit = d["mass_units"]
    lines = [f"  {d['method']}: " + "; ".join(f"plane {j + 1}: {m:.4g} {unit} at {a:.1f} deg"
                                             for j, (m, a) in enumerate(zip(d["correction_mass"], d["correction_angle_deg"]))),
             f"  worst reading {d['worst_initial']:.4g} -> {d['worst_residual']:.3g} {d['reading_units']} predicted; "
             f"condition number {d['condition_number']:.3g}{'; flags: ' + ', '.join(d['flags']) if d['flags'] else ''}"]
    for j, row in enumerate(d.get("split", [])):
        lines.append(f"  plane {j + 1} on holes: " + ", ".join(f"{m:.4g} {unit} at {p} deg" for p, m in row.items())
                     + (f" (to {d['weight_resolution']:g} {unit})" if "weight_resolution" in d else ""))
    if "iso" in d:
        iso = d["iso"]
        lines.append(f"  ISO 21940-11 G {iso['grade_mm_s']:g}: {iso['verdict']} (residual "
                     + ", ".join(f"{r * 1e6:.4g}" for r in iso["residual_unbalance_kg_m"]) + " g mm, permissible "
                     + ", ".join(f"{p * 1e6:.4g}" for p in iso["permissible_per_plane_kg_m"]) + " g mm)")
    from balancer.influence.job import check_run_lines, spread_lines

    if "spread" in d:
        lines += [f"  {line}" for line in spread_lines(d["spread"], d["reading_units"], unit)]
    if "check_run" in d:
        lines += [f"  {line}" for line in check_run_lines(d["check_run"], d["reading_units"], unit)]
    if "study" in d:
        st = d["study"]
        for i, w in enumerate(st["speeds_rad_s"]):
            lines.append(f"  {w:.4g} rad/s: alpha error {100 * st['alpha_model_error'][i]:.2g} % (model), "
                         f"{100 * st['alpha_measured_error'][i]:.2g} % (trial run); 1x amplitude "
                         f"{st['amplitude_before_m'][i] * 1e6:.4g} µm before, {st['amplitude_least_squares_m'][i] * 1e6:.3g} "
                         f"(least squares), {st['amplitude_minmax_m'][i] * 1e6:.3g} (min-max), "
                         f"{st['amplitude_model_only_m'][i] * 1e6:.3g} (model alpha, no trial) µm")
        if math.isfinite(st["adb_residual_amplitude_m"]):
            lines.append(f"  ball balancer at {st['adb_speed_rad_s']:.4g} rad/s: {st['adb_residual_amplitude_m'] * 1e6:.3g} µm "
                         f"(without balls {st['adb_amplitude_without_balls_m'] * 1e6:.4g} µm)")
    return lines


def format_summary(name, status, results, tables, timings, archive_path, plot_paths, warnings=None) -> str:
    """Stage statuses (with the number of warnings each gave), the requested tables, the warnings, and where the
    outputs are."""
    warnings = warnings or {}
    lines = [f"scene: {name}", "", "stages:"]
    for stage in STAGES:
        extra = f" ({timings[stage]:.2f} s)" if stage in timings else ""
        said = len(warnings.get(stage, ()))
        extra += f", {said} warning{'s' if said > 1 else ''}" if said else ""
        lines.append(f"  {stage:<14} {status[stage]}{extra}")
    for stage in tables:
        if stage in results:
            lines += ["", f"[{stage}]"] + _table(stage, results[stage])
    if warnings:
        # the numbers above stand on data these warnings question: they are repeated here, after the tables
        lines += ["", "warnings:"] + [f"  [{stage}] {text}" for stage in STAGES for text in warnings.get(stage, ())]
    if archive_path:
        lines += ["", f"archive: {archive_path}"]
    if plot_paths:
        lines += [f"plots: {', '.join(map(str, plot_paths))}"]
    return "\n".join(lines)
