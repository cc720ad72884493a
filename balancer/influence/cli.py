"""``python -m balancer influence READINGS.toml``: the weekly balancing job without a scene.

Prints the correction per plane (mass at the file's radius and angle), its split onto
holes, the predicted vibration per reading and, with ``--grade``, the ISO 21940-11
verdict; ``--json`` prints the same as one JSON document.  Exit codes as ``run``.
"""
from __future__ import annotations

import argparse
import json
import sys

from modal.errors import ModalError, ParameterError
from modal.report import jsonable

__all__ = ["add_parser", "run", "report_document"]


def add_parser(sub) -> argparse.ArgumentParser:
    """Add the ``influence`` sub-command to an argparse sub-parser set."""
    p = sub.add_parser("influence", help="influence-coefficient balancing from a readings file",
                       description="Correction masses from initial and trial-run readings (influence coefficients).")
    p.add_argument("readings", help="readings TOML file (see data/synthetic/balance_readings.toml)")
    p.add_argument("--method", choices=("least_squares", "minmax"), default=None,
                   help="least squares (default) or min-max (smallest worst reading)")
    p.add_argument("--grade", type=float, metavar="G", help="ISO 21940-11 balance quality grade G (mm/s), e.g. 2.5")
    p.add_argument("--rotor-mass", type=float, metavar="KG", help="rotor mass (kg) for the ISO check")
    p.add_argument("--speed-rpm", type=float, metavar="RPM", help="maximum service speed (rpm) for the ISO check")
    p.add_argument("--holes", type=int, metavar="N", help="split the correction onto N equally spaced holes (first at the mark)")
    p.add_argument("--weight-resolution", type=float, metavar="MASS",
                   help="round the masses on the holes to multiples of MASS (in the readings file's mass units), "
                        "the smallest step of the weights at hand")
    p.add_argument("--max-correction", type=float, metavar="KG_M", help="largest correction per plane (kg m)")
    p.add_argument("--reading-noise", type=float, metavar="FRACTION",
                   help="relative repeatability of a reading (default 0.05: 5 %%), against which a check run "
                        "([after]) is judged")
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    return p


def report_document(report) -> dict:
    """The report as a JSON-ready dict (user units for readings and masses; SI where named)."""
    from .job import check_run_summary, spread_summary
    from .readings import reading_unit, user_digits

    scale = 1e3 if report.mass_units == "g" else 1.0
    amp0, ph0 = report.in_user_units(report.initial)
    amp1, ph1 = report.in_user_units(report.residual)
    doc = {
        "method": report.method, "reading_units": reading_unit(report.reading_units).label,
        "mass_units": report.mass_units,
        "correction": [{"plane": j + 1, "mass": float(report.correction_mass_kg[j] * scale),
                        "angle_deg": float(report.correction_angle_deg[j]), "radius_m": float(report.radius_m[j]),
                        "unbalance_kg_m": float(abs(report.correction_kg_m[j]))}
                       for j in range(report.correction_kg_m.size)],
        "readings": [{"sensor": s, "initial_amplitude": float(amp0[i]), "initial_phase_deg": float(ph0[i]),
                      "predicted_amplitude": float(amp1[i]), "predicted_phase_deg": float(ph1[i])}
                     for i, s in enumerate(report.sensors)],
        "worst_initial": float(amp0.max()), "worst_residual": float(amp1.max()),
        "rms_initial": float((amp0**2).mean() ** 0.5), "rms_residual": float((amp1**2).mean() ** 0.5),
        "condition_number": report.condition_number, "flags": list(report.flags),
    }
    if report.spread is not None:
        doc["spread"] = spread_summary(report)
    if report.check is not None:
        amp2, ph2 = report.in_user_units(report.check.measured)
        for i, row in enumerate(doc["readings"]):
            row["measured_amplitude"], row["measured_phase_deg"] = float(amp2[i]), float(ph2[i])
        doc["check_run"] = check_run_summary(report)
    if report.positions_deg.size:
        doc["split"] = [[{"hole_deg": float(p), "mass": float(user_digits(m * scale))}
                         for p, m in zip(report.positions_deg, row) if m > 0] for row in report.split_mass_kg]
        if report.weight_resolution_kg is not None:
            doc["weight_resolution"] = float(user_digits(report.weight_resolution_kg * scale))
    if report.iso is not None:
        iso = report.iso
        doc["iso"] = {"grade_mm_s": iso.grade_mm_s, "verdict": iso.verdict,
                      "permissible_unbalance_kg_m": iso.permissible_unbalance_kg_m,
                      "permissible_per_plane_kg_m": [float(v) for v in iso.permissible_per_plane_kg_m],
                      "residual_unbalance_kg_m": [float(v) for v in iso.residual_unbalance_kg_m],
                      "passes": [bool(v) for v in iso.passes]}
    return doc


def _text(doc: dict) -> str:
    from .job import check_run_lines, spread_lines

    unit, mu = doc["reading_units"], doc["mass_units"]
    lines = [f"method: {doc['method']}", "", "correction (add):"]
    for c in doc["correction"]:
        lines.append(f"  plane {c['plane']}: {c['mass']:.4g} {mu} at {c['angle_deg']:.1f} deg (radius {c['radius_m']:g} m)")
    for j, row in enumerate(doc.get("split", [])):
        lines.append(f"  plane {j + 1} on holes: " + ", ".join(f"{h['mass']:.4g} {mu} at {h['hole_deg']:g} deg" for h in row)
                     + (f" (to {doc['weight_resolution']:g} {mu})" if "weight_resolution" in doc else ""))
    measured = "check_run" in doc
    lines += ["", f"{'reading':<28} {'initial':>18} {'predicted after':>20}" + (f" {'measured after':>20}" if measured else "")]
    for r in doc["readings"]:
        lines.append(f"{r['sensor']:<28} {r['initial_amplitude']:>9.4g} {unit} {r['initial_phase_deg']:>5.0f}° "
                     f"{r['predicted_amplitude']:>10.3g} {unit} {r['predicted_phase_deg']:>5.0f}°"
                     + (f" {r['measured_amplitude']:>10.4g} {unit} {r['measured_phase_deg']:>5.0f}°" if measured else ""))
    lines += ["", f"worst {doc['worst_initial']:.4g} -> {doc['worst_residual']:.3g} {unit}; "
              f"RMS {doc['rms_initial']:.4g} -> {doc['rms_residual']:.3g} {unit}; condition number {doc['condition_number']:.3g}"
              + (f"; flags: {', '.join(doc['flags'])}" if doc["flags"] else "")]
    if "spread" in doc:
        lines += spread_lines(doc["spread"], unit, mu)
    if measured:
        lines += [""] + check_run_lines(doc["check_run"], unit, mu)
    if "iso" in doc:
        iso = doc["iso"]
        lines.append(f"ISO 21940-11 G {iso['grade_mm_s']:g}: {iso['verdict']} (residual "
                     + ", ".join(f"{v * 1e6:.4g}" for v in iso["residual_unbalance_kg_m"]) + " g mm; permissible "
                     + ", ".join(f"{v * 1e6:.4g}" for v in iso["permissible_per_plane_kg_m"]) + " g mm)")
    return "\n".join(lines)


def run(args) -> int:
    """Run the sub-command; returns the exit code."""
    import tomllib
    from pathlib import Path

    from .job import balance, load_job
    from .readings import MASS_UNITS

    try:
        job = load_job(args.readings)
        options = tomllib.loads(Path(args.readings).read_text(encoding="utf-8"))
        iso = options.get("iso", {})
        grade = args.grade if args.grade is not None else iso.get("grade_mm_s")
        mass = args.rotor_mass if args.rotor_mass is not None else iso.get("rotor_mass_kg")
        speed = args.speed_rpm if args.speed_rpm is not None else iso.get("speed_rpm")
        noise = args.reading_noise if args.reading_noise is not None else options.get("reading_noise")
        resolution = args.weight_resolution if args.weight_resolution is not None else options.get("weight_resolution")
        if resolution is not None and not (isinstance(resolution, (int, float)) and 0 < resolution < float("inf")):
            where = "--weight-resolution" if args.weight_resolution is not None else f"{args.readings}: weight_resolution"
            raise ParameterError(f"{where} = {resolution!r}: expected the step of the weights at hand, a mass > 0 "
                                 f"in {job.mass_units}")
        report = balance(job, args.method or options.get("method", "least_squares"),
                         weights=options.get("weights"),
                         max_unbalance_kg_m=args.max_correction if args.max_correction is not None else options.get("max_unbalance_kg_m"),
                         holes=args.holes if args.holes is not None else options.get("holes"),
                         positions_deg=None if args.holes is not None else options.get("positions_deg"),
                         grade_mm_s=grade, rotor_mass_kg=mass, speed_rpm=speed,
                         distances_m=tuple(iso["distances_m"]) if "distances_m" in iso else None,
                         weight_resolution_kg=None if resolution is None else resolution * MASS_UNITS[job.mass_units],
                         reading_noise=noise)
    except ModalError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    doc = report_document(report)
    if args.json:
        json.dump(jsonable(doc), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(_text(doc))
    return 0
